package rtaccel.arb

import chisel3._
import chisel3.util._

/** A FIFO of `entries` in LUT RAM whose writes are a cycle late: an item enqueued is caught in a register and written
  * into the RAM in the next cycle; the dequeue side sees it the cycle after (two cycles after its enqueue, one more
  * than a Queue's). `enq.ready` comes from a count of the items taken,
  * so the enqueue's handshake (ready, the producer's valid and its fire) drives only that count and one valid bit,
  * while the RAM's write pointer and write enable come from registers. In a Chisel Queue the write pointer feeds both
  * its full compare and the write address of every RAM slice, and the placer put it beside the RAM, away from the
  * handshake: the pointer → full → enqueue → pointer loop crossed the part twice (the smallest platform's routed
  * critical path on ECP5 with TRI_II=2, 11.62 ns of which 10.60 routing, the IU's job queue).
  * The catch register loads every cycle (its valid says whether it holds an item): no enable fans out to its bits.
  */
class StagedQueue[T <: Data](gen: T, val entries: Int) extends Module {
  require(entries >= 1, s"a queue holds at least one entry (got $entries)")
  val io = IO(new Bundle {
    val enq = Flipped(Decoupled(gen))
    val deq = Decoupled(gen)
  })
  private val ram = Mem(entries, gen)
  private val countBits = log2Ceil(entries + 1)
  private val taken = RegInit(0.U(countBits.W))   // items enqueued and not dequeued (the caught one included)
  private val written = RegInit(0.U(countBits.W)) // of them, those in the RAM
  private val caught = RegNext(io.enq.bits)
  private val caughtValid = RegNext(io.enq.fire, false.B)
  private def next(ptr: UInt) = if (isPow2(entries)) ptr + 1.U else Mux(ptr === (entries - 1).U, 0.U, ptr + 1.U)
  private val wPtr = RegInit(0.U(log2Ceil(entries).max(1).W))
  private val rPtr = RegInit(0.U(log2Ceil(entries).max(1).W))
  io.enq.ready := taken =/= entries.U
  when(caughtValid) { ram(wPtr) := caught; wPtr := next(wPtr) }
  io.deq.valid := written =/= 0.U
  io.deq.bits := ram(rPtr)
  when(io.deq.fire) { rPtr := next(rPtr) }
  taken := taken + io.enq.fire.asUInt - io.deq.fire.asUInt
  written := written + caughtValid.asUInt - io.deq.fire.asUInt
}
