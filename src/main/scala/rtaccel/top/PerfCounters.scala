package rtaccel.top

import chisel3._

/** Performance counters in one place: each is a 64-bit event count, cleared by the control register. */
class PerfCounters(val names: Seq[String]) extends Module {
  val io = IO(new Bundle {
    val clear = Input(Bool())
    val events = Input(Vec(names.length, UInt(8.W))) // increments per cycle (several TUs may stall at once)
    val values = Output(Vec(names.length, UInt(64.W)))
  })
  val regs = RegInit(VecInit(Seq.fill(names.length)(0.U(64.W))))
  for (i <- names.indices) regs(i) := Mux(io.clear, 0.U, regs(i) + io.events(i))
  io.values := regs
}
