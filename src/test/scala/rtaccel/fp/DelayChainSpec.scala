package rtaccel.fp

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** A value and a bundle delayed by `n` cycles through a Stager whose delays of `ram` cycles or more go to LUT RAM. */
class DelayHarness(n: Int, ram: Option[Int]) extends Module {
  val io = IO(new Bundle {
    val in = Input(UInt(20.W))
    val out = Output(UInt(20.W))
    val pairOut = Output(new Bundle { val a = UInt(7.W); val b = Bool() })
  })
  private val pipe = new Stager(Some(4), DspShape.Dsp48, ram)
  io.out := pipe.chain(io.in, n)
  private val pair = Wire(new Bundle { val a = UInt(7.W); val b = Bool() })
  pair.a := io.in(6, 0); pair.b := io.in(19)
  io.pairOut := pipe.chain(pair, n)
}

/** Delay chains in LUT RAM (families without shift-register LUTs) against the input n cycles before, every cycle,
  * for delays below, at and above the threshold and with the flip-flop chains beside them.
  */
class DelayChainSpec extends AnyFunSuite with ChiselScalatestTester {
  for (n <- Seq(1, 2, 3, 4, 5, 17); ram <- Seq(None, Some(2), Some(4)))
    test(s"a delay of $n cycles ${ram.fold("in flip-flops")(r => s"with LUT RAM from $r cycles")} gives the input of $n cycles before") {
      test(new DelayHarness(n, ram)) { dut =>
        val rnd = new Random(n * 7 + ram.getOrElse(0))
        val history = scala.collection.mutable.ArrayBuffer[Int]()
        for (cycle <- 0 until 300) {
          val v = rnd.nextInt(1 << 20)
          dut.io.in.poke(v.U)
          history += v
          if (cycle >= n) {
            val want = history(cycle - n)
            dut.io.out.expect(want.U, s"cycle $cycle")
            dut.io.pairOut.a.expect((want & 0x7f).U, s"cycle $cycle (bundle)")
            dut.io.pairOut.b.expect(((want >> 19) & 1).B, s"cycle $cycle (bundle)")
          }
          dut.clock.step()
        }
      }
      // the ring is a memory exactly where the family asks for one
      val chirrtl = circt.stage.ChiselStage.emitCHIRRTL(new DelayHarness(n, ram))
      assert(chirrtl.linesIterator.exists(_.trim.matches("c?mem .*")) == ram.exists(n >= _), chirrtl.linesIterator.filter(_.contains("mem")).mkString("; ") + s"a memory ${if (ram.exists(n >= _)) "missing" else "where none belongs"}")
    }
  test("the ecp5 family puts its delay chains in LUT RAM, the Xilinx families do not") {
    assert(rtaccel.area.Timing.forFamily("ecp5").delayRamCycles.contains(4))
    assert(Seq("xc5v", "xc7", "xcup").forall(rtaccel.area.Timing.forFamily(_).delayRamCycles.isEmpty))
  }
}
