package rtaccel.mc

import scala.collection.mutable
import scala.util.Random
import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec

/** AxiReadMux (IUS > 1): n masters on one in-order slave. Every master must get exactly the beats of its own
  * bursts, in its own order, whatever the AR/R handshakes do; the slave must see one AXI ID only.
  */
class AxiReadMuxSpec extends AnyFlatSpec with ChiselScalatestTester {
  private val axi = AxiParams(addrBits = 32, dataBits = 64, idBits = 4)

  private def run(n: Int, depth: Int, cycles: Int, seed: Int, arReady: Double, rValid: Double, rReady: Double): Int = {
    var beatsChecked = 0
    test(new AxiReadMux(axi, n, depth)) { dut =>
      val rnd = new Random(seed)
      // master i's bursts: address i << 20 | k << 4, len 0..7; the slave answers beat b of address a with a * 16 + b
      val next = Array.fill(n)(0); val pendingLen = Array.fill(n)(rnd.nextInt(8))
      val expected = Array.fill(n)(mutable.Queue[Long]())
      val slave = mutable.Queue[(Long, Int)]() // (address, len) accepted, in order
      var slaveBeat = 0
      def addr(i: Int, k: Int): Long = (i.toLong << 20) | (k.toLong << 4)
      for (_ <- 0 until cycles) {
        for (i <- 0 until n) {
          val m = dut.io.in(i)
          m.ar.valid.poke(true.B) // a master that has a burst keeps AR valid until the handshake (AXI)
          m.ar.bits.addr.poke(addr(i, next(i)).U); m.ar.bits.len.poke(pendingLen(i).U)
          m.ar.bits.id.poke(i.U); m.ar.bits.size.poke(3.U); m.ar.bits.burst.poke(1.U)
          m.r.ready.poke((rnd.nextDouble() < rReady).B)
        }
        dut.io.out.ar.ready.poke((rnd.nextDouble() < arReady).B)
        val give = slave.nonEmpty && rnd.nextDouble() < rValid
        dut.io.out.r.valid.poke(give.B)
        if (give) {
          val (a, len) = slave.head
          dut.io.out.r.bits.data.poke((a * 16 + slaveBeat).U); dut.io.out.r.bits.last.poke((slaveBeat == len).B)
          dut.io.out.r.bits.resp.poke(0.U); dut.io.out.r.bits.id.poke(0.U)
        }
        // handshakes of this cycle
        if (dut.io.out.ar.valid.peek().litToBoolean && dut.io.out.ar.ready.peek().litToBoolean) {
          assert(dut.io.out.ar.bits.id.peek().litValue == 0, "the mux must put every burst on ID 0 (in-order answers)")
          slave.enqueue((dut.io.out.ar.bits.addr.peek().litValue.toLong, dut.io.out.ar.bits.len.peek().litValue.toInt))
        }
        for (i <- 0 until n) {
          val m = dut.io.in(i)
          if (m.ar.ready.peek().litToBoolean) {
            for (b <- 0 to pendingLen(i)) expected(i).enqueue(addr(i, next(i)) * 16 + b)
            next(i) += 1; pendingLen(i) = rnd.nextInt(8)
          }
          if (m.r.valid.peek().litToBoolean && m.r.ready.peek().litToBoolean) {
            assert(expected(i).nonEmpty, s"master $i got a beat it never asked for")
            assert(m.r.bits.data.peek().litValue.toLong == expected(i).dequeue(), s"master $i got another master's beat or one out of order")
            beatsChecked += 1
          }
        }
        val rFire = give && dut.io.out.r.ready.peek().litToBoolean
        val othersValid = (0 until n).count(i => dut.io.in(i).r.valid.peek().litToBoolean)
        assert(othersValid <= 1, "an R beat went to more than one master")
        if (rFire) {
          if (slaveBeat == slave.head._2) { slave.dequeue(); slaveBeat = 0 } else slaveBeat += 1
        }
        dut.clock.step()
      }
      // drain: the slave answers everything, every master takes everything
      var guard = 0
      while (slave.nonEmpty && guard < 10000) {
        for (i <- 0 until n) { dut.io.in(i).ar.valid.poke(false.B); dut.io.in(i).r.ready.poke(true.B) }
        val (a, len) = slave.head
        dut.io.out.r.valid.poke(true.B); dut.io.out.r.bits.data.poke((a * 16 + slaveBeat).U); dut.io.out.r.bits.last.poke((slaveBeat == len).B)
        for (i <- 0 until n if dut.io.in(i).r.valid.peek().litToBoolean) {
          assert(dut.io.in(i).r.bits.data.peek().litValue.toLong == expected(i).dequeue()); beatsChecked += 1
        }
        if (slaveBeat == len) { slave.dequeue(); slaveBeat = 0 } else slaveBeat += 1
        dut.clock.step(); guard += 1
      }
      for (i <- 0 until n) assert(expected(i).isEmpty, s"master $i is missing ${expected(i).length} beats")
      assert(next.forall(_ > 2), s"every master must have had bursts accepted: ${next.mkString(", ")}")
    }
    beatsChecked
  }

  "AxiReadMux" should "give each of 3 masters exactly its own beats in order under random handshakes" in {
    for (seed <- 1 to 3) {
      val n = run(3, 4, 3000, seed, arReady = 0.6, rValid = 0.7, rReady = 0.6)
      info(s"seed $seed: $n beats checked")
    }
  }
  it should "work with one master, a one-entry FIFO and a slow slave" in {
    run(1, 1, 1500, 7, arReady = 0.3, rValid = 0.4, rReady = 0.9)
  }
  it should "work with 4 masters always ready (the platform's MCs with response buffers)" in {
    run(4, 8, 2000, 11, arReady = 0.9, rValid = 0.9, rReady = 1.0)
  }
}
