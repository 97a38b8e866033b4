package rtaccel.arb

import chisel3._
import chiseltest._
import chiseltest.simulator.VerilatorCFlags
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** The tree arbiter under random traffic: every requester holds each request until it is taken (as TUs do); every
  * request comes out exactly once, with `chosen` naming its requester; a requester is never starved; with the output
  * always ready and every input busy, one request leaves per cycle. With `heldInputs` (registered grants at the
  * leaves) a request is never taken in the cycle it is first offered: its ready does not depend on its valid.
  */
class TreeArbiterSpec extends AnyFunSuite with ChiselScalatestTester {
  for ((n, fanIn, held, everywhere) <- Seq((32, 4, false, false), (5, 2, false, false), (7, 8, false, false), (32, 4, true, false),
      (5, 2, true, false), (3, 4, true, false), (32, 4, true, true), (5, 2, true, true)))
    test(s"$n requesters, fan-in $fanIn${if (everywhere) ", registered grants at every level" else if (held) ", registered grants" else ""}: " +
        "each request once, chosen = its requester, none starved, full rate") {
      // a 32-way tree in Verilator (about 6 s to build): treadle took 40 s for its thousands of cycles; the small
      // trees stay in treadle (a build would cost more than their run)
      val backend = if (n > 8) Seq(VerilatorBackendAnnotation, VerilatorCFlags(Seq("-O0"))) else Nil
      test(new TreeArbiter(UInt(16.W), n, fanIn, heldInputs = held, grantsEverywhere = everywhere)).withAnnotations(backend) { dut =>
        val rnd = new Random(n * 31 + fanIn)
        val next = Array.fill(n)(0) // the sequence number each requester offers next
        val offering = Array.fill(n)(false)
        val got = scala.collection.mutable.Map[(Int, Int), Int]().withDefaultValue(0)
        var lastTaken = Array.fill(n)(0L)
        val firstOffered = Array.fill(n)(-1L) // the cycle the request now offered was first offered
        val perRequester = 40
        var cycle = 0L
        def word(i: Int) = (i << 8) | next(i)
        while (next.exists(_ < perRequester) || offering.exists(identity)) {
          for (i <- 0 until n) if (!offering(i) && next(i) < perRequester && rnd.nextInt(3) > 0) { offering(i) = true; firstOffered(i) = cycle }
          for (i <- 0 until n) { dut.io.in(i).valid.poke(offering(i).B); dut.io.in(i).bits.poke(word(i).U) }
          val ready = rnd.nextInt(5) > 0
          dut.io.out.ready.poke(ready.B)
          if (ready && dut.io.out.valid.peek().litToBoolean) {
            val w = dut.io.out.bits.peekInt().toInt
            assert(dut.io.chosen.get.peekInt().toInt == (w >> 8), s"cycle $cycle: chosen names another requester than the data's")
            got((w >> 8, w & 0xff)) += 1
          }
          for (i <- 0 until n) if (offering(i) && dut.io.in(i).ready.peek().litToBoolean) {
            if (held) assert(firstOffered(i) < cycle, s"cycle $cycle: requester $i taken in the cycle it offered (the grant is not a register)")
            offering(i) = false; next(i) += 1; lastTaken(i) = cycle
          }
          for (i <- 0 until n) if (offering(i)) assert(cycle - lastTaken(i) < 20L * n, s"requester $i starved at cycle $cycle")
          dut.clock.step(); cycle += 1
          assert(cycle < 100000, "the arbiter stopped")
        }
        // drain the queues
        dut.io.out.ready.poke(true.B); for (i <- 0 until n) dut.io.in(i).valid.poke(false.B)
        // (the queues hold up to two requests per group and level)
        for (_ <- 0 until 4 * n * (dut.depth + 1)) {
          if (dut.io.out.valid.peek().litToBoolean) { val w = dut.io.out.bits.peekInt().toInt; got((w >> 8, w & 0xff)) += 1 }
          dut.clock.step()
        }
        assert(got.values.forall(_ == 1), s"duplicated: ${got.filter(_._2 != 1).take(5)}")
        assert(got.size == n * perRequester, s"lost ${n * perRequester - got.size} of ${n * perRequester}")
        // full rate: all inputs busy, output always ready
        for (i <- 0 until n) { dut.io.in(i).valid.poke(true.B); dut.io.in(i).bits.poke(0.U) }
        dut.clock.step(4 * (dut.depth + 1))
        var out = 0
        for (_ <- 0 until 100) { if (dut.io.out.valid.peek().litToBoolean) out += 1; dut.clock.step() }
        assert(out == 100, s"$out of 100 cycles delivered with every input busy")
        info(s"${dut.depth} queue levels, $cycle cycles for ${n * perRequester} requests")
      }
    }
}
