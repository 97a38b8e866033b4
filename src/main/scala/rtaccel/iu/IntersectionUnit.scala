package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.config.{PlatformParams, TriTest}
import rtaccel.mc.{FetchBeat, FetchReq}

/** The IU of paper Fig 1: takes requests from all TUs (round-robin), asks the memory controller for the
  * node or the leaf's primitives, assembles them from memory beats and streams them through the box and
  * triangle pipelines, one node or one primitive per cycle. Results are broadcast to the TUs (each TU has
  * at most one request outstanding and always takes its results, so the pipelines never stall).
  * Memory requests are issued ahead while earlier data is still arriving, up to `maxOutstanding`.
  */
class IntersectionUnit(p: PlatformParams, beatBits: Int, requesters: Int) extends Module {
  private val maxOutstanding = p.hw.iuOutstanding
  val io = IO(new Bundle {
    val req = Flipped(Vec(requesters, Decoupled(new IuReq(p))))
    val box = Valid(new BoxResult(p))
    val tri = Valid(new TriResult(p))
    val mem = new Bundle {
      val req = Decoupled(new FetchReq)
      val resp = Flipped(Decoupled(new FetchBeat(beatBits)))
    }
  })
  private val beatWords = beatBits / 32
  private val nodeWords = p.nodeSlotBytes / 4 // the stored node: full, or quantized (NodeDecode)
  private val primWords = p.primStrideBytes / 4
  require(beatWords <= primWords && nodeWords % beatWords == 0, s"a memory beat of $beatBits bits must divide a node and a primitive")
  private val primFlagBit = p.refs.refBits - 1

  // ---- arbitration and issue: a request goes to memory and its context to the job FIFO together
  val arb = Module(new RRArbiter(new IuReq(p), requesters))
  arb.io.in <> io.req
  class Job extends Bundle {
    val tu = UInt(p.tuBits.W)
    val isLeaf = Bool()
    val lastPrim = UInt(math.max(1, p.refs.countBits).W) // primitive count - 1
    val tmax = UInt(32.W)
    val ray = new RayData
  }
  val jobs = Module(new Queue(new Job, maxOutstanding))
  val r = arb.io.out.bits
  io.mem.req.valid := arb.io.out.valid && jobs.io.enq.ready
  io.mem.req.bits.childRef := r.cref
  jobs.io.enq.valid := arb.io.out.valid && io.mem.req.ready
  jobs.io.enq.bits.tu := r.tu
  jobs.io.enq.bits.isLeaf := r.cref(primFlagBit)
  jobs.io.enq.bits.lastPrim := (if (p.refs.countBits == 0) 0.U else r.cref(p.refs.primIndexBits + p.refs.countBits - 1, p.refs.primIndexBits))
  jobs.io.enq.bits.tmax := r.tmax
  jobs.io.enq.bits.ray := r.ray
  arb.io.out.ready := io.mem.req.ready && jobs.io.enq.ready

  // ---- collection: beats in request order become whole nodes or whole primitives
  val job = jobs.io.deq.bits
  val isLeaf = job.isLeaf
  val buf = Reg(Vec(math.max(nodeWords, primWords), UInt(32.W)))
  val beatIdx = RegInit(0.U(8.W))
  // a unit (node or primitive) is bad if any of its beats came with a memory error
  val errAcc = RegInit(false.B)
  val unitErr = errAcc || io.mem.resp.bits.err
  val primIdx = RegInit(0.U(8.W))
  io.mem.resp.ready := jobs.io.deq.valid
  val unitBeats = Mux(isLeaf, (primWords / beatWords).U, (nodeWords / beatWords).U)
  // PRIM_FORMAT=packed: a leaf's beats go to the LeafAssembler (its records span beats), not to this collection
  val packedLeaf = p.primPacked.B && isLeaf
  val beatFire = io.mem.resp.fire && !packedLeaf
  val unitDone = beatFire && beatIdx === unitBeats - 1.U
  val jobDone = unitDone && (!isLeaf || primIdx === job.lastPrim)
  // the words of the unit as they will be once this beat is stored (the last beat goes straight through)
  val words = Wire(Vec(buf.length, UInt(32.W)))
  for (w <- buf.indices) {
    val thisBeat = (w / beatWords).U === beatIdx
    words(w) := Mux(thisBeat, io.mem.resp.bits.data((w % beatWords) * 32 + 31, (w % beatWords) * 32), buf(w))
  }
  when(beatFire) {
    buf := words
    errAcc := unitErr && !unitDone
    beatIdx := Mux(unitDone, 0.U, beatIdx + 1.U)
    when(unitDone && isLeaf) { primIdx := Mux(jobDone, 0.U, primIdx + 1.U) }
  }
  jobs.io.deq.ready := jobDone

  val boxPipe = Module(new BoxPipe(p))
  val node = Wire(new NodeJob(p))
  node.tu := job.tu
  node.ray := job.ray
  node.tmax := job.tmax
  node.words := VecInit(words.take(nodeWords))
  node.err := unitErr
  boxPipe.io.in := NodeDecode.toBoxJob(p, unitDone && !isLeaf, node)
  // TRI_TEST: both pipes take the same job and give the same result, at their own latencies
  val (triIn, triOut) = p.triTest match {
    case TriTest.Mt => val t = Module(new TriPipe(p)); (t.io.in, t.io.out)
    case TriTest.Watertight => val t = Module(new WatertightPipe(p)); (t.io.in, t.io.out)
  }
  triIn.valid := unitDone && isLeaf
  triIn.bits.tu := job.tu
  triIn.bits.ray := job.ray
  triIn.bits.tmax := job.tmax
  triIn.bits.words := VecInit(words.take(10))
  triIn.bits.last := jobDone
  triIn.bits.err := unitErr
  if (p.primPacked) {
    val asm = Module(new LeafAssembler(p, beatBits))
    asm.io.in.valid := io.mem.resp.valid && jobs.io.deq.valid && isLeaf
    asm.io.in.bits.beat := io.mem.resp.bits
    asm.io.in.bits.lastPrim := job.lastPrim
    asm.io.in.bits.ctx.tu := job.tu
    asm.io.in.bits.ctx.ray := job.ray
    asm.io.in.bits.ctx.tmax := job.tmax
    io.mem.resp.ready := jobs.io.deq.valid && (!isLeaf || asm.io.in.ready)
    jobs.io.deq.ready := Mux(isLeaf, asm.io.leafTaken, jobDone)
    triIn.valid := asm.io.out.valid
    triIn.bits := asm.io.out.bits
  }
  io.box := boxPipe.io.out
  io.tri := triOut
}
