package rtaccel.fp

import chisel3._
import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.flatspec.AnyFlatSpec
import org.scalatest.matchers.should.Matchers

/** FpDivPipe with stages 0, 1, 5, 13 side by side, in fp32 and half precision, on one stream of random
  * operands per format (a new division in ~90% of cycles, bubbles otherwise): each output stream must be the
  * input stream delayed by exactly `stages` cycles, valid for valid, with Java's quotient (fp32) or
  * SoftFloat's (half).
  */
class FpDivPipeSpec extends AnyFlatSpec with ChiselScalatestTester with Matchers {
  private val stageList = Seq(0, 1, 5, 13)
  private val half = FpFormat(5, 10)
  private val cycles = 200000

  /** Stream state and checker for one format's ports. */
  private final class Stream(p: DivPipePorts, ref: (Long, Long) => Long, seed: Long) {
    private val f = p.f
    private val g = new FpTestGen(f, seed)
    private val wMask = (BigInt(1) << f.width) - 1
    private val hist = new Array[(Boolean, Long, Long)](cycles)
    var checked = 0L
    var failed = 0L
    val fails = scala.collection.mutable.ArrayBuffer[String]()

    def cycle(t: Int): Unit = {
      val v = g.rnd.nextInt(10) != 0
      val (a, b) = if (g.rnd.nextInt(50) == 0) (g.randomEdge(), g.randomEdge()) else g.mixed()
      hist(t) = (v, a, b)
      p.valid.poke(v.B)
      p.a.poke(BigInt(a))
      p.b.poke(BigInt(b))
      val ov = p.outValid.peekInt()
      val ob = p.outBits.peekInt()
      for ((s, i) <- stageList.zipWithIndex) {
        val gotV = ov.testBit(i)
        val gotB = ((ob >> (i * f.width)) & wMask).toLong
        val (wantV, wa, wb) = if (t - s >= 0) hist(t - s) else (false, 0L, 0L)
        checked += 1
        if (gotV != wantV || (wantV && gotB != ref(wa, wb))) {
          failed += 1
          if (fails.length < 10)
            fails += f"(${f.expBits},${f.manBits}) stages=$s cycle=$t valid=$gotV (want $wantV) got=0x$gotB%x want=0x${ref(wa, wb)}%x a=0x$wa%x b=0x$wb%x"
        }
      }
    }
  }

  "FpDivPipe" should s"stream fp32 and half divisions every cycle with stages ${stageList.mkString(",")}, equal to Java/SoftFloat" in {
    test(new DivPipeHarness(Seq(FpFormat.fp32, half), stageList)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
      dut.clock.setTimeout(0)
      val sfHalf = new SoftFloat(half)
      val streams = Seq(new Stream(dut.io(0), (a, b) => FpRef.java32(3, a, b), 5), new Stream(dut.io(1), sfHalf.div, 6))
      val t0 = System.nanoTime()
      for (t <- 0 until cycles) {
        streams.foreach(_.cycle(t))
        dut.clock.step()
      }
      val secs = (System.nanoTime() - t0) / 1e9
      for (s <- streams) if (s.fails.nonEmpty) info(s.fails.mkString("\n"))
      info(f"$cycles cycles x ${stageList.length} pipes x 2 formats = ${streams.map(_.checked).sum} output checks, ${cycles / secs}%.0f cycles/s")
      for (s <- streams) {
        s.failed shouldBe 0
        s.checked shouldBe cycles.toLong * stageList.length
      }
    }
  }

  // Every divider of the platform is a reciprocal: its dividend is the constant 1.0, which firtool folds into the
  // circuit (and firtool 1.62.1 once folded a subtract with a constant side wrongly, Fp.minus). So the reciprocal
  // is built as the TC and the triangle pipes build it, through firtool, not only with both operands as inputs.
  "FpDivPipe" should "take 1/x with the dividend the constant 1.0, through firtool, equal to Java on edges and 20000 random x" in {
    val s = rtaccel.sim.FirtoolHarness.shell(new RecipProbe, java.nio.file.Paths.get("build/test-fp/FpDivPipeSpec/recip"))(_.io)
    test(s.gen()).withAnnotations(rtaccel.sim.VerilatorBuild.quick.withSources(s.sources) :+ VerilatorBackendAnnotation) { dut =>
      val g = new FpTestGen(FpFormat.fp32, 7)
      val xs = g.edges.toSeq ++ Seq.fill(20000)(g.mixed()._2)
      val bad = xs.filter { x =>
        dut.io.b.poke(BigInt(x))
        val want = java.lang.Float.floatToRawIntBits(1f / java.lang.Float.intBitsToFloat(x.toInt)).toLong & 0xffffffffL
        val got = dut.io.y.peekInt().toLong
        got != want && !(isNaN32(got) && isNaN32(want))
      }
      assert(bad.isEmpty, f"${bad.length} of ${xs.length} reciprocals differ, e.g. 1/0x${bad.headOption.getOrElse(0L)}%08x")
    }
  }
  private def isNaN32(x: Long) = ((x >> 23) & 0xff) == 0xff && (x & 0x7fffff) != 0

  "FpDivPipe.placement" should "place exactly `stages` register levels, spread over the chain" in {
    val f = FpFormat.fp32
    for (s <- 0 to 40) FpDivPipe.placement(f, s).sum shouldBe s
    FpDivPipe.placement(f, 1).indexWhere(_ > 0) should (be > 5 and be < 25)
    FpDivPipe.placement(f, 13).max shouldBe 1
  }
}

/** 1/b as the platform builds it: FpDivPipe (combinational) with the dividend tied to the constant 1.0. */
class RecipProbe extends Module {
  val io = IO(new Bundle { val b = Input(UInt(32.W)); val y = Output(UInt(32.W)) })
  private val d = Module(new FpDivPipe(FpFormat.fp32, 0, None))
  d.io.in.valid := true.B
  d.io.in.bits.a := java.lang.Float.floatToRawIntBits(1f).toLong.U(32.W)
  d.io.in.bits.b := io.b
  io.y := d.io.out.bits
}
