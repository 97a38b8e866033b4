package rtaccel.mc

import chisel3._
import chisel3.util._

/** n AXI4 read masters onto c address-interleaved channels (IUS > 1: each IU cluster's MC is a master;
  * MEM_CHANNELS = c: channel = (addr >> interleaveLog2) mod c; docs/platform.md).
  * AR: one round-robin arbiter for all masters, one burst per cycle to its channel, every burst on AXI ID 0 so
  * that each channel answers strictly in its AR order (AXI orders only within an ID). Each channel keeps a FIFO
  * of the owner of each burst; each master (c > 1) a FIFO of the channel of each of its bursts. A master takes R
  * beats only from the channel of its oldest burst, and only when that channel's oldest burst is its own, so every
  * master sees its beats in its own AR order, as its MC expects.
  * Why this cannot deadlock: the single arbiter orders all bursts globally and every channel serves them in that
  * order, so the oldest burst in flight is at the head of both its channel and its master; and the MCs' response
  * buffers (credits) make every master take its beats without waiting on anything else.
  * A full FIFO holds AR back, never R.
  */
class AxiReadMux(axi: AxiParams, n: Int, depth: Int, channels: Int = 1, interleaveLog2: Int = 12) extends Module {
  require(n >= 1 && depth >= 1, s"AxiReadMux needs at least one master and one FIFO entry (got $n, $depth)")
  require(channels >= 1 && isPow2(channels), s"channels must be a power of two (got $channels)")
  require(interleaveLog2 >= 12, "a channel block must hold whole 4 KB pages (no AXI burst crosses 4 KB)")
  val io = IO(new Bundle {
    val in = Vec(n, Flipped(new AxiReadMaster(axi)))
    val out = Vec(channels, new AxiReadMaster(axi))
  })
  private val chBits = log2Ceil(channels)
  val arb = Module(new RRArbiter(new AxiAr(axi), n))
  for (i <- 0 until n) arb.io.in(i) <> io.in(i).ar
  val owners = Seq.fill(channels)(Module(new Queue(UInt(log2Ceil(math.max(2, n)).W), depth)))
  // c > 1: the channel of each master's bursts, oldest first
  val chans = if (channels == 1) Nil else Seq.fill(n)(Module(new Queue(UInt(chBits.W), depth)))
  val ar = arb.io.out.bits
  val ch: UInt = if (channels == 1) 0.U else ar.addr(interleaveLog2 + chBits - 1, interleaveLog2)
  val roomOwner = VecInit(owners.map(_.io.enq.ready))(ch)
  val roomChan = if (channels == 1) true.B else VecInit(chans.map(_.io.enq.ready))(arb.io.chosen)
  val chReady = VecInit(io.out.map(_.ar.ready))(ch)
  val go = arb.io.out.valid && roomOwner && roomChan
  for ((o, k) <- io.out.zipWithIndex) {
    o.ar.valid := go && ch === k.U
    o.ar.bits := ar
    o.ar.bits.id := 0.U
  }
  arb.io.out.ready := chReady && roomOwner && roomChan
  val fire = go && chReady
  for ((q, k) <- owners.zipWithIndex) { q.io.enq.valid := fire && ch === k.U; q.io.enq.bits := arb.io.chosen }
  for ((q, i) <- chans.zipWithIndex) { q.io.enq.valid := fire && arb.io.chosen === i.U; q.io.enq.bits := ch }

  // R: master i's oldest burst is on channel headCh(i); it is served when that channel's oldest burst is master i's
  def headCh(i: Int): UInt = if (channels == 1) 0.U else chans(i).io.deq.bits
  def headValid(i: Int): Bool = if (channels == 1) true.B else chans(i).io.deq.valid
  val rValid = VecInit(io.out.map(_.r.valid)); val rBits = VecInit(io.out.map(_.r.bits))
  val served = Seq.tabulate(n) { i =>
    val k = headCh(i)
    headValid(i) && VecInit(owners.map(_.io.deq.valid))(k) && VecInit(owners.map(_.io.deq.bits))(k) === i.U
  }
  for ((m, i) <- io.in.zipWithIndex) {
    m.r.valid := served(i) && rValid(headCh(i))
    m.r.bits := rBits(headCh(i))
  }
  for ((o, k) <- io.out.zipWithIndex) {
    val owner = owners(k).io.deq.bits
    val ownerTakes = VecInit(Seq.tabulate(n)(i => served(i) && headCh(i) === k.U && io.in(i).r.ready))(owner)
    o.r.ready := owners(k).io.deq.valid && ownerTakes
    owners(k).io.deq.ready := o.r.fire && o.r.bits.last
    when(o.r.valid) { assert(owners(k).io.deq.valid, "AxiReadMux: an R beat with no burst outstanding on its channel") }
  }
  for ((q, i) <- chans.zipWithIndex) q.io.deq.ready := io.in(i).r.fire && io.in(i).r.bits.last
}
