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
}
