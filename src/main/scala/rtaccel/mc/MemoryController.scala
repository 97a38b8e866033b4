package rtaccel.mc

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams

/** A fetch request: a child reference word exactly as stored in the memory image (RefCodec layout).
  * (Named childRef because `ref` is a reserved member of chisel3.Data.)
  * RESP_ORDER=tagged: `tag` (tagBits > 0) names the requester; every beat of the answer carries it back.
  */
class FetchReq(tagBits: Int = 0) extends Bundle {
  val childRef = UInt(32.W)
  val tag = if (tagBits > 0) Some(UInt(tagBits.W)) else None
}

/** One bus-width beat of fetched data; `last` marks the final beat of its request; `err` = the memory
  * answered it with an error (AXI RRESP other than OKAY, after MEM_RETRIES re-reads): its data must not be used. A
  * cache stores the error bit with the beat for the lookups queued behind that fill, and marks the line so that a
  * later lookup reads it again (rtaccel.cache.hw.CachePath, PoisonMarks).
  * RESP_ORDER=tagged: `tag` (tagBits > 0) is the tag of the request the beat answers.
  */
class FetchBeat(dataBits: Int, tagBits: Int = 0) extends Bundle {
  val data = UInt(dataBits.W)
  val last = Bool()
  val err = Bool()
  val tag = if (tagBits > 0) Some(UInt(tagBits.W)) else None
}

/** A memory read of `beats` consecutive full-width beats from byte address `addr` (beat aligned). */
class MemReq(addrBits: Int, beatsBits: Int) extends Bundle {
  val addr = UInt(addrBits.W)
  val beats = UInt(beatsBits.W)
}

/** A request as a path sees it: the DRAM read plus what a cache needs to place it. `line` is the node id
  * (node path) or the leaf's first primitive slot (primitive path); `level` is the node's tree level from its
  * reference, saturated to the level code (hw.levelCodeBits, 4 as in the paper's Section 7.2 encoding; 0 for
  * leaves and when the reference format has no level field).
  */
class PathReq(addrBits: Int, beatsBits: Int, levelBits: Int, tagBits: Int = 0) extends MemReq(addrBits, beatsBits) {
  val line = UInt(32.W)
  val level = UInt(levelBits.W)
  val tag = if (tagBits > 0) Some(UInt(tagBits.W)) else None // RESP_ORDER=tagged: the requester
}

/** Hit/miss counters a path reports (all zero for the pass-through). */
class PathStats(bits: Int) extends Bundle {
  val hits = UInt(bits.W)
  val misses = UInt(bits.W)
  val bypasses = UInt(bits.W)
}

/** What the MC counts (HwLimits.mcCounterBits each, never cleared by traffic): requests by kind, primitives and
  * bytes requested, R beats received (DRAM busy) and those with an error, each path's cache statistics, and the
  * re-reads of MEM_RETRIES.
  */
class McCounters(val bits: Int) extends Bundle {
  val nodeRequests = UInt(bits.W)
  val leafRequests = UInt(bits.W)
  val primsRequested = UInt(bits.W)
  val bytesRequested = UInt(bits.W)
  val busyBeats = UInt(bits.W)
  val readErrors = UInt(bits.W)
  val nodeCache = new PathStats(bits)
  val primCache = new PathStats(bits)
  val retries = UInt(bits.W) // MEM_RETRIES: reads issued again after an SLVERR
}

object McCounters {
  /** The field-by-field sum of several MCs' counters (IUS > 1: one MC per IU cluster); every field has `bits`. */
  def sum(cs: Seq[McCounters]): McCounters = if (cs.length == 1) cs.head else {
    val w = cs.head.bits
    val k = (new McCounters(w)).getWidth / w
    val vs = cs.map(_.asTypeOf(Vec(k, UInt(w.W))))
    VecInit(Seq.tabulate(k)(i => vs.map(_(i)).reduce(_ + _))).asTypeOf(new McCounters(w))
  }
}

/** Sizes shared by the MC and its paths. extraTagBits: tag bits above the TU's index (a node bank's MC: the
  * requesting IU cluster, rtaccel.cache.hw.NodeBanks).
  */
final case class McGeometry(p: PlatformParams, axi: AxiParams, extraTagBits: Int = 0) {
  require(axi.beatBytes <= p.primStrideBytes && axi.beatBytes <= p.nodeSlotBytes,
    s"an AXI beat (${axi.beatBytes} B) must not exceed a node (${p.nodeSlotBytes} B) or a primitive slot (${p.primStrideBytes} B); narrow the bus")
  val nodeBeats: Int = p.nodeSlotBytes / axi.beatBytes
  val primBeats: Int = p.primStrideBytes / axi.beatBytes
  /** leaf addresses and burst lengths of the primitive format */
  val leaf: LeafFetch = LeafFetch(p, axi.beatBytes)
  val maxBeats: Int = math.max(nodeBeats, leaf.maxBeats)
  val beatsBits: Int = log2Ceil(maxBeats + 1)
  /** RESP_ORDER=tagged: bits of the requester tag every request and response beat carries (0: untagged) */
  val tagBits: Int = p.respTagBits + extraTagBits
  require(extraTagBits == 0 || p.respTagBits > 0, "extra tag bits need RESP_ORDER=tagged")
  def memReq = new MemReq(axi.addrBits, beatsBits)
  def pathReq = new PathReq(axi.addrBits, beatsBits, p.hw.levelCodeBits, tagBits)
  /** a beat towards the requester (tagged with RESP_ORDER=tagged) */
  def respBeat = new FetchBeat(axi.dataBits, tagBits)
}

/** The interface a node or primitive cache implements to plug into the MC.
  * in:      requests of this path, in global order (addr, beats).
  * memReq:  reads this path wants from DRAM (a miss / fill); memResp: their beats, in memReq order,
  *          with `last` on the final beat of each memReq.
  * out:     the beats answering `in`, in `in` order, `last` on each request's final beat; RESP_ORDER=tagged: in
  *          any order, each request's beats back to back and tagged with its `tag`.
  * A path may serve requests without DRAM (hits) and may issue its DRAM reads late, so DRAM order can differ
  * from request order across the two paths. The MC then needs respBufferBeats > 0 (see MemoryController),
  * which guarantees that every R beat has room to land and the shared in-order R channel never blocks.
  */
class FetchPathIO(g: McGeometry) extends Bundle {
  val in = Flipped(Decoupled(g.pathReq))
  val primBase = Input(UInt(g.axi.addrBits.W))
  val maxLevel = Input(UInt(g.p.hw.levelCodeBits.W))
  val clearStats = Input(Bool()) // the host's CLEAR_COUNTERS
  val stats = Output(new PathStats(g.p.hw.mcCounterBits))
  val memReq = Decoupled(g.memReq)
  val memResp = Flipped(Decoupled(new FetchBeat(g.axi.dataBits)))
  val out = Decoupled(g.respBeat)
}

/** What the MC instantiates per path; a cache extends this and is passed to the MC as a factory. */
abstract class FetchPathModule(val g: McGeometry) extends Module {
  val io = IO(new FetchPathIO(g))
}

/** The pass-through: every request goes to DRAM, every beat straight back (DRAM answers in order, so with
  * RESP_ORDER=tagged a FIFO of the requests' tags, as deep as the MC's reads in flight, tags the beats).
  */
class FetchPath(g: McGeometry) extends FetchPathModule(g) {
  private val tags = if (g.tagBits > 0) Some(Module(new Queue(UInt(g.tagBits.W), g.p.hw.mcOutstanding))) else None
  private val tagReady = tags.fold(true.B)(_.io.enq.ready)
  io.memReq.valid := io.in.valid && tagReady
  io.memReq.bits.addr := io.in.bits.addr
  io.memReq.bits.beats := io.in.bits.beats
  io.in.ready := io.memReq.ready && tagReady
  io.out.valid := io.memResp.valid
  io.out.bits.data := io.memResp.bits.data
  io.out.bits.last := io.memResp.bits.last
  io.out.bits.err := io.memResp.bits.err
  io.memResp.ready := io.out.ready
  for (t <- tags) {
    t.io.enq.valid := io.in.fire
    t.io.enq.bits := io.in.bits.tag.get
    io.out.bits.tag.get := t.io.deq.bits
    t.io.deq.ready := io.memResp.fire && io.memResp.bits.last
    when(io.memResp.valid) { assert(t.io.deq.valid, "FetchPath: a DRAM beat with no tagged request outstanding") }
  }
  io.stats := 0.U.asTypeOf(io.stats)
}

object FetchPath {
  val Node = 0
  val Prim = 1
  /** The default factory: pass-through for both paths. */
  val passThrough: (McGeometry, Int) => FetchPathModule = (g, _) => new FetchPath(g)
}

/** Splits reads into AXI4 INCR bursts of at most 256 beats that never cross a 4 KB boundary
  * (AXI4 forbids it; node and primitive fetches only hit this when a leaf straddles a 4 KB page).
  * One burst per cycle; the next read is accepted in the cycle the previous read's final burst issues.
  */
class BurstSplitter(g: McGeometry, id: Int = 0) extends Module {
  val axi = g.axi
  val io = IO(new Bundle {
    val in = Flipped(Decoupled(g.memReq))
    val ar = Decoupled(new AxiAr(axi))
  })
  val beatShift = log2Ceil(axi.beatBytes)
  val pageBeats = 4096 / axi.beatBytes
  val busy = RegInit(false.B)
  val addr = Reg(UInt(axi.addrBits.W))
  val left = Reg(UInt(g.beatsBits.W))

  val beatInPage = if (pageBeats > 1) (addr >> beatShift)(log2Ceil(pageBeats) - 1, 0) else 0.U
  val toPageEnd = pageBeats.U(log2Ceil(pageBeats + 1).W) - beatInPage
  val maxBurst = math.min(256, pageBeats)
  val lim = Mux(toPageEnd < maxBurst.U, toPageEnd, maxBurst.U)
  val n = Mux(left < lim, left, lim) // beats of this burst (>= 1 while busy)
  val finalBurst = left <= lim

  io.ar.valid := busy
  io.ar.bits.id := id.U
  io.ar.bits.addr := addr
  io.ar.bits.len := (n - 1.U).pad(8)(7, 0)
  io.ar.bits.size := beatShift.U
  io.ar.bits.burst := 1.U
  io.in.ready := !busy || (io.ar.fire && finalBurst)

  when(io.ar.fire) {
    addr := (addr + (n << beatShift))(axi.addrBits - 1, 0)
    left := left - n
    when(finalBurst) { busy := false.B }
  }
  when(io.in.fire) {
    busy := true.B
    addr := Cat(io.in.bits.addr >> beatShift, 0.U(beatShift.W))
    left := io.in.bits.beats
  }
  when(io.in.fire) { assert(io.in.bits.beats =/= 0.U, "BurstSplitter: a read of zero beats") }
}

/** The memory controller (paper Section 4): turns child references into DRAM bursts and returns the beats
  * in request order.
  *
  * Decode (RefCodec layout, widths from p.refs): MSB of the refBits-wide ref = leaf flag.
  *   node ref: id = low nodeIdBits -> nodeStrideBytes at byte id * nodeStrideBytes (nodes start at 0)
  *   leaf ref: count = field + 1, first = low primIndexBits -> count * 64 B at primBase + first * 64
  *             (PRIM_FORMAT=packed: leafBytes(count) at primBase + first * leafRowBytes, LeafFetch)
  * Requests are steered to the node path or the primitive path (FetchPath, the cache plug-in point); an
  * order FIFO records the path of every accepted request and the response mux follows it, so responses
  * leave in global request order whatever the paths do. The paths' DRAM reads share one AXI AR port through
  * an arbiter; a second FIFO records which path each DRAM read belongs to and routes R beats back
  * (in-order AXI, one ID). Backpressure on io.resp reaches R.ready combinationally.
  * RESP_ORDER=path (p.respByPath): no order FIFO; io.resp carries the node path's beats and io.primResp the
  * primitive path's, each in its own request order, so neither stream waits on the other's misses.
  * Up to maxOutstanding requests may be in flight (RESP_ORDER=request). pathFactory(g, FetchPath.Node | FetchPath.Prim) builds the
  * two paths (default: pass-through); a cache is plugged in by passing a factory that returns it.
  *
  * respBufferBeats = 0 (default, enough for the pass-through paths, whose DRAM order is the request order):
  * R beats go straight to their path and io.resp backpressure reaches R.ready combinationally.
  * respBufferBeats > 0 (needed once a path can reorder DRAM traffic relative to the other, e.g. a cache):
  * each path gets a response buffer of that many beats; a path's DRAM read is granted only if its buffer has
  * room for all its beats (credits), so R never waits on the order mux and cannot deadlock; backpressure then
  * stops AR issue instead of holding R.
  * MEM_RETRIES = n > 0 (needs respBufferBeats > 0): a read whose beats include an SLVERR is read again, up to n times,
  * before its beats go on marked as errors. Each read's beats land in the slots its grant reserved (ReadBuffer), so a
  * re-read, issued after later reads, still reaches its path before them. Beats pass on as they land: the beats before
  * a read's first failed one go at once, and its re-read delivers only from that beat on (dropping what was already
  * delivered), so a read that needs no re-read waits for nothing. A DECERR (no memory at that address) is not re-read.
  * Re-reads go to DRAM before any new read (the arbiter's first choice): while one waits no new read is issued, so
  * the queue holds at most the reads then in the memory-order FIFO (mcOutstanding), the issue slice's two and the one
  * in its input register: it has mcOutstanding + 4 entries and cannot fill (an assertion checks it).
  * A node bank's MC (NODE_BANKS, rtaccel.cache.hw.NodeBanks): extraTagBits widen the tag by the requesting cluster,
  * and its node path sees line = node id >> nodeLineShift (the id without the bank bits, as a bank indexes its sets).
  */
class MemoryController(p: PlatformParams, axi: AxiParams,
                       pathFactory: (McGeometry, Int) => FetchPathModule = FetchPath.passThrough,
                       respBufferBeats: Int = 0, extraTagBits: Int = 0, nodeLineShift: Int = 0) extends Module {
  val g = McGeometry(p, axi, extraTagBits)
  private val ap = axi
  private val maxOutstanding = p.hw.mcOutstanding
  val io = IO(new Bundle {
    val req = Flipped(Decoupled(new FetchReq(g.tagBits)))
    // RESP_ORDER=request: every response, in request order; RESP_ORDER=path: the node path's responses only
    // (tagged: in any order, each beat with its request's tag)
    val resp = Decoupled(g.respBeat)
    // RESP_ORDER=path: the primitive path's responses, in primitive request order (tagged: in any order)
    val primResp = if (p.respByPath) Some(Decoupled(g.respBeat)) else None
    val primBase = Input(UInt(ap.addrBits.W))
    val maxLevel = Input(UInt(p.hw.levelCodeBits.W)) // MAX_LEVEL register of the level replacement policy
    val clearCounters = Input(Bool()) // zeroes the counters below and every path's cache statistics
    val axi = new AxiReadMaster(ap)
    val counters = Output(new McCounters(p.hw.mcCounterBits))
  })
  val f = p.refs
  // the two streams drain independently, so an R beat for a stream that waits must have room to land
  require(!p.respByPath || respBufferBeats > 0,
    "RESP_ORDER=path drains the node and primitive streams independently; give the MC respBufferBeats > 0")
  require(p.memRetries == 0 || respBufferBeats > 0,
    s"MEM_RETRIES=${p.memRetries} re-reads into the room a read reserved; give the MC respBufferBeats > 0 (PlatformParams.mcResponseBuffers)")
  require(respBufferBeats == 0 || respBufferBeats >= g.maxBeats,
    s"a response buffer of $respBufferBeats beats cannot hold the largest fetch (${g.maxBeats} beats); raise respBufferBeats")
  private val NodePath = FetchPath.Node
  private val PrimPath = FetchPath.Prim

  // ---- decode
  val ref = io.req.bits.childRef
  val isLeaf = ref(f.refBits - 1)
  val nodeId = ref(f.nodeIdBits - 1, 0)
  val first = ref(f.primIndexBits - 1, 0)
  val count: UInt =
    if (f.countBits == 0) 1.U(1.W)
    else ref(f.primIndexBits + f.countBits - 1, f.primIndexBits) +& 1.U
  def toAddr(x: UInt): UInt = x.pad(axi.addrBits)(axi.addrBits - 1, 0)
  val nodeAddr = toAddr(nodeId << log2Ceil(p.nodeSlotBytes))
  val primAddr = toAddr(g.leaf.addr(io.primBase, first))
  // the node's level field, saturated to the level code every cache policy works with
  private val codeBits = p.hw.levelCodeBits; private val maxCode = p.hw.maxLevelCode
  val nodeLevel: UInt =
    if (f.levelBits == 0) 0.U(codeBits.W)
    else { val l = ref(f.nodeIdBits + f.levelBits - 1, f.nodeIdBits); Mux(l > maxCode.U, maxCode.U, l)(codeBits - 1, 0) }

  // ---- paths and dispatch (order FIFO: path of every request in flight)
  // RESP_ORDER=path keeps no order FIFO: each path answers its own requests in order, and what bounds the
  // requests in flight is the requester (the IU's job FIFOs) and each path's own queues
  val paths = Seq.tabulate(2)(i => Module(pathFactory(g, i)))
  val order = if (p.respByPath) None else Some(Module(new Queue(UInt(1.W), maxOutstanding)))
  val orderReady = order.fold(true.B)(_.io.enq.ready)

  val target = Mux(isLeaf, PrimPath.U, NodePath.U)
  val pathReady = Mux(isLeaf, paths(PrimPath).io.in.ready, paths(NodePath).io.in.ready)
  io.req.ready := pathReady && orderReady
  for (o <- order) {
    o.io.enq.valid := io.req.valid && pathReady
    o.io.enq.bits := target
  }
  for ((path, i) <- paths.zipWithIndex) {
    path.io.in.valid := io.req.valid && orderReady && target === i.U
    path.io.in.bits.addr := (if (i == NodePath) nodeAddr else primAddr)
    path.io.in.bits.beats := (if (i == NodePath) g.nodeBeats.U else g.leaf.beats(count))
    path.io.in.bits.line := (if (i == NodePath) nodeId >> nodeLineShift else first).pad(32)
    path.io.in.bits.level := (if (i == NodePath) nodeLevel else 0.U)
    for (t <- path.io.in.bits.tag) t := io.req.bits.tag.get
    path.io.primBase := io.primBase
    path.io.maxLevel := io.maxLevel
    path.io.clearStats := io.clearCounters
  }
  io.counters.nodeCache := paths(NodePath).io.stats
  io.counters.primCache := paths(PrimPath).io.stats

  // ---- DRAM side: arbiter -> burst splitter -> AR; R routed back by the memory-order FIFO
  val arb = Module(new RRArbiter(g.memReq, 2))
  private val buffered = respBufferBeats > 0
  private val retrying = p.memRetries > 0
  private val attemptBits = log2Ceil(p.memRetries + 1)
  /** A read to issue: its path and beats; with response buffers the first slot it reserved; with MEM_RETRIES its
    * address (to read it again), its attempt (0 first) and the beats already delivered (`good`, re-reads skip them).
    */
  class Read extends Bundle {
    val path = UInt(1.W)
    val beats = UInt(g.beatsBits.W)
    val base = if (buffered) Some(UInt(log2Ceil(respBufferBeats).max(1).W)) else None
    val addr = if (retrying) Some(UInt(axi.addrBits.W)) else None
    val attempt = if (retrying) Some(UInt(attemptBits.W)) else None
    val good = if (retrying) Some(UInt(g.beatsBits.W)) else None
  }
  /** A read issued, in the memory-order FIFO: with its last beat's index (beats - 1), which the R side compares and
    * does not subtract. */
  class InFlight extends Read {
    val last = UInt(g.beatsBits.W)
  }
  /** the fields `to` shares with `from` (a Read's, in an InFlight or the other way round) */
  private def copyShared(to: Read, from: Read): Unit = for ((n, d) <- to.elements if from.elements.contains(n)) d := from.elements(n)
  val memOrder = Module(new Queue(new InFlight, maxOutstanding))
  val splitter = Module(new BurstSplitter(g))
  // Each path's DRAM-response sink: straight to the path, or a credit-managed buffer in front of it.
  // with response buffers (DRAM may answer the paths out of request order) and PIPELINE, a path's reads pass a
  // register slice: the arbiter's ready and the credits end there, and a cache path's miss queue is not read into
  // the arbiter
  val bufs = for ((path, i) <- paths.zipWithIndex) yield {
    val req = if (buffered) rtaccel.arb.Slice(p, path.io.memReq) else path.io.memReq
    if (!buffered) {
      arb.io.in(i) <> req
      None
    } else {
      val buf = Module(new ReadBuffer(new FetchBeat(axi.dataBits), respBufferBeats, g.beatsBits))
      val free = RegInit(respBufferBeats.U(log2Ceil(respBufferBeats + 1).W))
      val fits = free >= req.bits.beats
      arb.io.in(i).valid := req.valid && fits
      arb.io.in(i).bits := req.bits
      req.ready := arb.io.in(i).ready && fits
      val taken = Mux(arb.io.in(i).fire, req.bits.beats, 0.U)
      free := free - taken + buf.io.deq.fire.asUInt
      buf.io.alloc := arb.io.in(i).fire
      buf.io.allocBeats := req.bits.beats
      // a path's ready for DRAM beats comes from its ticket queue's head (a cache) or the response order (a pass-
      // through path): with PIPELINE it ends at a register slice, not in the buffer's pointers, credits and RAM
      // address (one cycle more on every DRAM read)
      path.io.memResp <> rtaccel.arb.Slice(p, buf.io.deq)
      Some(buf)
    }
  }
  // MEM_RETRIES: reads to issue again, ahead of every new read
  val retryQ = if (retrying) Some(Module(new Queue(new Read, maxOutstanding + 4))) else None
  // with PIPELINE the arbiter's choice passes a register slice (arb.Slice) before the splitter and the memory-order
  // FIFO: their readies end there. After the arbiter, so DRAM order stays the order it chose (one slice, not one
  // per path: two would let a later request overtake an earlier one, which the in-order response mux cannot wait out)
  val chosen = Wire(Decoupled(new Bundle { val req = g.memReq; val read = new Read }))
  val fresh = Wire(new Read)
  fresh.path := arb.io.chosen; fresh.beats := arb.io.out.bits.beats
  for (b <- fresh.base) b := VecInit(bufs.map(_.get.io.base))(arb.io.chosen)
  for (a <- fresh.addr) a := arb.io.out.bits.addr
  for (a <- fresh.attempt) a := 0.U
  for (gd <- fresh.good) gd := 0.U
  val again = retryQ.fold(false.B)(_.io.deq.valid)
  chosen.valid := arb.io.out.valid || again
  chosen.bits.read := fresh
  chosen.bits.req := arb.io.out.bits
  arb.io.out.ready := chosen.ready && !again
  for (q <- retryQ) {
    q.io.deq.ready := chosen.ready
    when(again) { chosen.bits.read := q.io.deq.bits; chosen.bits.req.addr := q.io.deq.bits.addr.get; chosen.bits.req.beats := q.io.deq.bits.beats }
  }
  val issue = rtaccel.arb.Slice(p, chosen)
  splitter.io.in.valid := issue.valid && memOrder.io.enq.ready
  splitter.io.in.bits := issue.bits.req
  issue.ready := splitter.io.in.ready && memOrder.io.enq.ready
  memOrder.io.enq.valid := issue.valid && splitter.io.in.ready
  copyShared(memOrder.io.enq.bits, issue.bits.read)
  // the last beat's index from the slice's register: subtracted before it, after the credit compare and the
  // arbiter's choice, it made the MC's routed critical path on ECP5 (16 elements into the slice)
  memOrder.io.enq.bits.last := issue.bits.req.beats - 1.U
  // with PIPELINE the AR channel leaves a register slice: the interconnect's ready ran through the splitter and the
  // issue logic (7 LUT levels on xc5v from the AXI read mux of IUS > 1; PlatformParams.passSliceCycles counts it)
  io.axi.ar <> rtaccel.arb.Slice(p, splitter.io.ar)

  val rBeat = RegInit(0.U(g.beatsBits.W))
  val rHead = memOrder.io.deq.bits
  val rLast = rBeat === rHead.last
  val rErr = io.axi.r.bits.resp =/= 0.U // SLVERR or DECERR
  // MEM_RETRIES: an SLVERR before the last attempt fails this attempt; its beats from the first failed one on are
  // dropped and the read goes to the re-read queue (beats before `good` were delivered by an earlier attempt)
  val retry = retryQ.map { q =>
    val failed = RegInit(false.B); val failAt = Reg(UInt(g.beatsBits.W))
    val fails = io.axi.r.bits.resp === 2.U && rHead.attempt.get =/= p.memRetries.U
    // whether this beat is at or past `good`, from a register but at a read's first beat: equalities only, the
    // memory-order FIFO's read reaches no carry chain
    val reachedReg = RegInit(false.B)
    val reached = Mux(rBeat === 0.U, rHead.good.get === 0.U, reachedReg)
    when(io.axi.r.fire) { reachedReg := !rLast && (reached || rBeat + 1.U === rHead.good.get) }
    val isNew = reached && !failed
    val failsNow = isNew && fails
    when(io.axi.r.fire) {
      when(failsNow) { failAt := rBeat }
      failed := Mux(rLast, false.B, failed || failsNow)
    }
    val push = Wire(Valid(new Read))
    push.valid := io.axi.r.fire && rLast && (failed || failsNow)
    copyShared(push.bits, rHead)
    push.bits.attempt.get := rHead.attempt.get + 1.U
    push.bits.good.get := Mux(failed, failAt, rBeat)
    // through a register: the memory-order FIFO's read (its pointer, its RAM) does not run into the re-read queue's
    // RAM in the same cycle (the MC's routed critical path on ECP5). The queue never refuses it (see above)
    val pushed = RegNext(push, 0.U.asTypeOf(push))
    q.io.enq.valid := pushed.valid
    q.io.enq.bits := pushed.bits
    when(pushed.valid) { assert(q.io.enq.ready, "MemoryController: the re-read queue filled") }
    isNew && !fails
  }
  val keep = retry.getOrElse(true.B)
  val rPathReady = bufs.head match {
    case None => VecInit(paths.map(_.io.memResp.ready))(rHead.path)
    case Some(_) => true.B // a beat always has its slot (credits), and a failed read a place in the re-read queue
  }
  io.axi.r.ready := memOrder.io.deq.valid && rPathReady
  for (((path, b), i) <- paths.zip(bufs).zipWithIndex) {
    val hit = io.axi.r.valid && memOrder.io.deq.valid && rHead.path === i.U
    val beat = Wire(new FetchBeat(axi.dataBits))
    beat.data := io.axi.r.bits.data
    beat.last := rLast
    beat.err := rErr
    b match {
      case None =>
        path.io.memResp.valid := hit
        path.io.memResp.bits := beat
      case Some(buf) =>
        // the R beat, routed by the memory-order FIFO's head, reaches the buffer's RAM from a register with PIPELINE
        // (the credits already hold room for it)
        val w = Wire(Valid(chiselTypeOf(buf.io.write.bits)))
        w.valid := hit && io.axi.r.ready && keep
        w.bits.slot := buf.wrap(rHead.base.get, rBeat)
        w.bits.beat := beat
        buf.io.write := rtaccel.arb.Slice.late(p, w)
    }
  }
  memOrder.io.deq.ready := io.axi.r.fire && rLast
  when(io.axi.r.fire) { rBeat := Mux(rLast, 0.U, rBeat + 1.U) }

  // ---- responses: one stream in global request order (the order FIFO picks the path), or one per path
  order match {
    case Some(o) =>
      val sel = o.io.deq.bits
      val outs = VecInit(paths.map(_.io.out.bits))
      io.resp.valid := o.io.deq.valid && VecInit(paths.map(_.io.out.valid))(sel)
      io.resp.bits := outs(sel)
      for ((path, i) <- paths.zipWithIndex) path.io.out.ready := io.resp.ready && o.io.deq.valid && sel === i.U
      o.io.deq.ready := io.resp.fire && io.resp.bits.last
    case None =>
      io.resp <> paths(NodePath).io.out
      io.primResp.get <> paths(PrimPath).io.out
  }

  // ---- counters
  def counter(inc: UInt, en: Bool): UInt = {
    val c = RegInit(0.U(p.hw.mcCounterBits.W))
    when(io.clearCounters) { c := 0.U }.elsewhen(en) { c := c + inc }
    c
  }
  val reqFire = io.req.fire
  io.counters.nodeRequests := counter(1.U, reqFire && !isLeaf)
  io.counters.leafRequests := counter(1.U, reqFire && isLeaf)
  // with PIPELINE a request's primitive and byte counts are registered before they are added (a cycle late): the
  // count field's +1, the packed leaf's beats table and the counter's 40-bit add in one cycle were 7 LUT levels on
  // xc5v, from the request's reference (the LX330T configuration in docs/roofline.md)
  private def lateCounter(inc: UInt, en: Bool): UInt = counter(rtaccel.arb.Slice.late(p, inc), rtaccel.arb.Slice.late(p, en))
  io.counters.primsRequested := lateCounter(count, reqFire && isLeaf)
  io.counters.bytesRequested := lateCounter(Mux(isLeaf, g.leaf.bytes(count), p.nodeSlotBytes.U), reqFire)
  io.counters.busyBeats := counter(1.U, io.axi.r.fire)
  io.counters.readErrors := counter(1.U, io.axi.r.fire && rErr)
  io.counters.retries := counter(1.U, retryQ.fold(false.B)(_.io.enq.fire))

  when(io.axi.r.valid) { assert(memOrder.io.deq.valid, "MemoryController: an R beat with no read outstanding") }
}
