package rtaccel.arb

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** The staged queue against a FIFO written here in Scala whose items become visible two cycles after they are taken
  * (caught, then written):
  * under random enqueues and backpressure, every cycle its `enq.ready` (fewer than `entries` taken), `deq.valid` and
  * `deq.bits` are the model's, at a power-of-two depth and another; with both sides always willing an item passes
  * per cycle.
  */
class StagedQueueSpec extends AnyFunSuite with ChiselScalatestTester {
  for (entries <- Seq(16, 3)) test(s"StagedQueue of $entries entries: a FIFO whose items show two cycles after they are taken") {
    test(new StagedQueue(UInt(16.W), entries)) { dut =>
      val rnd = new Random(entries)
      val fifo = scala.collection.mutable.Queue[Int]() // visible items
      val inFlight = scala.collection.mutable.Queue[(Int, Int)]() // taken, not visible yet: (item, first cycle visible)
      var next = 0; var passed = 0; var willing = 0
      for (cycle <- 0 until 6000) {
        val phase = (cycle / 500) % 3 // random, both sides always willing, consumer mostly stalled (fills it)
        if (phase == 1) willing += 1
        val v = phase match { case 1 => true; case _ => rnd.nextInt(3) > 0 }
        val r = phase match { case 1 => true; case 2 => rnd.nextInt(8) == 0; case _ => rnd.nextInt(2) == 0 }
        while (inFlight.headOption.exists(_._2 <= cycle)) fifo.enqueue(inFlight.dequeue()._1)
        dut.io.enq.valid.poke(v.B); dut.io.enq.bits.poke(next.U); dut.io.deq.ready.poke(r.B)
        val held = fifo.length + inFlight.length
        assert(dut.io.enq.ready.peek().litToBoolean == (held < entries), s"cycle $cycle: enq.ready with $held held")
        assert(dut.io.deq.valid.peek().litToBoolean == fifo.nonEmpty, s"cycle $cycle: deq.valid with ${fifo.length} visible")
        if (fifo.nonEmpty) assert(dut.io.deq.bits.peekInt().toInt == fifo.head, s"cycle $cycle: deq.bits")
        if (r && fifo.nonEmpty) { fifo.dequeue(); if (phase == 1) passed += 1 }
        if (v && held < entries) { inFlight.enqueue((next, cycle + 2)); next = (next + 1) & 0xffff }
        dut.clock.step()
      }
      assert(passed >= willing - 3 * 3, s"$passed items in $willing cycles with both sides always willing")
    }
  }
}
