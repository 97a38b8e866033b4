package rtaccel.cache.hw

import chisel3._
import chisel3.util._

/** A FIFO whose every held entry is visible (`held`: valid = the slot holds an entry), so that a hazard check can
  * look at all of them in one cycle (RESP_ORDER=tagged, CachePath: a hit against the fills still to be written, a
  * fill against the hits still to be read). Registers, not a RAM: the check reads every slot at once.
  * One enqueue and one dequeue per cycle; not flow-through (an entry is held for at least one cycle). Its ports
  * are a Queue's (QueueIO) plus `held`, so that it can stand where a Queue stood.
  */
class ScanQueueIO[T <: Data](gen: T, entries: Int) extends QueueIO(gen, entries) {
  val held = Output(Vec(entries, Valid(gen)))
}

class ScanQueue[T <: Data](gen: T, val entries: Int) extends Module {
  require(entries >= 1, s"a queue needs at least one entry (got $entries)")
  val io = IO(new ScanQueueIO(gen, entries))
  private val slots = Reg(Vec(entries, gen))
  private val full = RegInit(VecInit(Seq.fill(entries)(false.B)))
  // The producer's valid is the end of a hazard check in the cache path (a line against every held one, 9 LUT levels
  // on xc5v into the slots' write enables), so it reaches as little as it can: head and tail are one-hot, an entry's
  // data is written into the empty tail slot whenever there is room (it is held, `full`, only when it enters), and
  // the count, room and non-empty bits are registers whose next values are chosen by the enqueue, not computed after
  // it. The ready is the room register (a selection of every slot's bit by the tail before).
  private def rotate(x: UInt): UInt = if (entries == 1) x else Cat(x(entries - 2, 0), x(entries - 1))
  private val headOH = RegInit(1.U(entries.W)); private val tailOH = RegInit(1.U(entries.W))
  private val count = RegInit(0.U(log2Ceil(entries + 1).W))
  private val room = RegInit(true.B); private val some = RegInit(false.B)
  io.enq.ready := room
  io.deq.valid := some
  io.deq.bits := Mux1H(headOH, slots)
  private val enqFire = io.enq.valid && room
  private val deqFire = io.deq.ready && some
  for (i <- 0 until entries) {
    when(room && tailOH(i)) { slots(i) := io.enq.bits }
    full(i) := Mux(enqFire && tailOH(i), true.B, Mux(deqFire && headOH(i), false.B, full(i)))
  }
  when(enqFire) { tailOH := rotate(tailOH) }
  when(deqFire) { headOH := rotate(headOH) }
  private val kept = count - deqFire.asUInt // the count if nothing enters
  private val grown = kept + 1.U
  count := Mux(enqFire, grown, kept)
  room := Mux(enqFire, grown =/= entries.U, kept =/= entries.U)
  some := Mux(enqFire, true.B, kept =/= 0.U)
  io.count := count
  for (i <- 0 until entries) { io.held(i).valid := full(i); io.held(i).bits := slots(i) }
  assert(count === PopCount(full) && room === !Mux1H(tailOH, full) && some === Mux1H(headOH, full),
    "ScanQueue: its count out of step with its slots")
}
