package rtaccel.mc

import scala.collection.mutable
import scala.util.Random
import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec

/** AxiReadMux (IUS > 1, MEM_CHANNELS > 1): n masters on c in-order slaves (address-interleaved by 4 KB page). Every
  * master must get exactly the beats of its own bursts, in its own order, whatever the AR/R handshakes do; each slave
  * must see one AXI ID only and only addresses of its own pages.
  */
class AxiReadMuxSpec extends AnyFlatSpec with ChiselScalatestTester {
  private val axi = AxiParams(addrBits = 32, dataBits = 64, idBits = 4)

  private def run(n: Int, depth: Int, cycles: Int, seed: Int, arReady: Double, rValid: Double, rReady: Double, c: Int = 1): Int = {
    var beatsChecked = 0
    // Verilator, one build per circuit shared by its seeds (treadle took 57 s for the multi-channel case alone)
    test(new AxiReadMux(axi, n, depth, c, 12)).withAnnotations(rtaccel.TestSim.cached(s"AxiReadMuxSpec/n$n-d$depth-c$c")) { dut =>
      val rnd = new Random(seed)
      // master i's burst k: page 4k + 0..3 of master i's 16 MB (unique, its channel random), len 0..7; a slave
      // answers beat b of address a with a * 16 + b
      val next = Array.fill(n)(0); val pendingLen = Array.fill(n)(rnd.nextInt(8))
      val page = mutable.Map[(Int, Int), Long]()
      val expected = Array.fill(n)(mutable.Queue[Long]())
      val slaves = Array.fill(c)(mutable.Queue[(Long, Int)]()) // per channel: (address, len) accepted, in order
      val slaveBeat = Array.fill(c)(0)
      def addr(i: Int, k: Int): Long = (i.toLong << 24) | (page.getOrElseUpdate((i, k), 4L * k + rnd.nextInt(4)) << 12)
      for (_ <- 0 until cycles) {
        for (i <- 0 until n) {
          val m = dut.io.in(i)
          m.ar.valid.poke(true.B) // a master that has a burst keeps AR valid until the handshake (AXI)
          m.ar.bits.addr.poke(addr(i, next(i)).U); m.ar.bits.len.poke(pendingLen(i).U)
          m.ar.bits.id.poke(i.U); m.ar.bits.size.poke(3.U); m.ar.bits.burst.poke(1.U)
          m.r.ready.poke((rnd.nextDouble() < rReady).B)
        }
        val give = Array.tabulate(c) { k =>
          val o = dut.io.out(k)
          o.ar.ready.poke((rnd.nextDouble() < arReady).B)
          val g = slaves(k).nonEmpty && rnd.nextDouble() < rValid
          o.r.valid.poke(g.B)
          if (g) {
            val (a, len) = slaves(k).head
            o.r.bits.data.poke((a * 16 + slaveBeat(k)).U); o.r.bits.last.poke((slaveBeat(k) == len).B)
            o.r.bits.resp.poke(0.U); o.r.bits.id.poke(0.U)
          }
          g
        }
        // handshakes of this cycle
        for (k <- 0 until c) {
          val o = dut.io.out(k)
          if (o.ar.valid.peek().litToBoolean && o.ar.ready.peek().litToBoolean) {
            assert(o.ar.bits.id.peek().litValue == 0, "the mux must put every burst on ID 0 (in-order answers)")
            val a = o.ar.bits.addr.peek().litValue.toLong
            assert(((a >> 12) % c) == k, s"address $a went to channel $k")
            slaves(k).enqueue((a, o.ar.bits.len.peek().litValue.toInt))
          }
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
        val othersValid = (0 until n).count(i => dut.io.in(i).r.valid.peek().litToBoolean)
        assert(othersValid <= c, "more R beats went out than channels gave")
        for (k <- 0 until c if give(k) && dut.io.out(k).r.ready.peek().litToBoolean) {
          if (slaveBeat(k) == slaves(k).head._2) { slaves(k).dequeue(); slaveBeat(k) = 0 } else slaveBeat(k) += 1
        }
        dut.clock.step()
      }
      // drain: every slave answers everything, every master takes everything
      var guard = 0
      while (slaves.exists(_.nonEmpty) && guard < 20000) {
        for (i <- 0 until n) { dut.io.in(i).ar.valid.poke(false.B); dut.io.in(i).r.ready.poke(true.B) }
        val give = Array.tabulate(c) { k =>
          val o = dut.io.out(k); o.ar.ready.poke(false.B)
          o.r.valid.poke(slaves(k).nonEmpty.B)
          if (slaves(k).nonEmpty) { val (a, len) = slaves(k).head; o.r.bits.data.poke((a * 16 + slaveBeat(k)).U); o.r.bits.last.poke((slaveBeat(k) == len).B) }
          slaves(k).nonEmpty
        }
        for (i <- 0 until n if dut.io.in(i).r.valid.peek().litToBoolean) {
          assert(dut.io.in(i).r.bits.data.peek().litValue.toLong == expected(i).dequeue()); beatsChecked += 1
        }
        for (k <- 0 until c if give(k) && dut.io.out(k).r.ready.peek().litToBoolean) {
          if (slaveBeat(k) == slaves(k).head._2) { slaves(k).dequeue(); slaveBeat(k) = 0 } else slaveBeat(k) += 1
        }
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
  it should "route 3 masters over 2 and 4 interleaved channels, each master's beats in its own order (MEM_CHANNELS)" in {
    for ((c, seed) <- Seq(2 -> 21, 4 -> 22, 2 -> 23)) {
      val n = run(3, 4, 3000, seed, arReady = 0.6, rValid = 0.6, rReady = 0.7, c = c)
      info(s"$c channels, seed $seed: $n beats checked")
    }
  }
  it should "serve one master over 2 channels (IUS=1, MEM_CHANNELS=2)" in {
    run(1, 4, 2000, 31, arReady = 0.7, rValid = 0.5, rReady = 0.8, c = 2)
  }
}
