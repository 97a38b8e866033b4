package rtaccel.iu

import chisel3._
import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.config.PlatformParams

/** PRIM_FORMAT=packed: the LeafAssembler's records against a plain cut of the word stream, raw bits, on every bus
  * width: directed leaves of 1..16 primitives (MPPL 4, a 4-bit count field), an error beat in the middle of a leaf,
  * leaves back to back and with gaps, then random leaves with random gaps.
  */
class LeafAssemblerSpec extends AnyFunSuite with ChiselScalatestTester {
  /** A leaf as memory holds it: its records' words, the error bit of each of its beats, and a tag for its job. */
  private final case class Leaf(records: Seq[Seq[Long]], errBeats: Set[Int], tag: Int)
  private final case class Rec(words: Seq[Long], err: Boolean, last: Boolean, tag: Int)

  /** The reference: a leaf's words are its records back to back, zero-padded to whole beats; record k takes words
    * 10k .. 10k+9 and is bad if any beat those words lie in is.
    */
  private def beatsOf(l: Leaf, bw: Int): Seq[Seq[Long]] = {
    val w = l.records.flatten; val n = (w.length + bw - 1) / bw
    (w ++ Seq.fill(n * bw - w.length)(0xdeadbeefL)).grouped(bw).toSeq // padding words must never show up
  }
  private def expected(l: Leaf, bw: Int): Seq[Rec] = l.records.indices.map { k =>
    val beats = (10 * k / bw) to ((10 * k + 9) / bw)
    Rec(l.records(k), beats.exists(l.errBeats), k == l.records.length - 1, l.tag)
  }

  /** Feeds each phase's leaves (offering a beat with probability 100 - gap %) and drains it before the next. */
  private def run(bw: Int, phases: Seq[(Seq[Leaf], Int)]): Unit = {
    val p = PlatformParams(tus = 4, mppl = 4, axiDataBits = 32 * bw, primPacked = true)
    test(new LeafAssembler(p, 32 * bw)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
     for (((leaves, gapPct), seed) <- phases.zipWithIndex) {
      val rnd = new Random(seed)
      val want = leaves.flatMap(expected(_, bw))
      val got = scala.collection.mutable.ArrayBuffer[Rec]()
      val beats = leaves.flatMap(l => beatsOf(l, bw).zipWithIndex.map { case (b, i) => (l, b, l.errBeats(i)) })
      var i = 0; var cycles = 0; var stalls = 0
      def sample(): Unit = if (dut.io.out.valid.peek().litToBoolean) {
        val o = dut.io.out.bits
        got += Rec((0 until 10).map(k => o.words(k).peek().litValue.toLong), o.err.peek().litToBoolean,
          o.last.peek().litToBoolean, o.tmax.peek().litValue.toInt)
        assert(o.tu.peek().litValue == got.last.tag % 4 && o.ray.o(1).peek().litValue == (got.last.tag * 7L & 0xffffffffL),
          s"record ${got.length - 1}: the job of another leaf")
      }
      while (i < beats.length || got.length < want.length) {
        assert(cycles < 20 * beats.length + 100, s"bus $bw: stuck after ${got.length} of ${want.length} records")
        val offer = i < beats.length && rnd.nextInt(100) >= gapPct
        dut.io.in.valid.poke(offer.B)
        if (offer) {
          val (l, b, err) = beats(i)
          dut.io.in.bits.beat.data.poke(b.zipWithIndex.map { case (w, k) => BigInt(w) << (32 * k) }.sum.U)
          dut.io.in.bits.beat.err.poke(err.B)
          dut.io.in.bits.beat.last.poke(false.B) // the assembler counts beats itself
          dut.io.in.bits.lastPrim.poke((l.records.length - 1).U)
          dut.io.in.bits.ctx.tu.poke((l.tag % 4).U)
          dut.io.in.bits.ctx.tmax.poke(l.tag.U)
          dut.io.in.bits.ctx.ray.o(1).poke((l.tag * 7L & 0xffffffffL).U)
          if (dut.io.in.ready.peek().litToBoolean) i += 1 else stalls += 1
        }
        sample()
        dut.clock.step(); cycles += 1
      }
      for (_ <- 0 until 4) { dut.io.in.valid.poke(false.B); sample(); dut.clock.step() }
      assert(got.length == want.length, s"bus $bw: ${got.length} records out, ${want.length} expected")
      for (k <- want.indices) assert(got(k) == want(k), s"bus $bw record $k: got ${got(k)}, want ${want(k)}")
      info(s"${32 * bw}-bit bus, $gapPct% gaps: ${leaves.length} leaves, ${want.length} records, ${beats.length} beats in $cycles cycles ($stalls refused beats)")
     }
    }
  }

  private def leaf(rnd: Random, count: Int, tag: Int, bw: Int, errRate: Double): Leaf = {
    val nBeats = (10 * count + bw - 1) / bw
    Leaf(Seq.fill(count)(Seq.fill(10)(rnd.nextInt() & 0xffffffffL)), (0 until nBeats).filter(_ => rnd.nextDouble() < errRate).toSet, tag)
  }

  private val regress = sys.env.get("RTACCEL_REGRESS").contains("full")
  for (bw <- Seq(2, 4, 8, 16)) {
    val randomLeaves = if (bw == 8 || regress) 20000 else 3000
    test(s"${32 * bw}-bit beats: directed leaves (1..16 primitives, error beat mid-leaf) and $randomLeaves random leaves, bit for bit") {
      val rnd = new Random(bw)
      var tag = 0
      def next(count: Int, errs: Set[Int] = Set()): Leaf = { tag += 1; leaf(rnd, count, tag, bw, 0).copy(errBeats = errs) }
      // every count, back to back, then a leaf whose middle beat is bad (records across it and only those are bad)
      val directed = (1 to 16).map(next(_)) ++ Seq(next(4, Set((40 / bw) / 2)), next(7, Set((70 / bw) / 2)), next(1), next(16, Set(0)))
      val random = Seq.fill(randomLeaves) { tag += 1; leaf(rnd, if (rnd.nextInt(4) == 0) 1 + rnd.nextInt(16) else 1 + rnd.nextInt(4), tag, bw, 0.02) }
      run(bw, Seq(directed -> 0, directed -> 50, random -> 20))
    }
  }
}
