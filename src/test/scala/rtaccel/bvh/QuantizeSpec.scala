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

  test("NODE_FORMAT values: full, q2..q16; others refused naming the field and the numbers; the RTL builds q formats") {
    assert(Numerics.parseNodeFormat("full") == 0 && Numerics.parseNodeFormat("q8") == 8 && Numerics.parseNodeFormat("Q16") == 16)
    assert(intercept[InputError](Numerics.parseNodeFormat("q32")).getMessage.contains("2..16 bits"))
    assert(intercept[InputError](Numerics.parseNodeFormat("q1")).getMessage.contains("not 1"))
    assert(intercept[InputError](Numerics.parseNodeFormat("half")).getMessage.contains("full or q<bits>"))
    for (k <- Seq(2, 8, 16)) rtaccel.cache.hw.CachePath.validate(PlatformParams(nodeQuantBits = k)) // no refusal
    assert(intercept[IllegalArgumentException](PlatformParams(nodeQuantBits = 17)).getMessage.contains("2..16 bits"))
  }

  test("the stored layout fits its slot for every M and k (M=4 q8: 14 of 16 words)") {
    for (m <- Seq(2, 4, 8); k <- 2 to 16) {
      val p = PlatformParams(m = m, nodeQuantBits = k); val lay = new QNodeLayout(m, k)
      assert(lay.usedWords * 4 <= p.nodeSlotBytes, s"M=$m q$k: ${lay.usedWords} words in a ${p.nodeSlotBytes} B slot")
    }
    assert(new QNodeLayout(4, 8).usedWords == 14 && PlatformParams(nodeQuantBits = 8).nodeSlotBytes == 64)
  }

  // The image the hardware reads: node n at n * nodeSlotBytes in QNodeLayout; the model's decoded view of it.
  private def scenes: Seq[(String, rtaccel.scene.Scene)] =
    Seq("soup300" -> rtaccel.TestScenes.soup(5, 300), "soup-tiny" -> rtaccel.TestScenes.soup(6, 40, size = 1e-3f)) ++
      rtaccel.TestScenes.fixtures.map(f => f._1 -> f._2)
  test("quantized images: the decoded boxes are Quantize.boxes of the exact ones and contain them; refs as the full image's") {
    for ((name, s) <- scenes; (m, k) <- Seq((4, 8), (2, 4), (8, 16), (4, 2))) {
      val p = PlatformParams(m = m, nodeQuantBits = k)
      val bvh = Mbvh.build(s, p.copy(nodeQuantBits = 0))
      val full = MemoryImage.pack(bvh, s, p.copy(nodeQuantBits = 0))
      val img = MemoryImage.pack(bvh, s, p)
      assert(img.nodes.length == bvh.numNodes * p.nodeSlotBytes / 4 && img.numNodes == bvh.numNodes)
      assert(full.planes eq full.nodes, "full nodes: the traversal reads the stored words themselves")
      var children = 0
      for (n <- bvh.nodes) {
        val exact = n.children.map(c => (Array.tabulate(3)(c.box.min(_)), Array.tabulate(3)(c.box.max(_))))
        val want = if (exact.isEmpty) Nil else Quantize.boxes(Quantize.encode(exact, k))
        for (j <- 0 until m) {
          assert(img.childRef(n.id, j) == full.childRef(n.id, j), s"$name M=$m q$k node ${n.id} child $j: ref")
          if (j < exact.length) {
            children += 1
            for (a <- 0 until 3) {
              val lo = java.lang.Float.intBitsToFloat(img.childWord(n.id, j, a)); val hi = java.lang.Float.intBitsToFloat(img.childWord(n.id, j, 3 + a))
              assert(java.lang.Float.floatToRawIntBits(lo) == java.lang.Float.floatToRawIntBits(want(j)._1(a)) &&
                java.lang.Float.floatToRawIntBits(hi) == java.lang.Float.floatToRawIntBits(want(j)._2(a)), s"$name M=$m q$k node ${n.id} child $j axis $a")
              assert(lo <= exact(j)._1(a) && hi >= exact(j)._2(a), s"$name M=$m q$k node ${n.id} child $j axis $a: not contained")
            }
          }
        }
      }
      assert(children == bvh.nodes.map(_.children.length).sum && children > 0)
    }
  }

  test("q8 traversal over the quantized image finds the full nodes' hits (the boxes only grow)") {
    val s = rtaccel.TestScenes.soup(9, 300); val rays = rtaccel.TestScenes.rays(10, 400)
    val p = PlatformParams(m = 4, mppl = 4, tus = 1); val bvh = Mbvh.build(s, p)
    val st = Seq(p, p.copy(nodeQuantBits = 8)).map { q =>
      val stats = new rtaccel.model.RayStats
      (new rtaccel.model.Traversal(MemoryImage.pack(bvh, s, q)).traceAll(rays, stats = stats), stats)
    }
    val ((hf, sf), (hq, sq)) = (st(0), st(1))
    // a hit can differ only where a full box's rounding culls it or equal distances reorder: rare on a soup
    val agree = (0 until rays.count).count(i => hf.prim(i) == hq.prim(i) && hf.t(i) == hq.t(i))
    info(s"$agree of ${rays.count} rays agree; box tests full ${sf.boxTests}, q8 ${sq.boxTests}")
    assert(agree >= rays.count * 99 / 100 && hq.prim.count(_ >= 0) > rays.count / 10)
    assert(sq.boxTests > sf.boxTests, "looser boxes must cost box tests")
  }
}
