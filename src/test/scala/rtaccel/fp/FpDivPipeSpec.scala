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

  "FpDivPipe.placement" should "place exactly `stages` register levels, spread over the chain" in {
    val f = FpFormat.fp32
    for (s <- 0 to 40) FpDivPipe.placement(f, s).sum shouldBe s
    FpDivPipe.placement(f, 1).indexWhere(_ > 0) should (be > 5 and be < 25)
    FpDivPipe.placement(f, 13).max shouldBe 1
  }
}
