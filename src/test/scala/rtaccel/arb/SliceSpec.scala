package rtaccel.arb

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** The register slice against a two-entry FIFO written here in Scala: under random enqueues and random
  * backpressure, every cycle its `enq.ready`, `deq.valid` and `deq.bits` are the FIFO's (so a slice is a two-entry
  * queue cycle for cycle), and with both sides always willing one item passes per cycle.
  */
class SliceSpec extends AnyFunSuite with ChiselScalatestTester {
  test("RegSlice behaves as a two-entry queue, cycle for cycle") {
    test(new RegSlice(UInt(16.W))) { dut =>
      val rnd = new Random(7)
      val fifo = scala.collection.mutable.Queue[Int]()
      var next = 0
      var passed = 0; var willing = 0 // items passed and cycles in the always-willing phase
      for (cycle <- 0 until 4000) {
        // phases: random, both sides always willing, consumer stalled
        val phase = (cycle / 500) % 3
        if (phase == 1) willing += 1
        val v = phase match { case 1 => true; case _ => rnd.nextInt(3) > 0 }
        val r = phase match { case 1 => true; case 2 => rnd.nextInt(8) == 0; case _ => rnd.nextInt(2) == 0 }
        dut.io.enq.valid.poke(v.B); dut.io.enq.bits.poke(next.U); dut.io.deq.ready.poke(r.B)
        assert(dut.io.enq.ready.peek().litToBoolean == (fifo.length < 2), s"cycle $cycle: enq.ready with ${fifo.length} held")
        assert(dut.io.deq.valid.peek().litToBoolean == fifo.nonEmpty, s"cycle $cycle: deq.valid with ${fifo.length} held")
        if (fifo.nonEmpty) assert(dut.io.deq.bits.peekInt().toInt == fifo.head, s"cycle $cycle: deq.bits")
        val deq = r && fifo.nonEmpty
        val enq = v && fifo.length < 2
        if (deq) { fifo.dequeue(); if (phase == 1) passed += 1 }
        if (enq) { fifo.enqueue(next); next = (next + 1) & 0xffff }
        dut.clock.step()
      }
      // (each always-willing phase starts from whatever the phase before left: at most two cycles to fill)
      assert(passed >= willing - 2 * 3, s"$passed items in $willing cycles with both sides always willing")
    }
  }
}
