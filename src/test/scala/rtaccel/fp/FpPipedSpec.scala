package rtaccel.fp

import chisel3._
import chisel3.util.Cat
import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.funsuite.AnyFunSuite

/** Every FpOps operation built by a Stager with a budget (registers inside the operators, fp.Stager), one pair per
  * cycle, all results read at the cycle of the slowest: `out` packs the 8 value results then the 5 compare bits.
  */
class FpPipedHarness(f: FpFormat, budget: Int, dsp: DspShape = DspShape.Dsp48, lutInputs: Int = 6) extends Module {
  val io = IO(new Bundle {
    val a = Input(UInt(f.width.W))
    val b = Input(UInt(f.width.W))
    val out = Output(UInt((FpOps.numValueOps * f.width + 5).W))
  })
  private val pipe = new Stager(Some(budget), dsp, None, lutInputs)
  private val a = Timed(io.a, 0, 1); private val b = Timed(io.b, 0, 1)
  private val div = Module(new FpDivPipe(f, 0, Some(budget), lutInputs))
  div.io.in.valid := true.B; div.io.in.bits.a := io.a; div.io.in.bits.b := io.b
  private def sel(fn: (FpFormat, UInt, UInt) => UInt) = Fp.selT(pipe, f, a, b)(fn)
  private def cmp(fn: (FpFormat, UInt, UInt) => Bool) = Fp.cmpT(pipe, f, a, b)(fn).map(0)(_.asUInt)
  private val all = Seq(Fp.addT(pipe, f, a, b), Fp.subT(pipe, f, a, b), Fp.mulT(pipe, f, a, b), Timed(div.io.out.bits, div.latency, 0),
    sel(Fp.minNum), sel(Fp.maxNum), sel(Fp.minProp), sel(Fp.maxProp),
    cmp(Fp.lt), cmp(Fp.le), cmp(Fp.gt), cmp(Fp.ge), cmp(Fp.eq))
  private val aligned = pipe.align(all)
  /** Cycles from an operand pair to its results. */
  val latency: Int = aligned.head.at + 1
  /** Each operation's own cycles (without the alignment). */
  val opLatencies: Seq[Int] = all.map(_.at)
  io.out := RegNext(Cat(aligned.map(_.v).reverse))
}

class FpPipedSpec extends AnyFunSuite with ChiselScalatestTester {
  private val fp32 = FpFormat.fp32
  private val nRandom = 60000
  // budgets: the paper's xc5v at 150 MHz (6) and the deepest that still splits every segment (2), on Xilinx's DSP48;
  // a made-up 7 x 9 DSP block cuts the product into 12 tiles summed over four levels (the tree ECP5's 18 x 18 blocks
  // use with four tiles); ECP5's blocks with their own registers (DspTile, two cycles a tile); make regress adds 4 and
  // 9 levels and ECP5's block inferred
  // (ECP5's 4-input LUTs: roundPack's sticky bit by mask, and at 7 levels (125 MHz there) roundPack's first two
  // segments cut apart, Fp.roundPackT)
  private val runs = Seq((2, DspShape.Dsp48, 6), (6, DspShape.Dsp48, 6), (3, DspShape(7, 9), 6), (5, DspShape(18, 18, 3, registered = true), 4),
    (7, DspShape(18, 18, 3, registered = true), 4)) ++
    (if (rtaccel.Regress.full) Seq((4, DspShape.Dsp48, 6), (9, DspShape.Dsp48, 6), (2, DspShape(18, 18), 4), (4, DspShape.Dsp48, 4)) else Nil)
  test("a product's tiles cover each bit pair of the operands once, within the DSP block") {
    for (n <- Seq(8, 11, 17, 18, 24, 25, 53); dsp <- Seq(DspShape.Dsp48, DspShape(18, 18), DspShape(7, 9))) {
      val tiles = Fp.mulTiles(n, dsp)
      val cover = for (((a0, a1), (b0, b1)) <- tiles; i <- a0 until a1; j <- b0 until b1) yield (i, j)
      assert(cover.sorted == (for (i <- 0 until n; j <- 0 until n) yield (i, j)), s"n=$n on $dsp")
      assert(tiles.forall { case ((a0, a1), (b0, b1)) => a1 - a0 <= dsp.a && b1 - b0 <= dsp.b }, s"n=$n on $dsp")
    }
    assert(Fp.mulTiles(24, DspShape(18, 18)).length == 4 && Fp.mulTiles(24, DspShape.Dsp48).length == 2)
  }
  for ((budget, dsp, lutIn) <- runs)
    test(s"fp32 operators pipelined at a $budget-level budget on ${dsp} DSP blocks and $lutIn-input LUTs equal Java float on edge pairs, ties and $nRandom random pairs, one per cycle") {
      test(new FpPipedHarness(fp32, budget, dsp, lutIn)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
        val lat = dut.latency
        info(s"latencies (add, sub, mul, div, min/max x4, compares x5): ${dut.opLatencies.mkString(", ")}; read at $lat")
        val g = new FpTestGen(fp32, 11 + budget + dsp.a)
        val pairs = g.edgePairs.iterator ++ Iterator.fill(20000)(g.addTie()) ++ Iterator.fill(20000)(g.mulTie()) ++
          Iterator.fill(10000)(g.rangeEdge()) ++ Iterator.fill(nRandom)(g.mixed())
        val chk = new FpCheck(s"piped$budget")
        val inFlight = scala.collection.mutable.Queue[(Long, Long)]()
        val W = fp32.width; val wMask = (BigInt(1) << W) - 1
        def read(): Unit = {
          val (a, b) = inFlight.dequeue()
          val out = dut.io.out.peekInt()
          for (op <- 0 until FpOps.numValueOps) chk.check(op, a, b, ((out >> (op * W)) & wMask).toLong, FpRef.java32(op, a, b))
          val cmp = (out >> (FpOps.numValueOps * W)).toInt
          for (op <- FpOps.numValueOps until FpOps.n) chk.check(op, a, b, ((cmp >> (op - FpOps.numValueOps)) & 1).toLong, FpRef.java32(op, a, b))
        }
        var n = 0L
        for ((a, b) <- pairs) {
          dut.io.a.poke(a.U); dut.io.b.poke(b.U); inFlight.enqueue((a, b))
          if (inFlight.length > lat) read()
          dut.clock.step(); n += 1
        }
        // the last `lat` pairs: one result a cycle, the oldest first
        while (inFlight.nonEmpty) { read(); dut.clock.step() }
        info(s"$n pairs; " + chk.report)
        assert(chk.totalFailed == 0)
        assert(chk.minChecked >= n)
      }
    }
}
