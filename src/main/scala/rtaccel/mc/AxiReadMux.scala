package rtaccel.mc

import chisel3._
import chisel3.util._

/** n AXI4 read masters onto one port (IUS > 1: each IU cluster's MC is a master; docs/architecture.md).
  * AR: round-robin, one burst per cycle, all on AXI ID 0 so that the slave answers strictly in AR order
  * (AXI orders only within an ID); a FIFO of `depth` entries remembers which master each burst belongs to
  * and how long it is, and R beats go back to that master. A full FIFO holds AR back, never R.
  * R backpressure of the head's master reaches R.ready combinationally; the MCs' own response buffers
  * (credits) make sure it never waits on another cluster.
  */
class AxiReadMux(axi: AxiParams, n: Int, depth: Int) extends Module {
  require(n >= 1 && depth >= 1, s"AxiReadMux needs at least one master and one FIFO entry (got $n, $depth)")
  val io = IO(new Bundle {
    val in = Vec(n, Flipped(new AxiReadMaster(axi)))
    val out = new AxiReadMaster(axi)
  })
  val arb = Module(new RRArbiter(new AxiAr(axi), n))
  for (i <- 0 until n) arb.io.in(i) <> io.in(i).ar
  val owners = Module(new Queue(UInt(log2Ceil(math.max(2, n)).W), depth))
  io.out.ar.valid := arb.io.out.valid && owners.io.enq.ready
  io.out.ar.bits := arb.io.out.bits
  io.out.ar.bits.id := 0.U
  arb.io.out.ready := io.out.ar.ready && owners.io.enq.ready
  owners.io.enq.valid := arb.io.out.valid && io.out.ar.ready
  owners.io.enq.bits := arb.io.chosen

  val head = owners.io.deq.bits
  io.out.r.ready := owners.io.deq.valid && VecInit(io.in.map(_.r.ready))(head)
  for ((m, i) <- io.in.zipWithIndex) {
    m.r.valid := io.out.r.valid && owners.io.deq.valid && head === i.U
    m.r.bits := io.out.r.bits
  }
  owners.io.deq.ready := io.out.r.fire && io.out.r.bits.last
  when(io.out.r.valid) { assert(owners.io.deq.valid, "AxiReadMux: an R beat with no burst outstanding") }
}
