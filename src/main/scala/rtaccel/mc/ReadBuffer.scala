package rtaccel.mc

import chisel3._
import chisel3.util._

/** A path's response buffer (MemoryController, respBufferBeats > 0) whose room is reserved per read: a read granted
  * to DRAM is given the next `beats` slots (`base`, the credits the MC keeps guarantee they are free), and each of
  * its beats lands in its own slot, base + its index. Beats leave in slot order, each as soon as it has landed.
  *
  * So a read's beats may land in any order and more than once is never needed: MEM_RETRIES re-reads a failed read
  * into the slots its first read reserved while later reads' beats land behind it, and the path still sees its
  * reads in the order it made them. A slot is written only while empty (the MC drops the beats a re-read repeats).
  */
class ReadBuffer(gen: FetchBeat, val size: Int, beatsBits: Int) extends Module {
  require(size >= 2, "a response buffer needs at least two slots")
  val slotBits: Int = math.max(1, log2Ceil(size))
  val io = IO(new Bundle {
    /** a read of `allocBeats` beats is granted this cycle: it gets the slots from `base` on */
    val alloc = Input(Bool())
    val allocBeats = Input(UInt(beatsBits.W))
    val base = Output(UInt(slotBits.W))
    /** a beat landing in `slot` */
    val write = Flipped(Valid(new Bundle {
      val slot = UInt(slotBits.W)
      val beat = gen.cloneType
    }))
    val deq = Decoupled(gen.cloneType)
  })
  /** (a + b) mod size, for a, b < size (size need not be a power of two) */
  def wrap(a: UInt, b: UInt): UInt = { val s = a +& b; Mux(s >= size.U, s - size.U, s)(slotBits - 1, 0) }

  private val ram = Mem(size, gen.cloneType)
  private val full = RegInit(VecInit(Seq.fill(size)(false.B))) // the slot holds a beat not yet taken
  private val alloc = RegInit(0.U(slotBits.W))
  private val head = RegInit(0.U(slotBits.W))
  // the slot after head, kept in a register: a beat's leaving (full(head), the consumer's ready) then selects head's
  // next value and does not run through head's increment and wrap too (Yosys folds head into the RAM's read port, so
  // that path ended in the RAM: the MC's routed critical path on ECP5, 9 LUT levels)
  private val headNext = RegInit(1.U(slotBits.W))
  // whether head's slot holds a beat (full(head)), kept in a register for the same reason: the beat's leaving then
  // waits on no 1-of-size select, so head's next value is two LUT levels from registers
  private val headFull = RegInit(false.B)
  private def lands(slot: UInt): Bool = io.write.valid && io.write.bits.slot === slot
  io.base := alloc
  when(io.alloc) { alloc := wrap(alloc, io.allocBeats) }

  io.deq.valid := headFull
  io.deq.bits := ram(head)
  headFull := Mux(io.deq.fire, full(headNext) || lands(headNext), headFull || lands(head))
  when(io.deq.fire) { full(head) := false.B; head := headNext; headNext := wrap(headNext, 1.U) }
  assert(headFull === full(head), "ReadBuffer: the head's full bit and its register disagree")
  when(io.write.valid) {
    ram(io.write.bits.slot) := io.write.bits.beat
    full(io.write.bits.slot) := true.B
    assert(!full(io.write.bits.slot), "ReadBuffer: a beat landed on a slot still full")
  }
}
