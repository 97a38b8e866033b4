package rtaccel.arb

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams

/** A register slice on a handshake between units, with PIPELINE only: a queue of `p.sliceEntries`, so that
  * neither the producer's valid and data nor the consumer's ready cross it in the same cycle (each side's logic
  * ends at the slice's registers). One cycle more per item; an item every cycle still.
  */
object Slice {
  def apply[T <: Data](p: PlatformParams, d: DecoupledIO[T]): DecoupledIO[T] =
    if (p.stageBudget.isDefined) Queue(d, p.sliceEntries) else d

  /** `x` a cycle late through a register (zero after reset) with PIPELINE, else `x` itself: for signals no
    * handshake holds (events, status bits).
    */
  def late[T <: Data](p: PlatformParams, x: T): T = if (p.stageBudget.isDefined) RegNext(x, 0.U.asTypeOf(x)) else x

  /** A job stream that never stalls, a cycle late through a register with PIPELINE (the bits load only with a job). */
  def late[T <: Data](p: PlatformParams, j: Valid[T]): Valid[T] = if (p.stageBudget.isEmpty) j else {
    val r = Wire(Valid(chiselTypeOf(j.bits)))
    r.valid := RegNext(j.valid, false.B)
    r.bits := RegEnable(j.bits, j.valid)
    r
  }
}
