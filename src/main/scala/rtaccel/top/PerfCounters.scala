package rtaccel.top

import chisel3._

/** Performance counters in one place: each is a 64-bit event count, cleared by the control register.
  * Increments are `incBits` wide, sized by the caller from the parameters (several TUs may stall in one
  * cycle: log2(TUs + 1) bits), so no event is ever truncated; 64 bits do not wrap in any run.
  */
class PerfCounters(val names: Seq[String], val incBits: Int) extends Module {
  require(incBits >= 1 && incBits <= 32, s"counter increments must be 1..32 bits (got $incBits)")
  val io = IO(new Bundle {
    val clear = Input(Bool())
    val events = Input(Vec(names.length, UInt(incBits.W))) // increments per cycle
    val values = Output(Vec(names.length, UInt(64.W)))
  })
  val regs = RegInit(VecInit(Seq.fill(names.length)(0.U(64.W))))
  for (i <- names.indices) regs(i) := Mux(io.clear, 0.U, regs(i) + io.events(i))
  io.values := regs
}
