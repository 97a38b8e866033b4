package rtaccel.fp

import chisel3._
import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.flatspec.AnyFlatSpec
import org.scalatest.matchers.should.Matchers

/** FpDivPipe with stages 0, 1, 5, 13 side by side on one stream of random operands (a new division in ~90%
  * of cycles, bubbles otherwise): each output stream must be the input stream delayed by exactly `stages`
  * cycles, valid for valid, with Java's quotient (fp32) / SoftFloat's (half).
  */
class FpDivPipeSpec extends AnyFlatSpec with ChiselScalatestTester with Matchers {
  private val stageList = Seq(0, 1, 5, 13)

  private def runStream(dut: DivPipeHarness, cycles: Int, ref: (Long, Long) => Long, seed: Long): (Long, Long) = {
    val f = dut.f
    val g = new FpTestGen(f, seed)
    val W = f.width
    val wMask = (BigInt(1) << W) - 1
    val maxS = stageList.max
    val hist = new Array[(Boolean, Long, Long)](cycles)
    var checked = 0L
    var failed = 0L
    val fails = scala.collection.mutable.ArrayBuffer[String]()
    dut.clock.setTimeout(0)
    for (t <- 0 until cycles) {
      val v = g.rnd.nextInt(10) != 0
      val (a, b) = if (g.rnd.nextInt(50) == 0) (g.randomEdge(), g.randomEdge()) else g.mixed()
      hist(t) = (v, a, b)
      dut.io.valid.poke(v.B)
      dut.io.a.poke(BigInt(a))
      dut.io.b.poke(BigInt(b))
      val ov = dut.io.outValid.peekInt()
      val ob = dut.io.outBits.peekInt()
      for ((s, i) <- stageList.zipWithIndex) {
        val gotV = ov.testBit(i)
        val gotB = ((ob >> (i * W)) & wMask).toLong
        val (wantV, wa, wb) = if (t - s >= 0) hist(t - s) else (false, 0L, 0L)
        checked += 1
        val ok = gotV == wantV && (!wantV || gotB == ref(wa, wb))
        if (!ok) {
          failed += 1
          if (fails.length < 10) fails += f"stages=$s cycle=$t valid=$gotV (want $wantV) got=0x$gotB%x want=0x${ref(wa, wb)}%x a=0x$wa%x b=0x$wb%x"
        }
      }
      dut.clock.step()
    }
    if (fails.nonEmpty) info(fails.mkString("\n"))
    require(maxS < cycles)
    (checked, failed)
  }

  "FpDivPipe" should s"stream fp32 divisions every cycle with stages ${stageList.mkString(",")} equal to Java float" in {
    val cycles = 200000
    test(new DivPipeHarness(FpFormat.fp32, stageList)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
      val t0 = System.nanoTime()
      val (checked, failed) = runStream(dut, cycles, (a, b) => FpRef.java32(3, a, b), 5)
      val secs = (System.nanoTime() - t0) / 1e9
      info(f"$cycles cycles x ${stageList.length} pipes = $checked output checks, ${cycles / secs}%.0f cycles/s")
      failed shouldBe 0
      checked shouldBe cycles.toLong * stageList.length
    }
  }

  it should "stream half-precision divisions equal to SoftFloat" in {
    val cycles = 50000
    val half = FpFormat(5, 10)
    val sf = new SoftFloat(half)
    test(new DivPipeHarness(half, stageList)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
      val (checked, failed) = runStream(dut, cycles, sf.div, 6)
      failed shouldBe 0
      checked shouldBe cycles.toLong * stageList.length
    }
  }

  "FpDivPipe.placement" should "place exactly `stages` register levels, spread over the chain" in {
    val f = FpFormat.fp32
    for (s <- 0 to 40) FpDivPipe.placement(f, s).sum shouldBe s
    FpDivPipe.placement(f, 1).indexWhere(_ > 0) should (be > 5 and be < 25)
    FpDivPipe.placement(f, 13).max shouldBe 1
  }
}
