package rtaccel.iu

import chisel3._
import chisel3.util._
import chisel3.util.experimental.loadMemoryFromFileInline
import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import java.nio.file.{Files, Path, Paths}
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.config.PlatformParams

/** Drives a LeafAssembler from a ROM of beats (each with the idle cycles to wait before it is offered) and checks
  * every record it puts out against a ROM of expected records, in hardware, so that a run of tens of thousands of
  * leaves takes seconds. Stimulus entry, LSB first: beat data | err | lastPrim (4 bits) | gap (2 bits) | tag (32);
  * expected entry: 10 words (word 0 lowest) | err | last | tag. A leaf's job carries tu = tag mod 4, tmax = tag and
  * ray.o(1) = 7 tag.
  */
class LeafAssemblerBench(p: PlatformParams, beatBits: Int, stimHex: String, beats: Int, expHex: String, records: Int) extends Module {
  val io = IO(new Bundle {
    val done = Output(Bool())
    val seen = Output(UInt(32.W))
    val mismatches = Output(UInt(32.W))
    val firstBad = Output(UInt(32.W))
    val refused = Output(UInt(32.W))
    val close = Output(UInt(32.W)) // records that left fewer than TRI_II cycles after the one before
  })
  val dut = Module(new LeafAssembler(p.leaves, beatBits))
  val stim = Mem(beats, UInt((beatBits + 1 + 4 + 2 + 32).W)); loadMemoryFromFileInline(stim, stimHex)
  val exp = Mem(records, UInt((320 + 2 + 32).W)); loadMemoryFromFileInline(exp, expHex)
  val i = RegInit(0.U(32.W)); val waited = RegInit(0.U(2.W))
  val s = stim(i(math.max(1, log2Ceil(beats)) - 1, 0))
  val tag = s(beatBits + 38, beatBits + 7)
  val offer = i < beats.U && waited === s(beatBits + 6, beatBits + 5)
  when(i < beats.U && !offer) { waited := waited + 1.U }
  dut.io.in.valid := offer
  dut.io.in.bits.beat.data := s(beatBits - 1, 0)
  dut.io.in.bits.beat.err := s(beatBits)
  dut.io.in.bits.beat.last := false.B // the assembler counts a leaf's beats itself
  dut.io.in.bits.lastPrim := s(beatBits + 4, beatBits + 1)
  dut.io.in.bits.ctx := 0.U.asTypeOf(new LeafCtx(p.leaves))
  dut.io.in.bits.ctx.tu := tag(1, 0)
  dut.io.in.bits.ctx.tmax := tag
  dut.io.in.bits.ctx.ray.o(1) := (tag * 7.U)(31, 0)
  when(dut.io.in.fire) { i := i + 1.U; waited := 0.U }
  val refused = RegInit(0.U(32.W)); when(offer && !dut.io.in.ready) { refused := refused + 1.U }

  val r = RegInit(0.U(32.W)); val bad = RegInit(0.U(32.W)); val firstBad = RegInit(0.U(32.W))
  val e = exp(r(math.max(1, log2Ceil(records)) - 1, 0))
  val o = dut.io.out.bits
  val eTag = e(353, 322)
  val same = r < records.U && o.words.asUInt === e(319, 0) &&
    o.err === e(320) && o.last === e(321) && o.tmax === eTag && o.tu === eTag(1, 0) && o.ray.o(1) === (eTag * 7.U)(31, 0)
  when(dut.io.out.valid) {
    r := r + 1.U
    when(!same) { bad := bad + 1.U; when(bad === 0.U) { firstBad := r } }
  }
  // TRI_II: cycles since the last record (saturating), counted independently of the assembler's own wait
  val ii = p.triInterval
  val since = RegInit(ii.U(8.W)); val close = RegInit(0.U(32.W))
  since := Mux(dut.io.out.valid, 1.U, Mux(since === ii.U, since, since + 1.U))
  when(dut.io.out.valid && since < ii.U) { close := close + 1.U }
  io.done := i === beats.U && r === records.U
  io.seen := r; io.mismatches := bad; io.firstBad := firstBad; io.refused := refused; io.close := close
}

/** PRIM_FORMAT=packed: the LeafAssembler's records against a plain cut of the word stream, raw bits, on every bus
  * width: directed leaves of 1..16 primitives (MPPL 4, a 4-bit count field: up to maxLeafPrims), an error beat in the
  * middle of a leaf, leaves back to back and with idle cycles between beats, then random leaves.
  */
class LeafAssemblerSpec extends AnyFunSuite with ChiselScalatestTester {
  /** A leaf as memory holds it: its records' words, the error bit of each of its beats, and a tag for its job. */
  private final case class Leaf(records: Seq[Seq[Long]], errBeats: Set[Int], tag: Int)

  /** The reference: a leaf's words are its records back to back, padded to whole beats; record k takes words
    * 10k .. 10k+9 and is bad if any beat those words lie in is; the leaf's last record is `last`.
    */
  private def beatsOf(l: Leaf, bw: Int): Seq[Seq[Long]] = {
    val w = l.records.flatten; val n = (w.length + bw - 1) / bw
    (w ++ Seq.fill(n * bw - w.length)(0xdeadbeefL)).grouped(bw).toSeq // padding words must never show up
  }
  private def expected(l: Leaf, bw: Int): Seq[(Seq[Long], Boolean, Boolean, Int)] = l.records.indices.map { k =>
    (l.records(k), ((10 * k / bw) to ((10 * k + 9) / bw)).exists(l.errBeats), k == l.records.length - 1, l.tag)
  }
  private def hexLines(path: Path, digits: Int, vals: Seq[BigInt]): Unit =
    Files.write(path, vals.map(v => { val h = v.toString(16); "0" * (digits - h.length) + h }).mkString("", "\n", "\n").getBytes)

  private def leaf(rnd: Random, count: Int, tag: Int, bw: Int, errRate: Double): Leaf = {
    val nBeats = (10 * count + bw - 1) / bw
    Leaf(Seq.fill(count)(Seq.fill(10)(rnd.nextInt() & 0xffffffffL)), (0 until nBeats).filter(_ => rnd.nextDouble() < errRate).toSet, tag)
  }

  // make test: the 512-bit bus (a beat holds more than a record: the only width where the assembler refuses beats;
  // the platform's 256-bit one runs packed leaves in PlatformSpec); make regress adds 64, 128 and 256 bits (a record
  // across up to 5 beats)
  // TRI_II=k: records at least k cycles apart (make test: the 256-bit bus at 2, where records complete up to a cycle
  // apart; make regress: every bus at 3)
  private val regress = rtaccel.Regress.full
  for ((bw, ii) <- if (regress) Seq(2, 4, 8, 16).flatMap(b => Seq(b -> 1, b -> 3)) else Seq(16 -> 1, 8 -> 2)) {
    val randomLeaves = 20000
    test(s"${32 * bw}-bit beats${if (ii > 1) s", TRI_II=$ii" else ""}: directed leaves (1..16 primitives, an error beat mid-leaf, back to back and with gaps) and $randomLeaves random leaves, bit for bit") {
      val rnd = new Random(bw)
      var tag = 0
      def next(count: Int, errs: Set[Int] = Set()): Leaf = { tag += 1; leaf(rnd, count, tag, bw, 0).copy(errBeats = errs) }
      // every count back to back, then leaves whose middle beat is bad (the records across it, and only those, are bad)
      def directed = (1 to 16).map(next(_)) ++ Seq(next(4, Set((40 / bw) / 2)), next(7, Set((70 / bw) / 2)), next(1), next(16, Set(0)))
      val random = Seq.fill(randomLeaves) { tag += 1; leaf(rnd, if (rnd.nextInt(4) == 0) 1 + rnd.nextInt(16) else 1 + rnd.nextInt(4), tag, bw, 0.02) }
      // phases: directed without gaps, directed with idle cycles before half the beats, random with a few idle cycles
      val phases: Seq[(Seq[Leaf], () => Int)] = Seq((directed, () => 0), (directed, () => if (rnd.nextBoolean()) 1 + rnd.nextInt(3) else 0),
        (random, () => if (rnd.nextInt(5) == 0) 1 + rnd.nextInt(3) else 0))
      val stim = phases.flatMap { case (ls, gap) => ls.flatMap(l => beatsOf(l, bw).zipWithIndex.map { case (b, i) =>
        val data = b.zipWithIndex.map { case (w, k) => BigInt(w) << (32 * k) }.sum
        data | (BigInt(if (l.errBeats(i)) 1 else 0) << (32 * bw)) | (BigInt(l.records.length - 1) << (32 * bw + 1)) |
          (BigInt(gap()) << (32 * bw + 5)) | (BigInt(l.tag) << (32 * bw + 7))
      }) }
      val want = phases.flatMap(_._1.flatMap(expected(_, bw)))
      val dir = Paths.get(s"build/test-leaf-assembler/bus${32 * bw}-ii$ii").toAbsolutePath; Files.createDirectories(dir)
      hexLines(dir.resolve("stim.hex"), (32 * bw + 39 + 3) / 4, stim)
      hexLines(dir.resolve("exp.hex"), (354 + 3) / 4, want.map { case (w, err, last, t) =>
        w.zipWithIndex.map { case (x, k) => BigInt(x) << (32 * k) }.sum | (BigInt(if (err) 1 else 0) << 320) |
          (BigInt(if (last) 1 else 0) << 321) | (BigInt(t) << 322) })
      val p = PlatformParams(tus = 4, mppl = 4, axiDataBits = 32 * bw, primPacked = true, triInterval = ii)
      test(new LeafAssemblerBench(p, 32 * bw, dir.resolve("stim.hex").toString, stim.length, dir.resolve("exp.hex").toString, want.length))
        .withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
          dut.clock.setTimeout(0)
          var cycles = 0L
          while (!dut.io.done.peek().litToBoolean && cycles < 4L * ii * stim.length + 1000) { dut.clock.step(1000); cycles += 1000 }
          dut.clock.step(16) // a record beyond the expected ones would count as a mismatch
          val seen = dut.io.seen.peek().litValue; val bad = dut.io.mismatches.peek().litValue
          assert(dut.io.done.peek().litToBoolean, s"stuck after $seen of ${want.length} records")
          assert(bad == 0 && seen == want.length, s"$bad of $seen records differ, the first is record ${dut.io.firstBad.peek().litValue}: " +
            s"${want.lift(dut.io.firstBad.peek().litValue.toInt)}")
          assert(dut.io.close.peek().litValue == 0, s"${dut.io.close.peek().litValue} records left fewer than TRI_II=$ii cycles after the one before")
          info(s"${phases.map(_._1.length).sum} leaves, ${want.length} records, ${stim.length} beats, " +
            s"${want.count(_._2)} bad records, ${dut.io.refused.peek().litValue} beats refused, about $cycles cycles")
        }
    }
  }
}
