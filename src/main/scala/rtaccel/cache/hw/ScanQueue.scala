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
  private val ptrBits = math.max(1, log2Ceil(entries))
  private def next(x: UInt): UInt = if (entries == 1) 0.U else Mux(x === (entries - 1).U, 0.U, x + 1.U)
  private val head = RegInit(0.U(ptrBits.W)); private val tail = RegInit(0.U(ptrBits.W))
  // the entries held, and whether there is room, in registers of their own: `!full(tail)` was a selection of every
  // slot's bit by the tail (3 LUT levels at 32 entries) in front of the cache path's lookup decision and on into its
  // tag RAMs' write enables (8 levels on xc5v, CachePath)
  private val count = RegInit(0.U(log2Ceil(entries + 1).W))
  private val room = RegInit(true.B)
  private val countNext = count + io.enq.fire.asUInt - io.deq.fire.asUInt
  count := countNext
  room := countNext =/= entries.U
  io.enq.ready := room
  io.deq.valid := full(head)
  io.deq.bits := slots(head)
  when(io.deq.fire) { full(head) := false.B; head := next(head) }
  when(io.enq.fire) { slots(tail) := io.enq.bits; full(tail) := true.B; tail := next(tail) }
  io.count := count
  assert(count === PopCount(full) && room === !full(tail), "ScanQueue: its count out of step with its slots")
  for (i <- 0 until entries) { io.held(i).valid := full(i); io.held(i).bits := slots(i) }
}
