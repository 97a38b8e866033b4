package rtaccel.cache.hw

import chisel3._
import chisel3.util._
import rtaccel.cache.policy.Policies
import rtaccel.config.{CacheParams, CachePolicy}
import rtaccel.mc.{FetchBeat, FetchPath, FetchPathModule, McGeometry, PathReq}

/** Geometry of one cache in front of a path. A line holds one request: a node, or a leaf of up to
  * `entriesPerLine` (= MPPL) primitives: CacheParams.lines, as in the trace model.
  */
final case class CacheGeometry(c: CacheParams, entriesPerLine: Int, lineBeats: Int, strideBytes: Int) {
  require(c.entries > 0, "a cache path needs entries > 0")
  val lines: Int = c.lines(entriesPerLine)
  require(Integer.bitCount(lines) == 1, s"cache lines ($lines) must be a power of two")
  require(lines % c.ways == 0, s"cache ways (${c.ways}) must divide its lines ($lines)")
  val beatBits: Int = log2Ceil(lineBeats)
  /** hybrid: the complementary LRP cache beside the direct-mapped array (same sizes as CacheModel) */
  val sideLines: Int = c.sideLines(lines)
  val sideWays: Int = c.sideWays(lines)
  val dataLines: Int = lines + sideLines
}

/** A node or primitive cache as an MC fetch path (paper Sections 6-8). Policies dm, lru, plru, lrp (set-
  * associative, TagArray), bf (static buffer of lines 0..lines-1, preloaded from DRAM before the first request
  * is served, never replaced) and hybrid (direct-mapped LRP array + a small LRU/LRP side array).
  *
  * Tags run ahead of data: the tag arrays are looked up and updated in request order exactly as the trace model
  * does (one request every two cycles: read the set, decide and write; TAG_FORWARD=1: one per cycle, the next
  * request's read overlapping the decision, whose write the write-first tag RAM forwards), so hit and miss counts equal the model's
  * on the same order. Each lookup leaves a ticket (hit, fill, data line) in an in-order queue; misses send their
  * DRAM read at once. The data stage serves tickets strictly in order: a miss passes its DRAM beats to the output
  * and, if it allocated, writes them into the data RAM; a hit reads its line from the data RAM. Because data is
  * written and read only in ticket order, a hit always sees the line of the latest earlier fill, even when that
  * fill's DRAM data arrived after the hit was looked up (no stale or wrong data, whatever the latency).
  *
  * RESP_ORDER=tagged (hits under misses): the tag stage is the same, so the counts still equal the model's. A hit
  * whose data line no ticket still has to fill is clean: it goes to a hit queue of its own, read from the data RAM
  * as soon as the RAM's read port is free, and answered beside the misses, whatever DRAM does. Every other lookup
  * (a miss, or a hit on a line an older miss is still filling) keeps the in-order ticket queue above. Two hazards,
  * both checked over every held entry (ScanQueue):
  *  - read after write: a hit on a line with a fill still in the ticket queue is not clean (it reads in order, after
  *    the fill, as before);
  *  - write after read: a fill takes its first DRAM beat only when no queued clean hit reads its data line. No
  *    younger clean hit can ask for that line meanwhile (its tag now names the filling line: not clean), so once
  *    the fill starts it runs to its end.
  * The answers leave through two output queues (clean hits, tickets), merged a whole answer at a time and
  * alternately when both wait, so neither starves the other.
  */
class CachePath(g0: McGeometry, val cg: CacheGeometry, forwardWrites: Boolean = true) extends FetchPathModule(g0) {
  // forwardWrites = false with TAG_FORWARD=1 only in the formal checks: one lookup per cycle on read-first tag RAMs
  // (no forwarding: a lookup sees the set before the decision just taken), the mutant their proofs must refute
  private val hw = g0.p.hw
  private val tickets = hw.cacheTickets
  private val c = cg.c
  private val dataBits = g.axi.dataBits
  private val isBf = c.policy == CachePolicy.Bf
  private val isHybrid = c.policy == CachePolicy.Hybrid
  private val lineBits = log2Ceil(cg.dataLines)
  private val tagged = g.tagBits > 0 // RESP_ORDER=tagged: hits under misses
  /** PIPELINE's registers (g0.p.cacheSliceCycles, 0 or 1): between a lookup's decision and the queues it enters
    * (stage 2), and in front of the data RAM.
    */
  private val slice = if (g0.p.cacheSliceCycles > 0) 1 else 0

  class Ticket extends Bundle {
    val hit = Bool()
    val fill = Bool()     // write the DRAM beats into the data RAM
    val silent = Bool()   // preload: fill only, nothing to output
    val line = UInt(math.max(1, lineBits).W)
    val beats = UInt(g.beatsBits.W)
    val tag = if (tagged) Some(UInt(g.tagBits.W)) else None
  }
  // in-order tickets; RESP_ORDER=tagged: a ScanQueue, whose held fills the clean-hit check sees (instance name
  // ticketQ either way)
  val ticketScan = if (tagged) Some(Module(new ScanQueue(new Ticket, tickets)).suggestName("ticketQ")) else None
  private val ticketFifo = if (tagged) None else Some(Module(new Queue(new Ticket, tickets)).suggestName("ticketQ"))
  private def ticketQ: QueueIO[Ticket] = ticketScan.fold(ticketFifo.get.io)(_.io)
  /** the tickets the data stage serves. With PIPELINE the head ticket comes from a register slice of two entries
    * (arb.RegSlice), so it comes from flip-flops, not the queue's storage: in order its LUT RAM (read asynchronously
    * into the output queue's write: the MC's routed critical path on ECP5), tagged a 32:1 selection of the
    * ScanQueue's slots before the fill check (10 LUT levels on xc5v, the deepest path of a tagged platform); and the
    * queue's ready is the slice's skid bit, not the end of a beat's completion (the beat counter's compare, the
    * DRAM beat's handshake and the head's load ran into the queue's pointers: 8 levels). In order a hit waits a cycle
    * more (PlatformParams.cacheSliceCycles); two tickets more are held. Tagged, the clean-hit check scans the slice
    * too (`heldTickets`), so no held fill is hidden from it.
    */
  private val headStage: Option[rtaccel.arb.RegSlice[Ticket]] = Option.when(slice > 0)(Module(new rtaccel.arb.RegSlice(new Ticket)))
  private val ticketOut: DecoupledIO[Ticket] = headStage.fold(ticketQ.deq) { h => h.io.enq <> ticketQ.deq; h.io.deq }
  /** RESP_ORDER=tagged: every ticket the data stage has not finished, the queue's and the head slice's */
  private def heldTickets(t: ScanQueue[Ticket]): Seq[Valid[Ticket]] = t.io.held ++ headStage.toSeq.flatMap(_.io.held)
  val missQ = Module(new Queue(g.memReq, hw.cacheMissQueue))
  io.memReq <> missQ.io.deq

  val hits = RegInit(0.U(hw.mcCounterBits.W)); val misses = RegInit(0.U(hw.mcCounterBits.W)); val bypasses = RegInit(0.U(hw.mcCounterBits.W))
  io.stats.hits := hits; io.stats.misses := misses; io.stats.bypasses := bypasses

  // ---------------------------------------------------------------- lookup: stage 0 reads, stage 1 decides
  // (PIPELINE: stage 2 holds the decision a cycle before it enters the queues)
  val s1 = Reg(g.pathReq)
  val s1Valid = RegInit(false.B)
  val ready = WireDefault(true.B) // false while the arrays are cleared or the static buffer is preloaded

  val hit = Wire(Bool()); val fill = Wire(Bool()); val dataLine = Wire(UInt(math.max(1, lineBits).W))
  // the lookup hit a poisoned line (see `poison` below): it refetches, a miss that fills the same data line
  val forced = WireDefault(false.B)
  // RESP_ORDER=tagged: a hit is clean when no held ticket still fills its data line; it then waits in the hit
  // queue, not behind the tickets
  val hitQ = if (tagged) Some(Module(new ScanQueue(new Ticket, hw.cacheHitQueue))) else None
  // a decision enters the queues when every queue it may enter has room, judged without the decision: the tag
  // RAM's read data then reaches no enable, no RAM address and no ready, only data (a hit may wait for room in the
  // miss queue it does not use; the order of lookups, and so every count, is unchanged)
  val roomAll = ticketQ.enq.ready && missQ.io.enq.ready && hitQ.fold(true.B)(_.io.enq.ready)
  // PIPELINE: stage 2 takes a decision when it is empty or its own enters the queues this cycle; the tag RAM's read
  // data then reaches stage 2's registers (and the tag RAM's write data) only, not the queues across the unit
  val s2Valid = RegInit(false.B)
  val s1Go = Wire(Bool())
  val s1Fire = s1Valid && s1Go
  when(s1Fire) { s1Valid := false.B }
  /** a decision entering the queues (`eFire`): stage 1's, or stage 2's with PIPELINE */
  val eFire = if (slice == 0) s1Fire else s2Valid && roomAll
  private def entering[T <: Data](x: T): T = if (slice == 0) x else RegEnable(x, s1Fire)
  val (eHit, eFill, eLine, eReq) = (entering(hit && !forced), entering(fill || forced), entering(dataLine), entering(s1))
  /** a lookup that refetched a poisoned line (simulation taps it: the trace model replays these as misses) */
  val eForced: Bool = entering(forced)
  s1Go := (if (slice == 0) roomAll else !s2Valid || eFire)
  if (slice > 0) when(s1Fire) { s2Valid := true.B }.elsewhen(eFire) { s2Valid := false.B }
  // every ticket older than the entering decision is held or done, so the check sees all the fills ahead of it
  val clean = ticketScan.fold(false.B)(t => eHit && !heldTickets(t).map(e => e.valid && e.bits.fill && e.bits.line === eLine).reduce(_ || _))
  // TAG_FORWARD=1: a new request enters stage 1 in the cycle the one there decides; its read gets the set that
  // decision writes from the tag RAMs' write-first port (TagArray)
  val advance = if (g0.p.tagForward) s1Go else false.B
  io.in.ready := (!s1Valid || advance) && ready
  when(io.in.fire) { s1 := io.in.bits; s1Valid := true.B }
  val lookLine = Mux(s1Valid && !advance, s1.line, io.in.bits.line)

  /** An errored fill is not kept as a good line (MEM_RETRIES left an error the re-reads met each time, or there
    * were none): the data stage marks its data line poisoned, and a lookup that hits a poisoned line refetches it, a
    * miss that fills the same line, whatever the error's kind. The lookups already queued behind the errored fill
    * read its beats, error bits and all: they asked for the line the fill brought (as requests merged into a miss
    * would). A clean fill of the line clears the mark. The marks sit beside the tag arrays, one per way, read with
    * the set; whether a lookup saw a mark depends on when its fill's DRAM answer came, so the simulation logs each
    * refetch for the trace model (CacheReport).
    */
  class PoisonMarks(val sets: Int, val ways: Int) {
    private val setBits = math.max(1, log2Ceil(sets))
    private val mem = SyncReadMem(sets, Vec(ways, Bool()), SyncReadMem.ReadFirst)
    private val wEn = WireDefault(false.B); private val wSet = WireDefault(0.U(setBits.W))
    private val wWay = WireDefault(0.U(math.max(1, log2Ceil(ways)).W)); private val wBit = WireDefault(false.B)
    private val clearAll = WireDefault(false.B)
    mem.write(wSet, VecInit(Seq.fill(ways)(wBit && !clearAll)), VecInit(Seq.tabulate(ways)(w => wEn && (clearAll || wWay === w.U))))
    def read(setLine: UInt): Vec[Bool] = mem.read(if (sets == 1) 0.U else setLine(setBits - 1, 0))
    /** the reset sweep (with the tags') */
    def clear(clearing: Bool, clearSet: UInt): Unit = when(clearing && clearSet < sets.U) {
      wEn := true.B; clearAll := true.B; wSet := clearSet(setBits - 1, 0)
    }
    /** through a register: the ticket queue's read and the fill's last-beat compare do not run into the marks' RAM (a
      * lookup may then see a mark a cycle later, which the simulation's log of refetches records as it falls) */
    def mark(en: Bool, set: UInt, way: UInt, bad: Bool): Unit = {
      val (e, s, w, b) = (RegNext(en, false.B), RegNext(set), RegNext(way), RegNext(bad))
      when(e) { wEn := true.B; wSet := s; wWay := w; wBit := b }
    }
  }
  // one per tag array (bf: one per line), so the data line of (set, way) is set * ways + way after the arrays before
  val poison: Seq[PoisonMarks] =
    if (isBf) Seq(new PoisonMarks(cg.lines, 1))
    else Seq(new PoisonMarks(cg.lines / c.ways, c.ways)) ++ (if (isHybrid) Seq(new PoisonMarks(cg.sideLines / cg.sideWays, cg.sideWays)) else Nil)

  if (isBf) {
    // static buffer: lines 0..lines-1 hold nodes 0..lines-1 (the highest, breadth-first ids)
    hit := s1.line < cg.lines.U
    fill := false.B
    dataLine := s1.line(math.max(1, lineBits) - 1, 0)
    forced := hit && poison.head.read(lookLine)(0)
  } else {
    val tagRuw = if (!g0.p.tagForward) SyncReadMem.Undefined else if (forwardWrites) SyncReadMem.WriteFirst else SyncReadMem.ReadFirst
    val mainPol = Policies.of(if (isHybrid) CachePolicy.Dm else c.policy, c.ways)
    val main = new TagArray(cg.lines / c.ways, mainPol, lrp = c.policy.levelAware, hw.levelCodeBits, hw.policyStateBits, tagRuw)
    val arrays = Seq(main) ++ (if (isHybrid) Seq(new TagArray(cg.sideLines / cg.sideWays, Policies.of(CachePolicy.Lru, cg.sideWays), lrp = true, hw.levelCodeBits, hw.policyStateBits, tagRuw)) else Nil)
    val entries = arrays.map(_.read(lookLine))
    val ds = arrays.zip(entries).map { case (a, e) => a.decide(e, s1.line, s1.level, io.maxLevel) }
    // data line of (set, way): set * ways + way, after `base` lines of the arrays before this one
    def index(a: TagArray, base: Int, way: UInt): UInt = {
      val wayBits = log2Ceil(a.ways)
      val local = if (wayBits == 0) a.setOf(s1.line) else if (a.setBits == 0) way(wayBits - 1, 0) else Cat(a.setOf(s1.line), way(wayBits - 1, 0))
      (base.U +& local)(math.max(1, lineBits) - 1, 0)
    }
    val mainIdx = index(main, 0, ds.head.way)
    // after reset every set is cleared once (a SyncReadMem has no reset), one set per cycle
    val maxSets = arrays.map(_.sets).max
    val clearIdx = RegInit(0.U(log2Ceil(maxSets + 1).W))
    val clearing = clearIdx =/= maxSets.U
    when(clearing) { clearIdx := clearIdx + 1.U }
    ready := !clearing
    val poisoned = poison.zip(arrays).map { case (pm, a) => pm.read(a.setOf(lookLine)) }
    poison.foreach(_.clear(clearing, clearIdx))
    if (!isHybrid) {
      hit := ds.head.hit; fill := ds.head.fill; dataLine := mainIdx
      forced := ds.head.hit && poisoned.head(ds.head.way)
      main.update(s1.line, ds.head, s1Fire, true.B, clearing, clearIdx)
    } else {
      // a line is in at most one array; the DM line is replaced when the level policy allows, else the side
      // array is offered the line (its own empty/LRU victim + level rule); refused there too = bypass
      val (dm, side) = (ds(0), ds(1))
      val sideIdx = index(arrays(1), cg.lines, side.way)
      hit := dm.hit || side.hit
      fill := !hit && (dm.fill || side.fill)
      dataLine := Mux(dm.hit || (!side.hit && dm.fill), mainIdx, sideIdx)
      forced := (dm.hit && poisoned(0)(0)) || (side.hit && poisoned(1)(side.way))
      main.update(s1.line, dm, s1Fire, !side.hit, clearing, clearIdx)
      arrays(1).update(s1.line, side, s1Fire, side.hit || (!dm.hit && !dm.fill), clearing, clearIdx)
    }
  }

  ticketQ.enq.valid := eFire && !clean
  ticketQ.enq.bits.hit := eHit
  ticketQ.enq.bits.fill := eFill
  ticketQ.enq.bits.silent := false.B
  ticketQ.enq.bits.line := eLine
  ticketQ.enq.bits.beats := eReq.beats
  for (t <- ticketQ.enq.bits.tag) t := eReq.tag.get
  for (q <- hitQ) { q.io.enq.valid := eFire && clean; q.io.enq.bits := ticketQ.enq.bits }
  missQ.io.enq.valid := eFire && !eHit
  missQ.io.enq.bits.addr := eReq.addr
  missQ.io.enq.bits.beats := eReq.beats
  when(eFire) {
    when(eHit) { hits := hits + 1.U }.otherwise { misses := misses + 1.U }
    when(!eHit && !eFill) { bypasses := bypasses + 1.U }
  }
  when(io.clearStats) { hits := 0.U; misses := 0.U; bypasses := 0.U }
  if (isBf) preload() // after the defaults above: its ticket and DRAM read override them while it runs

  /** bf: before the first request is served, read nodes 0 .. min(lines, primBase / stride) - 1 into the buffer
    * (primBase bounds the node region; it is set by the host before any ray arrives).
    */
  private def preload(): Unit = {
    val started = RegInit(false.B); val done = RegInit(false.B)
    val k = RegInit(0.U(log2Ceil(cg.lines + 1).W))
    // line k is read while it starts inside the node region [0, primBase) and k < lines
    val kAddr = k << log2Ceil(cg.strideBytes)
    val more = k < cg.lines.U && kAddr < io.primBase
    when(io.in.valid) { started := true.B }
    val issuing = started && !done
    val issue = issuing && more && ticketQ.enq.ready && missQ.io.enq.ready
    when(issuing && !more) { done := true.B }
    when(issue) { k := k + 1.U }
    ready := done
    when(issue) {
      ticketQ.enq.valid := true.B
      ticketQ.enq.bits.hit := false.B
      ticketQ.enq.bits.fill := true.B
      ticketQ.enq.bits.silent := true.B
      ticketQ.enq.bits.line := k
      ticketQ.enq.bits.beats := cg.lineBeats.U
      missQ.io.enq.valid := true.B
      missQ.io.enq.bits.addr := kAddr
      missQ.io.enq.bits.beats := cg.lineBeats.U
    }
  }

  // ---------------------------------------------------------------- data: tickets strictly in order
  // each beat is stored with its error bit (MSB): a poisoned beat stays poisoned while it is cached
  val data = SyncReadMem(cg.dataLines << cg.beatBits, UInt((dataBits + 1).W))
  val outQ = Module(new Queue(g.respBeat, hw.cacheOutQueue))
  val head = ticketOut.bits
  val beat = RegInit(0.U(g.beatsBits.W))
  val lastBeat = beat === head.beats - 1.U
  def addr(line: UInt, b: UInt): UInt = if (cg.beatBits == 0) line else Cat(line, b(cg.beatBits - 1, 0))
  // PIPELINE (`slice`): the data RAM's address, enable and write data leave flip-flops, a cycle after the read or
  // write is decided, not the ticket queue's LUT RAM through the issue logic across the RAM's many blocks. Reads and
  // writes shift together, so the order in which the RAM sees them, and every hazard, is unchanged; a read lands
  // two cycles after its decision.
  private def toRam[T <: Data](x: T): T = ShiftRegister(x, slice)
  private def toRamValid(v: Bool): Bool = ShiftRegister(v, slice, false.B, true.B)
  /** a read decided in cycle t lands in cycle t + 1 + slice; `flight(v)` is v for each cycle until then, the last
    * the one landing */
  def flight(v: Bool): Seq[Bool] = Seq.iterate(RegNext(v, false.B), 1 + slice)(RegNext(_, false.B))
  /** a data RAM read may issue when `q` has room for it and for those in flight (`flying`). Unsliced: at most
    * depth - 2 beats queued or landing. Sliced: depth - 1, and a DRAM beat waits while any in-order read flies, so
    * nothing else enters `q` between a decision and its landing (a full-rate stream of reads keeps its rate).
    */
  private val roomLimit = hw.cacheOutQueue - (if (slice == 0) 2 else 1)
  def room(q: QueueIO[FetchBeat], flying: Seq[Bool]): Bool = (q.count +& PopCount(flying)) <= roomLimit.U

  // a data RAM read issued (decided) in one cycle lands in outQ 1 + slice cycles later, only when outQ has room
  val readIssue = Wire(Bool())
  val readFlight = flight(readIssue)
  val inflight = readFlight.last
  // outQ's entries and the reads flying to it, counted in a register: their sum from outQ's pointers and the flight
  // (room) ran into the ticket queue's ready, the MC's routed critical path on ECP5. outQ takes only landing reads
  // and DRAM beats; a landing read leaves the flight as it enters outQ.
  val outOcc = RegInit(0.U(log2Ceil(hw.cacheOutQueue + 2).W))
  private val outOccNext = outOcc + readIssue.asUInt + (io.memResp.fire && !head.silent).asUInt - outQ.io.deq.fire.asUInt
  outOcc := outOccNext
  assert(outOcc === outQ.io.count +& PopCount(readFlight), "CachePath: outOcc lost count of outQ and the reads flying to it")
  // whether outQ has room for a DRAM beat, from a register: a DRAM beat is taken only while no read flies, when outOcc
  // is outQ's count, so this is outQ's enq.ready then. The queue's pointers through its full compare into the ready
  // for DRAM beats, and on to the MC's response slice, were the smallest platform's routed critical path on ECP5.
  private val outRoom = RegNext(outOccNext < hw.cacheOutQueue.U, true.B)
  assert(outRoom === (outOcc < hw.cacheOutQueue.U), "CachePath: outRoom out of step with outOcc")
  readIssue := ticketOut.valid && head.hit && outOcc <= roomLimit.U
  val inflightLast = ShiftRegister(lastBeat, 1 + slice)
  // RESP_ORDER=tagged: the clean hits' reads share the RAM's one read port; an in-order hit's read goes first
  val hitRead = hitQ.map { q =>
    val h = q.io.deq.bits
    val hBeat = RegInit(0.U(g.beatsBits.W))
    val hOut = Module(new Queue(g.respBeat, hw.cacheOutQueue))
    val issue = Wire(Bool())
    val hFlight = flight(issue)
    issue := q.io.deq.valid && !readIssue && room(hOut.io, hFlight)
    val hLast = hBeat === h.beats - 1.U
    when(issue) { hBeat := Mux(hLast, 0.U, hBeat + 1.U) }
    q.io.deq.ready := issue && hLast
    (issue, addr(h.line, hBeat), hOut, hFlight.last, ShiftRegister(hLast, 1 + slice), ShiftRegister(h.tag.get, 1 + slice))
  }
  val rdAddr = toRam(hitRead.fold(addr(head.line, beat)) { case (issue, a, _, _, _, _) => Mux(issue, a, addr(head.line, beat)) })
  val rdEn = toRamValid(readIssue || hitRead.fold(false.B)(_._1))

  val missHead = ticketOut.valid && !head.hit
  // RESP_ORDER=tagged: a fill starts only when no queued clean hit still reads its data line (write after read)
  val fillBlocked = hitQ.fold(false.B) { q =>
    val reads = q.io.held.map(e => e.valid && e.bits.line === head.line).reduce(_ || _)
    headStage match {
      case None => head.fill && beat === 0.U && reads
      case Some(_) =>
        // PIPELINE: the check is a cycle old, so the hit queue's compares reach a register, not the response's ready
        // (and the MC's arbitration behind it). It still holds: the head is the same ticket (the slice's output
        // register neither loaded nor let it go), and no clean hit on its line has entered meanwhile (the clean check sees the head
        // register's fill). A fill's first beat waits a cycle after its ticket reaches the head.
        val passed = RegNext(ticketOut.valid && !ticketOut.ready && !reads, false.B)
        head.fill && beat === 0.U && !passed
    }
  }
  val canTakeMiss = missHead && !readFlight.reduce(_ || _) && (head.silent || outRoom) && !fillBlocked
  when(canTakeMiss && !head.silent) { assert(outQ.io.enq.ready, "CachePath: outRoom said room where outQ had none") }
  io.memResp.ready := canTakeMiss
  val missBeat = io.memResp.fire
  // a fill's error bits, gathered over its beats, mark its data line at its last beat (PoisonMarks)
  val fillErr = RegInit(false.B)
  when(missBeat && head.fill) { fillErr := !lastBeat && (fillErr || io.memResp.bits.err) }
  private val lineErr = fillErr || io.memResp.bits.err
  locally {
    var base = 0
    for (pm <- poison) {
      val wayBits = log2Ceil(pm.ways)
      val local = head.line -& base.U
      val inIt = head.line >= base.U && head.line < (base + pm.sets * pm.ways).U
      pm.mark(missBeat && head.fill && lastBeat && inIt, (local >> wayBits)(math.max(1, log2Ceil(pm.sets)) - 1, 0),
        if (wayBits == 0) 0.U else local(wayBits - 1, 0), lineErr)
      base += pm.sets * pm.ways
    }
  }
  val wrEn = toRamValid(missBeat && head.fill)
  val wrAddr = toRam(addr(head.line, beat))
  val wrData = toRam(Cat(io.memResp.bits.err, io.memResp.bits.data))
  // In order, a read (a hit's) and a write (a miss's fill) are never decided in the same cycle and both reach the RAM
  // `slice` cycles later, so the RAM has one port, written explicitly: left to itself, firtool merged the two ports
  // into one whose write mode was the ticket queue's unregistered `hit` (ECP5: the queue's LUT RAM read routed into
  // every block's write enable, the MC's routed critical path). Tagged, a clean hit's read may meet a fill.
  val rd = if (hitQ.isEmpty) data.readWrite(Mux(wrEn, wrAddr, rdAddr), wrData, rdEn || wrEn, wrEn)
  else {
    when(wrEn) { data.write(wrAddr, wrData) }
    data.read(rdAddr, rdEn)
  }

  outQ.io.enq.valid := inflight || (missBeat && !head.silent)
  outQ.io.enq.bits.data := Mux(inflight, rd(dataBits - 1, 0), io.memResp.bits.data)
  outQ.io.enq.bits.err := Mux(inflight, rd(dataBits), io.memResp.bits.err)
  outQ.io.enq.bits.last := Mux(inflight, inflightLast, lastBeat)
  // a DRAM beat is the head ticket's; a data RAM read lands after its issue, when an in-order hit's last read has
  // already let its ticket go: the tag is kept with the read
  for (t <- outQ.io.enq.bits.tag) t := Mux(inflight, ShiftRegister(head.tag.get, 1 + slice), head.tag.get)

  val beatDone = readIssue || missBeat
  when(beatDone) { beat := Mux(lastBeat, 0.U, beat + 1.U) }
  ticketOut.ready := beatDone && lastBeat

  hitRead match {
    case None => io.out <> outQ.io.deq
    case Some((_, _, hOut, hInflight, hInflightLast, hInflightTag)) =>
      hOut.io.enq.valid := hInflight
      hOut.io.enq.bits.data := rd(dataBits - 1, 0)
      hOut.io.enq.bits.err := rd(dataBits)
      hOut.io.enq.bits.last := hInflightLast
      hOut.io.enq.bits.tag.get := hInflightTag
      // merge a whole answer at a time: `busy` holds the source until its last beat; when both wait, the one that
      // did not go last goes (so neither starves the other)
      val srcs = Seq(outQ.io.deq, hOut.io.deq)
      val busy = RegInit(false.B); val cur = RegInit(0.U(1.W)); val lastWent = RegInit(1.U(1.W))
      val pick = Mux(busy, cur, Mux(srcs(0).valid && srcs(1).valid, ~lastWent, Mux(srcs(0).valid, 0.U, 1.U)))
      io.out.valid := Mux(pick === 0.U, srcs(0).valid, srcs(1).valid)
      io.out.bits := Mux(pick === 0.U, srcs(0).bits, srcs(1).bits)
      for ((s, i) <- srcs.zipWithIndex) s.ready := io.out.ready && pick === i.U
      when(io.out.fire) { busy := !io.out.bits.last; cur := pick; when(io.out.bits.last) { lastWent := pick } }
      when(hInflight) { assert(hOut.io.enq.ready, "CachePath: a clean hit's data RAM read found its output queue full") }
  }

  when(missBeat) { assert(io.memResp.bits.last === lastBeat, "CachePath: DRAM beats out of step with the ticket") }
  when(inflight) { assert(outQ.io.enq.ready, "CachePath: a data RAM read found the output queue full") }
}

object CachePath {
  /** Refuses cache configurations the RTL cannot build, with what to change (InputError: one `error:` line). */
  def validate(p: rtaccel.config.PlatformParams): Unit = {
    def fail(msg: String) = throw new rtaccel.io.InputError(msg)
    rtaccel.config.Fit.checkLevelField(p)
    for ((what, c) <- Seq("NODE" -> p.nodeCache, "PRIM" -> p.primCache) if c.entries > 0) {
      val pol = try Policies.of(c.policy, c.ways) catch { case e: IllegalArgumentException => fail(s"${what}_POLICY: ${e.getMessage.stripPrefix("requirement failed: ")}") }
      if (pol.stateBits > p.hw.policyStateBits)
        fail(s"${what}_WAYS=${c.ways} with ${c.policy}: the RTL tabulates at most ${p.hw.policyStateBits} state bits per set (true LRU up to 4 ways, PLRU up to 8); use fewer ways or make cachesim")
    }
    if (p.primCache.entries > 0 && !CachePolicy.primRtl(p.primCache.policy))
      fail(s"PRIM_POLICY=${p.primCache.policy} is not built in RTL (leaf references carry no level, and the static buffer preloads nodes); use dm|lru|plru, or make cachesim for the model")
    if (p.primCache.entries > 0 && p.primCache.entries < p.mppl)
      fail(s"PRIM_CACHE=${p.primCache.entries} holds less than one leaf of MPPL=${p.mppl} primitives; use at least ${p.mppl}")
  }

  /** MC path factory: a cache on the node and/or primitive path when its CacheParams has entries, else the
    * pass-through. The primitive cache's lines hold one leaf of up to MPPL primitives (the paper's W x D).
    */
  def factory(node: CacheParams, prim: CacheParams, mppl: Int): (McGeometry, Int) => FetchPathModule = (g, i) =>
    if (i == FetchPath.Node && node.entries > 0) new CachePath(g, nodeGeometry(node, g.p, g.nodeBeats))
    else if (i == FetchPath.Prim && prim.entries > 0) new CachePath(g, primGeometry(prim, mppl, g.p, g.axi.beatBytes))
    else new FetchPath(g)

  /** A node cache line holds one node; a primitive cache line one leaf of up to MPPL primitives (also what the cost
    * model tiles into block RAM, rtaccel.area.CostModel.caches): MPPL slots, or with PRIM_FORMAT=packed one leaf
    * row (leafBytes(MPPL), keyed by the row number the reference holds).
    */
  def nodeGeometry(c: CacheParams, p: rtaccel.config.PlatformParams, nodeBeats: Int): CacheGeometry =
    CacheGeometry(c, 1, nodeBeats, p.nodeSlotBytes)
  def primGeometry(c: CacheParams, mppl: Int, p: rtaccel.config.PlatformParams, beatBytes: Int): CacheGeometry =
    CacheGeometry(c, mppl, p.leafRowBytes / beatBytes, p.primStrideBytes)
}
