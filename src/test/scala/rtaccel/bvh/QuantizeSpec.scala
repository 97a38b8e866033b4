package rtaccel.bvh

import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.config.{Numerics, PlatformParams}
import rtaccel.io.InputError

/** NODE_FORMAT=q<k>: every decoded child box contains its exact box, is at most a few quanta larger, uses the
  * smallest scale that fits, and the encoding is stable; node slot sizes and refusals.
  */
class QuantizeSpec extends AnyFunSuite {
  test("decoded child boxes contain the exact boxes, tightly, at the smallest scale (20000 random nodes, k = 2..16)") {
    val rnd = new Random(3)
    for (it <- 0 until 20000) {
      val k = Seq(2, 4, 8, 12, 16)(it % 5)
      val n = 1 + rnd.nextInt(8)
      val scale = math.pow(2, rnd.nextInt(40) - 30).toFloat
      val centre = Array.fill(3)((rnd.nextFloat() - 0.5f) * 2)
      val boxes = Seq.fill(n) {
        val lo = Array.tabulate(3)(a => centre(a) + (rnd.nextFloat() - 0.5f) * scale)
        // flat, a few ulps wide, or up to `scale` wide (hi >= lo always)
        val hi = Array.tabulate(3)(a => if (rnd.nextInt(10) == 0) lo(a)
          else math.max(Iterator.iterate(lo(a))(Math.nextUp).drop(rnd.nextInt(3)).next(), lo(a) + rnd.nextFloat() * scale))
        (lo, hi)
      }
      val q = Quantize.encode(boxes, k)
      val dec = Quantize.boxes(q)
      for (((lo, hi), (dl, dh)) <- boxes.zip(dec); a <- 0 until 3) {
        assert(dl(a) <= lo(a) && dh(a) >= hi(a), s"k=$k axis $a: [${dl(a)}, ${dh(a)}] does not contain [${lo(a)}, ${hi(a)}]")
        val quantum = math.pow(2, q.exp(a))
        // two quanta, plus the decode's rounding: up to 2 ulps when the decoded plane crosses into the next binade
        assert(lo(a) - dl(a) <= 2 * quantum + 2 * math.ulp(lo(a)) && dh(a) - hi(a) <= 2 * quantum + 2 * math.ulp(hi(a)), s"k=$k axis $a: loose")
      }
      for (a <- 0 until 3; c <- boxes.indices) assert(q.lo(c)(a) >= 0 && q.hi(c)(a) < (1 << k) && q.lo(c)(a) <= q.hi(c)(a))
      // one scale smaller cannot reach the largest upper plane (unless the scale is at its minimum)
      for (a <- 0 until 3 if q.exp(a) > Quantize.MinExp) {
        val top = (1 << k) - 1
        assert(Quantize.decode(q.origin(a), q.exp(a) - 2, top) < boxes.map(_._2(a)).max, s"k=$k axis $a: scale 2^${q.exp(a)} is not minimal")
      }
      assert(Quantize.encode(dec, k).exp.sameElements(q.exp) || it % 5 == 0, "re-encoding the decoded boxes changes the scales")
    }
  }

  test("the node slot and the bytes of a fetch follow the format; the tree does not") {
    val p = PlatformParams(m = 4)
    assert(p.nodeSlotBytes == 128 && p.copy(nodeQuantBits = 8).nodeSlotBytes == 64 && p.copy(nodeQuantBits = 16).nodeSlotBytes == 128)
    assert(p.copy(m = 8, nodeQuantBits = 8).nodeSlotBytes == 128 && p.copy(m = 8).nodeSlotBytes == 256)
    assert(p.copy(nodeQuantBits = 8).nodeAccessBytes == 64 && p.copy(nodeQuantBits = 8).treeNodeBytes == p.treeNodeBytes)
    assert(Quantize.nodeBits(4, 8) == 440)
  }

  test("NODE_FORMAT values: full, q2..q16; others refused naming the field and the numbers; the RTL refuses q formats") {
    assert(Numerics.parseNodeFormat("full") == 0 && Numerics.parseNodeFormat("q8") == 8 && Numerics.parseNodeFormat("Q16") == 16)
    assert(intercept[InputError](Numerics.parseNodeFormat("q32")).getMessage.contains("2..16 bits"))
    assert(intercept[InputError](Numerics.parseNodeFormat("q1")).getMessage.contains("not 1"))
    assert(intercept[InputError](Numerics.parseNodeFormat("half")).getMessage.contains("full or q<bits>"))
    val e = intercept[InputError](rtaccel.cache.hw.CachePath.validate(PlatformParams(nodeQuantBits = 8)))
    assert(e.getMessage.contains("NODE_FORMAT=q8") && e.getMessage.contains("NODE_FORMAT=full"))
  }
}
