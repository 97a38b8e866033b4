package rtaccel.iu

import chisel3._
import chisel3.experimental.hierarchy.{instantiable, public}
import chisel3.util._
import rtaccel.config.{PlatformParams, TriTest}
import rtaccel.mc.{FetchBeat, FetchReq}

/** The IU of paper Fig 1: takes requests from all TUs (round-robin), asks the memory controller for the
  * node or the leaf's primitives, assembles them from memory beats and streams them through the box and
  * triangle pipelines, one node or one primitive per cycle. Results are broadcast to the TUs (each TU has
  * at most one request outstanding and always takes its results, so the pipelines never stall).
  * Memory requests are issued ahead while earlier data is still arriving, up to `maxOutstanding`.
  * RESP_ORDER=request: one job FIFO and one collection follow the MC's single in-order stream.
  * RESP_ORDER=path: a job FIFO and a collection per kind (nodes, leaves), each fed by its own MC stream, so a
  * node's box test never waits for an older leaf's data; up to `maxOutstanding` jobs of each kind.
  * RESP_ORDER=tagged: the two streams answer in any order, each beat tagged with its requester (the arbiter's
  * input: a TU has one request in flight); a job table per kind of one entry per requester (LUTRAM) replaces the
  * FIFOs and each collection reads its job by the beat's tag.
  * RAY_STORE=1: requests and jobs carry no ray; the ray store (LUTRAM, one entry per requester, written through
  * `rays` as the TC hands a TU its ray) is read by the job's TU index as each node or primitive is assembled.
  * Instantiable: the board top elaborates one and instantiates it per cluster (IUS), so the pipes, most of the
  * circuit's text, are elaborated and compiled by firtool once whatever the clusters.
  */
@instantiable
class IntersectionUnit(p: PlatformParams, beatBits: Int, requesters: Int) extends Module {
  private val maxOutstanding = p.hw.iuOutstanding
  @public val io = IO(new Bundle {
    val req = Flipped(Vec(requesters, Decoupled(new IuReq(p.tuBits, p.rayStore))))
    val box = Valid(new BoxResult(p.pipes))
    val tri = Valid(new TriResult(p.pipes))
    val mem = new Bundle {
      val req = Decoupled(new FetchReq(p.respTagBits))
      val resp = Flipped(Decoupled(new FetchBeat(beatBits, p.respTagBits))) // RESP_ORDER=path: node beats only
      val primResp = if (p.respByPath) Some(Flipped(Decoupled(new FetchBeat(beatBits, p.respTagBits)))) else None // RESP_ORDER=path
    }
    val rays = if (p.rayStore) Some(Flipped(Valid(new RayWrite(requesters)))) else None // RAY_STORE=1
  })
  private val beatWords = beatBits / 32
  private val nodeWords = p.nodeSlotBytes / 4 // the stored node: full, or quantized (NodeDecode)
  private val primWords = p.primStrideBytes / 4
  require(beatWords <= primWords && nodeWords % beatWords == 0, s"a memory beat of $beatBits bits must divide a node and a primitive")
  private val primFlagBit = p.refs.refBits - 1

  // ---- arbitration and issue: a request goes to memory and its context to the job FIFO together
  // a tree of small arbiters with queues between its levels (PIPELINE), one RRArbiter without a budget
  // (the winner's index tags requests with RESP_ORDER=tagged only); with PIPELINE the leaves' grants are registers
  // (a TU holds its request until taken), so a TU's request and its ready are not one path through the arbiter
  val arb = Module(new rtaccel.arb.TreeArbiter(new IuReq(p.tuBits, p.rayStore), requesters, rtaccel.arb.TreeArbiter.fanIn(p.stageBudget, requesters),
    withChosen = p.respTagged, heldInputs = p.stageBudget.isDefined))
  arb.io.in <> io.req
  class Job extends Bundle {
    val tu = UInt(p.tuBits.W)
    val isLeaf = Bool()
    val lastPrim = UInt(math.max(1, p.refs.countBits).W) // primitive count - 1
    val tmax = UInt(32.W)
    val ray = if (p.rayStore) None else Some(new RayData)
  }
  // RAY_STORE=1: the rays of this IU's requesters, by index; a TU's entry changes only while it is idle
  val rayStore = io.rays.map { w =>
    val s = Mem(math.max(2, requesters), new RayData).suggestName("ray_store")
    when(w.valid) { s.write(w.bits.slot, w.bits.ray) }
    s
  }
  def rayOf(job: Job): RayData = rayStore.fold(job.ray.get) { s =>
    val slot = Wire(UInt(RayWrite.slotBits(requesters).W))
    slot := job.tu // a TU's index within the cluster: the low bits (the store has one entry per requester)
    s(slot)
  }
  // one FIFO for every job (RESP_ORDER=request), or FIFO 0 for nodes and FIFO 1 for leaves (RESP_ORDER=path)
  // (instance names: `jobs` as before RESP_ORDER existed, `jobs_node` / `jobs_leaf` with path)
  // (path: each kind's FIFO its own module, so that the fields its kind never reads are not stored)
  // (with PIPELINE a StagedQueue: its write pointer out of the enqueue's handshake, a job visible a cycle later)
  val jobQs: Seq[(DecoupledIO[Job], DecoupledIO[Job])] = (if (p.respTagged) Nil else if (p.respByPath) Seq("jobs_node", "jobs_leaf") else Seq("jobs")).map { n =>
    val (q, enq, deq) = if (p.stageBudget.isDefined) { val q = Module(new rtaccel.arb.StagedQueue(new Job, maxOutstanding)); (q, q.io.enq, q.io.deq) }
      else { val q = Module(new Queue(new Job, maxOutstanding)); (q, q.io.enq, q.io.deq) }
    q.suggestName(n)
    if (p.respByPath) chisel3.experimental.doNotDedup(q)
    (enq, deq)
  }
  // the requests leave through a register slice with PIPELINE (arb.Slice): the MC's ready then ends here
  val memReq = Wire(Decoupled(new FetchReq(p.respTagBits)))
  io.mem.req <> rtaccel.arb.Slice(p, memReq)
  // with PIPELINE the winner passes a register slice (arb.Slice) before it becomes a memory request and a job, so the
  // job queues' and the request slice's ready end there and do not run through the arbiter's grants into the TUs'
  // states (the smallest platform's routed critical path at TRI_II=BOX_II=2: a job queue's full compare -> the
  // arbiter -> a TU's state, 9.7 ns of it routing; a cycle more per access: PlatformParams.accessSliceCycles)
  class Issue extends Bundle {
    val req = new IuReq(p.tuBits, p.rayStore)
    val chosen = UInt(math.max(1, log2Ceil(requesters)).W) // the winner's input (RESP_ORDER=tagged only)
  }
  val issueIn = Wire(Decoupled(new Issue))
  issueIn.valid := arb.io.out.valid
  issueIn.bits.req := arb.io.out.bits
  issueIn.bits.chosen := arb.io.chosen.getOrElse(0.U)
  arb.io.out.ready := issueIn.ready
  val issue = rtaccel.arb.Slice(p, issueIn)
  val r = issue.bits.req
  val reqIsLeaf = r.cref(primFlagBit)
  val jobReady = if (p.respTagged) true.B else if (p.respByPath) Mux(reqIsLeaf, jobQs(1)._1.ready, jobQs(0)._1.ready) else jobQs(0)._1.ready
  memReq.valid := issue.valid && jobReady
  memReq.bits.childRef := r.cref
  for (t <- memReq.bits.tag) t := issue.bits.chosen
  val newJob = Wire(new Job)
  newJob.tu := r.tu
  newJob.isLeaf := reqIsLeaf
  newJob.lastPrim := (if (p.refs.countBits == 0) 0.U else r.cref(p.refs.primIndexBits + p.refs.countBits - 1, p.refs.primIndexBits))
  newJob.tmax := r.tmax
  for ((j, q) <- newJob.ray.zip(r.ray)) j := q
  for ((q, i) <- jobQs.zipWithIndex) {
    val mine = if (p.respByPath) reqIsLeaf === (i == 1).B else true.B
    q._1.valid := issue.valid && memReq.ready && mine
    q._1.bits := newJob
  }
  issue.ready := memReq.ready && jobReady
  // RESP_ORDER=tagged: a requester's job waits in its entry of its kind's table (nodes, leaves: each stores only
  // the fields its collection reads) until its answer; each collection sees a job stream whose head is the job its
  // beat's tag names, valid while a job of its kind is outstanding (at least 2 entries: a 1-bit tag addresses them)
  val jobTables = if (p.respTagged) Seq(false, true).map { leaf =>
    val t = Mem(math.max(2, requesters), new Job).suggestName(if (leaf) "jobs_leaf" else "jobs_node")
    when(memReq.fire && reqIsLeaf === leaf.B) { t.write(issue.bits.chosen, newJob) }
    t
  } else Nil
  def tableJobs(beats: DecoupledIO[FetchBeat], leaf: Boolean): DecoupledIO[Job] = {
    val jobs = Wire(Decoupled(new Job))
    val outstanding = RegInit(0.U(log2Ceil(requesters + 1).W))
    outstanding := outstanding + (memReq.fire && reqIsLeaf === leaf.B).asUInt - jobs.fire.asUInt
    jobs.valid := outstanding =/= 0.U
    jobs.bits := jobTables(if (leaf) 1 else 0)(beats.bits.tag.get)
    jobs
  }

  /** Collection: the beats of `beats`, in the order of the jobs of `jobs`, become whole nodes (to the box
    * pipe) or whole primitives (to the triangle pipe). `only` = Some(leaf) when every job is of one kind
    * (RESP_ORDER=path): the other kind's logic is then constant and elaborates away.
    */
  def collect(jobs: DecoupledIO[Job], beats: DecoupledIO[FetchBeat], only: Option[Boolean]): (Valid[BoxJob], Valid[TriJob]) = {
    val job = jobs.bits
    val isLeaf = only.fold(job.isLeaf)(_.B)
    val buf = Reg(Vec(math.max(nodeWords, primWords), UInt(32.W)))
    val beatIdx = RegInit(0.U(8.W))
    // the same count one-hot: a word's select is one bit of it (no compare between the register and the words,
    // which go on into the box pipe's first stage in the same cycle)
    val unitBeatsMax = only.fold(buf.length)(leaf => if (leaf) primWords else nodeWords) / beatWords
    val beatHot = RegInit(1.U(unitBeatsMax.W))
    // a unit (node or primitive) is bad if any of its beats came with a memory error
    val errAcc = RegInit(false.B)
    val unitErr = errAcc || beats.bits.err
    val primIdx = RegInit(0.U(8.W))
    beats.ready := jobs.valid
    val unitBeats = Mux(isLeaf, (primWords / beatWords).U, (nodeWords / beatWords).U)
    // PRIM_FORMAT=packed: a leaf's beats go to the LeafAssembler (its records span beats), not to this collection
    val packedLeaf = p.primPacked.B && isLeaf
    val beatFire = beats.fire && !packedLeaf
    val unitDone = beatFire && beatIdx === unitBeats - 1.U
    val jobDone = unitDone && (!isLeaf || primIdx === job.lastPrim)
    // the words of the unit as they will be once this beat is stored (the last beat goes straight through)
    val words = Wire(Vec(buf.length, UInt(32.W)))
    for (w <- buf.indices) {
      val thisBeat = if (w / beatWords < unitBeatsMax) beatHot(w / beatWords) else false.B
      words(w) := Mux(thisBeat, beats.bits.data((w % beatWords) * 32 + 31, (w % beatWords) * 32), buf(w))
    }
    when(beatFire) {
      buf := words
      errAcc := unitErr && !unitDone
      beatIdx := Mux(unitDone, 0.U, beatIdx + 1.U)
      beatHot := Mux(unitDone, 1.U, (beatHot << 1)(unitBeatsMax - 1, 0))
      when(unitDone && isLeaf) { primIdx := Mux(jobDone, 0.U, primIdx + 1.U) }
    }
    jobs.ready := jobDone
    // a response's `last` must agree with the size of the job this collection counted (RESP_ORDER=path: nothing else
    // reads it; in request order the MC's mux does, and the IU's register slice on the responses carries it here)
    when(beatFire) { assert(beats.bits.last === jobDone, "IntersectionUnit: a response's last beat disagrees with its job's size") }

    val node = Wire(new NodeJob(p.nodes))
    node.tu := job.tu
    node.ray := rayOf(job)
    node.tmax := job.tmax
    node.words := VecInit(words.take(nodeWords))
    node.err := unitErr
    val box = NodeDecode.toBoxJob(p.nodes, unitDone && !isLeaf, node)
    val tri = Wire(Valid(new TriJob(p.pipes)))
    tri.valid := unitDone && isLeaf
    tri.bits.tu := job.tu
    tri.bits.ray := rayOf(job)
    tri.bits.tmax := job.tmax
    tri.bits.words := VecInit(words.take(10))
    tri.bits.last := jobDone
    tri.bits.err := unitErr
    if (p.primPacked && !only.contains(false)) {
      val asm = Module(new LeafAssembler(p.leaves, beatBits))
      asm.io.in.valid := beats.valid && jobs.valid && isLeaf
      asm.io.in.bits.beat := beats.bits
      asm.io.in.bits.lastPrim := job.lastPrim
      asm.io.in.bits.ctx.tu := job.tu
      asm.io.in.bits.ctx.ray := rayOf(job)
      asm.io.in.bits.ctx.tmax := job.tmax
      beats.ready := jobs.valid && (!isLeaf || asm.io.in.ready)
      jobs.ready := Mux(isLeaf, asm.io.leafTaken, jobDone)
      if (only.isDefined) when(beats.fire && isLeaf) { assert(beats.bits.last === asm.io.leafTaken, "IntersectionUnit: a leaf's last beat disagrees with its size") }
      tri.valid := asm.io.out.valid
      tri.bits := asm.io.out.bits
    }
    (box, tri)
  }

  // with PIPELINE the MC's responses pass a register slice: a job queue's valid (the beats' ready) and the collection's
  // wide load enables no longer reach into the MC's response mux and its caches' output queues in one cycle (the
  // smallest platform's routed critical path on ECP5; a cycle more per access: PlatformParams.accessSliceCycles)
  val resp = rtaccel.arb.Slice(p, io.mem.resp)
  lazy val primResp = rtaccel.arb.Slice(p, io.mem.primResp.get)
  val (boxJob, triJob0) =
    if (!p.respByPath) collect(jobQs(0)._2, resp, None)
    else if (p.respTagged) (collect(tableJobs(resp, leaf = false), resp, Some(false))._1,
      collect(tableJobs(primResp, leaf = true), primResp, Some(true))._2)
    else (collect(jobQs(0)._2, resp, Some(false))._1, collect(jobQs(1)._2, primResp, Some(true))._2)

  // with PIPELINE a node's and a primitive's job pass a register into their pipe: the MC's response mux and the
  // words' assembly then end there, and the pipes' first stages start from it (a cycle more per access, which the
  // throughput model adds: PlatformParams.accessSliceCycles)
  val boxIn = rtaccel.arb.Slice.late(p, boxJob)
  val triJob = rtaccel.arb.Slice.late(p, triJob0)
  val boxPipe = Module(new BoxPipe(p.pipes))
  boxPipe.io.in := boxIn
  // TRI_TEST: both pipes take the same job and give the same result, at their own latencies
  val (triIn, triOut, triLatency) = p.triTest match {
    case TriTest.Mt => val t = Module(new TriPipe(p.pipes)); (t.io.in, t.io.out, t.latency)
    case TriTest.Watertight => val t = Module(new WatertightPipe(p.pipes)); (t.io.in, t.io.out, t.latency)
  }
  triIn := triJob
  /** The pipes' latencies, which the board top reports in its register map. */
  @public val boxLatency: Int = boxPipe.latency
  @public val triPipeLatency: Int = triLatency
  io.box := boxPipe.io.out
  io.tri := triOut
}
