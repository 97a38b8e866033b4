package rtaccel.top

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** PerfCounters with the widest increment its callers build: RtAccelTop sizes increments for the TUs that
  * may stall in one cycle, log2Ceil(tus + 1) bits, so a 1024-TU platform needs 11 bits and adds up to 1024
  * per cycle. Expected values are plain Scala sums of what was poked.
  */
class PerfCountersSpec extends AnyFunSuite with ChiselScalatestTester {
  private val maxTus = 1024
  private val incBits = 11 // bits to hold 0..1024 (log2Ceil(1024 + 1)); checked below without the RTL's helper
  private val names = Seq("a", "b", "c")
  private val mask64 = (BigInt(1) << 64) - 1

  test("the increment width of a 1024-TU platform holds 1024 but not 2048") {
    assert((1 << (incBits - 1)) <= maxTus && maxTus < (1 << incBits))
  }

  test("increments of 1024 and of 2047 (all 11 bits) per cycle count exactly; random increments too") {
    val seed = 4711L
    val rnd = new Random(seed)
    test(new PerfCounters(names, incBits)) { dut =>
      assert(dut.io.events(0).getWidth == incBits && dut.io.values(0).getWidth == 64)
      dut.io.clear.poke(false.B)
      for (i <- names.indices) dut.io.values(i).expect(0.U, "counters must reset to 0")
      val sums = Array.fill(names.length)(BigInt(0))
      for (cycle <- 0 until 2000) {
        val inc = Seq(maxTus, (1 << incBits) - 1, rnd.nextInt(1 << incBits))
        for (i <- names.indices) { dut.io.events(i).poke(inc(i).U); sums(i) += inc(i) }
        dut.clock.step()
        for (i <- names.indices)
          assert(dut.io.values(i).peek().litValue == sums(i), s"counter ${names(i)} after cycle $cycle (seed $seed)")
      }
      assert(sums(0) == BigInt(2000 * 1024) && sums(1) == BigInt(2000 * 2047))
    }
  }

  test("a counter carries past bit 31 (64-bit counts) at 2047 per cycle") {
    test(new PerfCounters(Seq("x"), incBits)) { dut =>
      dut.io.clear.poke(false.B)
      dut.io.events(0).poke(2047.U)
      val cycles = ((BigInt(1) << 32) / 2047 + 3).toInt // 2 098 179 cycles: past 2^32
      dut.clock.setTimeout(0)
      dut.clock.step(cycles)
      val want = BigInt(cycles) * 2047
      assert(want > (BigInt(1) << 32))
      assert(dut.io.values(0).peek().litValue == (want & mask64), s"after $cycles cycles of +2047")
    }
  }

  test("clear zeroes every counter (an event in the clear cycle is dropped) and counting resumes from 0") {
    val seed = 99L
    val rnd = new Random(seed)
    test(new PerfCounters(names, incBits)) { dut =>
      dut.io.clear.poke(false.B)
      val sums = Array.fill(names.length)(BigInt(0))
      for (cycle <- 0 until 600) {
        val clear = rnd.nextInt(40) == 0
        val inc = Seq.fill(names.length)(if (rnd.nextBoolean()) maxTus else rnd.nextInt(1 << incBits))
        dut.io.clear.poke(clear.B)
        for (i <- names.indices) dut.io.events(i).poke(inc(i).U)
        dut.clock.step()
        for (i <- names.indices) {
          sums(i) = if (clear) 0 else sums(i) + inc(i)
          assert(dut.io.values(i).peek().litValue == sums(i), s"counter ${names(i)} after cycle $cycle (clear=$clear, seed $seed)")
        }
      }
      // clear held for several cycles keeps them at zero
      dut.io.clear.poke(true.B)
      for (_ <- 0 until 3) { dut.clock.step(); for (i <- names.indices) dut.io.values(i).expect(0.U) }
    }
  }
}
