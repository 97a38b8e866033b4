package rtaccel.arb

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams

/** A register slice of two entries: an output register and a skid register beside it. Its handshake is that of a
  * two-entry queue cycle for cycle (an item enqueued leaves a cycle later at the earliest; `enq.ready` while fewer
  * than two are held), but every output is a register: `deq.valid` and `deq.bits` come straight from the output
  * register (a queue's read mux and its pointer compare are a LUT level after its registers) and `enq.ready` is the
  * skid register's empty bit. So neither side's logic runs into the other's, nor into the slice's own.
  */
class RegSlice[T <: Data](gen: T) extends Module {
  val io = IO(new Bundle {
    val enq = Flipped(Decoupled(gen))
    val deq = Decoupled(gen)
    /** what it holds: the output register, then the skid register (a hazard check may scan them) */
    val held = Output(Vec(2, Valid(gen)))
  })
  private val outValid = RegInit(false.B)
  private val out = Reg(gen)
  private val skidValid = RegInit(false.B) // only while the output register is held
  private val skid = Reg(gen)
  io.held(0).valid := outValid; io.held(0).bits := out
  io.held(1).valid := skidValid; io.held(1).bits := skid
  io.enq.ready := !skidValid
  io.deq.valid := outValid
  io.deq.bits := out
  // The data registers load whether or not an item arrives (their valid bits say whether they hold one), so a load
  // enable never waits for `enq.valid`: a producer's valid (a queue's pointer compare) reached every bit's enable
  // in the same cycle (the TC's routed critical path on ECP5, a 385-bit ray).
  when(io.deq.ready || !outValid) { // the output register takes the oldest item held, else the one arriving
    outValid := skidValid || io.enq.valid
    out := Mux(skidValid, skid, io.enq.bits)
    skidValid := false.B
  }.elsewhen(!skidValid) {
    skidValid := io.enq.valid
    skid := io.enq.bits
  }
}

/** Register slices on the handshakes between units, with PIPELINE only (one cycle more per item; an item every
  * cycle still).
  */
object Slice {
  def apply[T <: Data](p: PlatformParams, d: DecoupledIO[T]): DecoupledIO[T] = if (p.stageBudget.isEmpty) d else {
    val s = Module(new RegSlice(chiselTypeOf(d.bits)))
    s.io.enq <> d
    s.io.deq
  }

  /** `x` a cycle late through a register (zero after reset) with PIPELINE, else `x` itself: for signals no
    * handshake holds (events, status bits).
    */
  def late[T <: Data](p: PlatformParams, x: T): T = if (p.stageBudget.isDefined) RegNext(x, 0.U.asTypeOf(x)) else x

  /** A job stream that never stalls, a cycle late through a register with PIPELINE. The bits load every cycle and
    * are read only with their valid: a load enable would be the valid's fan-out to every bit of a wide job, which
    * routed as the smallest platform's critical path on ECP5 (the IU's job queue pointers through the valid to
    * the box pipe's input register, docs/timing.md).
    */
  def late[T <: Data](p: PlatformParams, j: Valid[T]): Valid[T] = late(p.stageBudget, j)
  /** The same for a unit that takes a view with the register budget (tu.TuParams). */
  def late[T <: Data](stageBudget: Option[Int], j: Valid[T]): Valid[T] = if (stageBudget.isEmpty) j else {
    val r = Wire(Valid(chiselTypeOf(j.bits)))
    r.valid := RegNext(j.valid, false.B)
    r.bits := RegNext(j.bits)
    r
  }
}
