package rtaccel.fp

import chisel3._
import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** The directed-rounding operators of the reduced-precision box test (subDirected, mulDirected, convert).
  * SoftFloat's directed modes are checked against Java (exact double results rounded to float with
  * Math.nextUp/nextDown, an independent route); the RTL against SoftFloat bit for bit, for fp32 into bf16,
  * fp16 and e8m15 and back.
  */
class FpDirectedSpec extends AnyFunSuite with ChiselScalatestTester {
  private val fp32 = FpFormat.fp32
  private val sf32 = new SoftFloat(fp32)
  import SoftFloat.{Down, Up}

  private def bits(x: Float): Long = java.lang.Float.floatToRawIntBits(x) & 0xffffffffL
  private def fl(x: Long): Float = java.lang.Float.intBitsToFloat(x.toInt)
  /** A double rounded toward -inf (down) or +inf to float, by Java's nearest rounding and one step. */
  private def javaDirected(x: Double, up: Boolean): Float = {
    val n = x.toFloat
    if (n.isInfinite && !x.isInfinite) { if (up == (x > 0)) n else if (x > 0) Float.MaxValue else -Float.MaxValue }
    else if (up && n.toDouble < x) Math.nextUp(n) else if (!up && n.toDouble > x) Math.nextDown(n) else n
  }
  private def sameBits(got: Long, want: Float) = got == bits(want) || (fl(got).isNaN && want.isNaN)

  test("SoftFloat directed mul, sub and conversion equal Java's exact result rounded up or down") {
    val g = new FpTestGen(fp32, 3)
    val rnd = new Random(4)
    for (i <- 0 until 200000) {
      val (a, b) = if (i % 3 == 0) g.nearby() else if (i % 3 == 1) g.cancel() else (g.randomEdge(), g.uniform())
      val (fa, fb) = (fl(a), fl(b))
      for (up <- Seq(false, true)) {
        val mode = if (up) Up else Down
        val p = fa.toDouble * fb.toDouble // exact: 24 x 24 bits
        if (!p.isNaN) assert(sameBits(sf32.mul(a, b, mode), javaDirected(p, up)), f"mul $fa * $fb up=$up")
        val ea = (a >>> 23) & 0xff; val eb = (b >>> 23) & 0xff
        if (math.abs(ea - eb) < 28 && !fa.isNaN && !fb.isNaN && !fa.isInfinite && !fb.isInfinite) { // the difference is exact in double
          val d = fa.toDouble - fb.toDouble
          val want = if (d == 0) zeroSub(fa, fb, up) else javaDirected(d, up)
          assert(sameBits(sf32.subFrom(sf32, a, b, mode), want), f"sub $fa - $fb up=$up")
        }
      }
      val x = java.lang.Double.longBitsToDouble(rnd.nextLong())
      if (!x.isNaN) for (up <- Seq(false, true))
        assert(sameBits(sf32.convertFrom(new SoftFloat(FpFormat.fp64), java.lang.Double.doubleToRawLongBits(x), if (up) Up else Down),
          javaDirected(x, up)), s"convert $x up=$up")
    }
  }

  /** IEEE 754 6.3: an exact zero difference is +0, or -0 toward -inf; x - (-x) keeps x's sign when x is zero. */
  private def zeroSub(a: Float, b: Float, up: Boolean): Float = {
    val sa = bits(a) >>> 31; val sb = (bits(b) >>> 31) ^ 1 // sign of -b
    if (sa == sb) (if (sa == 1) -0f else 0f) else if (up) 0f else -0f
  }

  private class Directed(fo: FpFormat) extends Module {
    val io = IO(new Bundle {
      val a = Input(UInt(32.W)); val b = Input(UInt(32.W)); val c = Input(UInt(fo.width.W)); val d = Input(UInt(fo.width.W))
      val up = Input(Bool())
      val sub = Output(UInt(fo.width.W)); val conv = Output(UInt(fo.width.W)); val mul = Output(UInt(fo.width.W))
      val widen = Output(UInt(32.W))
    })
    io.sub := Fp.subDirected(fp32, fo, io.a, io.b, io.up)
    io.conv := Fp.convert(fp32, fo, io.a, io.up)
    io.mul := Fp.mulDirected(fo, io.c, io.d, io.up)
    io.widen := Fp.convert(fo, fp32, io.c, io.up)
  }

  /** The directed sub and conversion pipelined for ECP5 (4-input LUTs, where the adder swaps its operands a segment
    * after its compare and saturates the difference apart), a result `lat` cycles after its operands. */
  private class DirectedPiped(fo: FpFormat, budget: Int) extends Module {
    val io = IO(new Bundle {
      val a = Input(UInt(32.W)); val b = Input(UInt(32.W)); val up = Input(Bool())
      val sub = Output(UInt(fo.width.W)); val conv = Output(UInt(fo.width.W))
    })
    private val pipe = new Stager(Some(budget), DspShape(18, 18, 3, registered = true), None, 4)
    private val (a, b, up) = (Timed(RegNext(io.a), 1, 0), Timed(RegNext(io.b), 1, 0), Timed(RegNext(io.up), 1, 0))
    private val sub = Fp.subDirectedT(pipe, fp32, fo, a, b, up)
    private val conv = Fp.convertT(pipe, fp32, fo, a, up)
    val lat: Int = sub.at max conv.at
    io.sub := pipe.delayTo(sub, lat).v; io.conv := pipe.delayTo(conv, lat).v
  }

  test("RTL directed sub and conversion into bf16, pipelined for 4-input LUTs at 5 and 7 levels, equal SoftFloat bit for bit, one per cycle") {
    val bf16 = FpFormat(8, 7); val so = new SoftFloat(bf16)
    for (budget <- Seq(5, 7)) {
      val g32 = new FpTestGen(fp32, 30 + budget)
      test(new DirectedPiped(bf16, budget)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
        val lat = dut.lat
        val n = 30000
        val ins = IndexedSeq.tabulate(n) { i =>
          val (a, b) = if (i % 4 == 0) g32.nearby() else if (i % 4 == 1) g32.cancel() else if (i % 4 == 2) (g32.randomEdge(), g32.randomEdge()) else (g32.uniform(), g32.uniform())
          (a, b, (i * 7 & 2) == 0)
        }
        for (i <- 0 until n + lat) {
          if (i < n) { val (a, b, up) = ins(i); dut.io.a.poke(a.U); dut.io.b.poke(b.U); dut.io.up.poke(up.B) }
          if (i >= lat) {
            val (a, b, up) = ins(i - lat); val mode = if (up) Up else Down
            assert(dut.io.sub.peek().litValue.toLong == so.subFrom(sf32, a, b, mode), f"$budget levels: sub a=0x$a%08x b=0x$b%08x up=$up")
            assert(dut.io.conv.peek().litValue.toLong == so.convertFrom(sf32, a, mode), f"$budget levels: convert a=0x$a%08x up=$up")
          }
          dut.clock.step()
        }
        info(s"$budget levels: $lat cycles")
      }
    }
  }

  // bf16 narrows the fraction only, fp16 the exponent too; make regress adds e8m15 (one Verilator build each)
  for ((fo, name) <- Seq((FpFormat(8, 7), "bf16"), (FpFormat(5, 10), "fp16")) ++
      (if (rtaccel.Regress.full) Seq((FpFormat(8, 15), "e8m15")) else Nil))
    test(s"RTL directed sub, mul and conversions (fp32 <-> $name) equal SoftFloat bit for bit") {
      val so = new SoftFloat(fo)
      val g32 = new FpTestGen(fp32, 21); val go = new FpTestGen(fo, 22)
      test(new Directed(fo)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
        val n = 40000
        for (i <- 0 until n) {
          val (a, b) = if (i % 4 == 0) g32.nearby() else if (i % 4 == 1) g32.cancel() else if (i % 4 == 2) (g32.randomEdge(), g32.randomEdge()) else (g32.uniform(), g32.uniform())
          val (c, d) = if (i % 3 == 0) go.nearby() else if (i % 3 == 1) (go.randomEdge(), go.uniform()) else (go.uniform(), go.uniform())
          val up = (i & 1) == 0
          val mode = if (up) Up else Down
          dut.io.a.poke(a.U); dut.io.b.poke(b.U); dut.io.c.poke(c.U); dut.io.d.poke(d.U); dut.io.up.poke(up.B)
          def chk(what: String, got: BigInt, want: Long) =
            assert(got.toLong == want, f"$name $what up=$up a=0x$a%08x b=0x$b%08x c=0x$c%x d=0x$d%x: RTL 0x${got.toLong}%x, SoftFloat 0x$want%x")
          chk("sub", dut.io.sub.peek().litValue, so.subFrom(sf32, a, b, mode))
          chk("convert", dut.io.conv.peek().litValue, so.convertFrom(sf32, a, mode))
          chk("mul", dut.io.mul.peek().litValue, so.mul(c, d, mode))
          chk("widen", dut.io.widen.peek().litValue, sf32.convertFrom(so, c, mode))
        }
      }
    }
}
