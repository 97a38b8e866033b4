package rtaccel.top

import chisel3._
import chisel3.util._
import chisel3.experimental.BaseModule
import rtaccel.config.PlatformParams
import rtaccel.iu.IntersectionUnit
import rtaccel.cache.hw.{CachePath, NodeBanks}
import rtaccel.mc.{AxiParams, AxiReadMaster, AxiReadMux, McGeometry, MemoryController}
import rtaccel.tc.TraversalController
import rtaccel.tu.TraversalUnit

/** One AXI4-Stream beat (tvalid/tready come from Decoupled). */
class AxisBeat(bits: Int) extends Bundle {
  val tdata = UInt(bits.W)
  val tlast = Bool()
}

object RtAccelTop {
  /** Ray beat: 9 words, word i at bits 32i+31..32i: id, ox, oy, oz, dx, dy, dz, tmin, tmax. */
  val RayBits = 9 * 32
  /** Hit beat: 6 words: id, t, prim, u, v, flags (bit 0 = stack overflow, bit 1 = memory read error, bit 2 = step limit). */
  val HitBits = 6 * 32
  /** The AXI4-Lite port's address width: the register map's (RegMap.addrBits). */
  def liteAddrBits: Int = RegMap.addrBits(counterNames)
  /** Counted here, per cycle. */
  val eventNames: Seq[String] = Seq("cycles", "busy_cycles", "rays_in", "hits_out", "stall_iu_arbitration",
    "stall_memory_request", "stall_memory_data", "stall_host_backpressure", "tu_busy_cycles", "batch_cycles")
  /** Counted by the memory controller (not cleared by the control register). */
  val memoryNames: Seq[String] = Seq("node_requests", "leaf_requests", "prim_requests", "mem_bytes", "mem_busy_beats",
    "node_cache_hits", "node_cache_misses", "node_cache_bypasses", "prim_cache_hits", "prim_cache_misses", "prim_cache_bypasses",
    "mem_read_errors", "mem_retries")
  /** Counted here too, after the memory controller's (counters keep their addresses as the map grows):
    * rays that left flagged with the step limit. */
  val rayFaultNames: Seq[String] = Seq("step_limit_rays")
  val counterNames: Seq[String] = eventNames ++ memoryNames ++ rayFaultNames

  /** The read-only configuration registers of RegMap: what a host driver checks before it uploads anything. */
  def configWords(p: PlatformParams): Seq[(RegMap.Reg, BigInt)] = configWords(p, rtaccel.iu.PipeLatencies.of(p))
  /** The configuration words with the pipes' latencies given (the board top passes its own instances').
    * A knob's fields are the registry's (config.Knobs: `reads`, each with the value it encodes); the fields no knob
    * sets are derived here: the reference format, slot and beat sizes, and the pipes' latencies. */
  def configWords(p: PlatformParams, lat: rtaccel.iu.PipeLatencies): Seq[(RegMap.Reg, BigInt)] = {
    import RegMap._
    val derived: Seq[(String, Long)] = Seq("CONFIG0.MAX_LEAF_PRIMS" -> math.min(255, p.refs.maxLeafPrims),
      "CONFIG1.LEVEL_BITS" -> p.refs.levelBits, "CONFIG1.COUNT_BITS" -> p.refs.countBits, "CONFIG1.NODE_ID_BITS" -> p.refs.nodeIdBits,
      "FORMATS.PRIM_BYTES_LOG2" -> log2Ceil(p.primStrideBytes), "FORMATS.AXI_DATA_BYTES_LOG2" -> log2Ceil(p.axiDataBits / 8),
      // latencies past 255 cycles read 255
      "PIPELINE.BOX_LATENCY" -> math.min(255, lat.box), "PIPELINE.TRI_LATENCY" -> math.min(255, lat.tri),
      "PIPELINE.PREP_LATENCY" -> math.min(255, lat.prep))
    val values = rtaccel.config.Knobs.all.flatMap(_.fields).map(f => f.name -> f.value(p)) ++ derived
    configRegs.map { r =>
      val mine = values.filter(_._1.startsWith(r.name + "."))
      val names = mine.map(_._1.stripPrefix(r.name + "."))
      // every field written, once: a field a knob adds to the map needs its encoding in the registry
      require(names.sorted == r.fields.map(_.name).sorted, s"${r.name}: fields ${r.fields.map(_.name).mkString(", ")}, encoded ${names.mkString(", ")}")
      r -> mine.map { case (n, v) =>
        val f = r.fields.find(f => s"${r.name}.${f.name}" == n).get
        require(v >= 0 && v < (1L << f.width), s"$n = $v does not fit its ${f.width} bits")
        BigInt(v) << f.lsb
      }.sum
    }
  }
  /** The read-only registers that describe the circuit, in the order the host reads them. */
  val configRegs: Seq[RegMap.Reg] = Seq(RegMap.Config0, RegMap.Config1, RegMap.NodeCache, RegMap.PrimCache, RegMap.Formats, RegMap.Formats2, RegMap.Pipeline, RegMap.Intervals)
}

/** Board top (paper Fig 1, with the PCIe communication controller replaced by AXI4-Stream): rays in, hits
  * out, an AXI4 read master to onboard memory, and an AXI4-Lite slave with the register map of RegMap
  * (configuration, control, status, interrupt, counters; docs/registers.md) plus its interrupt line.
  * The node and primitive caches of p.nodeCache / p.primCache sit in the MC (none when entries = 0).
  * IUS = p.ius clusters of TUS / IUS TUs, each with its own IU, MC and caches, share the memory port.
  * NODE_BANKS > 0: the node cache is one, shared by the clusters in banks (NodeBanks), each bank with an MC of its
  * own; a cluster's node requests go to the banks and its leaf requests to its own MC and primitive cache.
  * tapAccesses (simulation): `tap(i)` shows every child reference MC i accepts (the clusters' MCs, then the node
  * banks'), so a harness can log the access order each cache saw and replay it through the trace model.
  */
class RtAccelTop(p: PlatformParams, tapAccesses: Boolean = false) extends Module {
  val axiP = AxiParams.of(p)
  val io = IO(new Bundle {
    val rays = Flipped(Decoupled(new AxisBeat(RtAccelTop.RayBits)))
    val hits = Decoupled(new AxisBeat(RtAccelTop.HitBits))
    val mem = new AxiReadMaster(axiP) // memory channel 0 (the only one unless MEM_CHANNELS > 1)
    val memMore = if (p.memChannels > 1) Some(Vec(p.memChannels - 1, new AxiReadMaster(axiP))) else None // channels 1..
    val lite = Flipped(new AxiLite(RtAccelTop.liteAddrBits))
    val irq = Output(Bool())
    val tap = if (tapAccesses) Some(Output(Vec(p.memControllers, Valid(UInt(32.W))))) else None // per IU cluster, then per node bank
  })
  val tc = Module(new TraversalController(p))
  val tus = Seq.fill(p.tus)(Module(new TraversalUnit(p.traversal)))
  // IUS clusters: TU i belongs to cluster i / tusPerIu, which has its own IU, MC and caches; the MCs share the
  // one memory port (AxiReadMux). A cluster's TUs answer to their index within it.
  // instance names: iu / mc as before at IUS=1 (waveforms and scripts keep their paths), iu_<c> / mc_<c> otherwise
  private def clusterName(n: String, c: Int) = if (p.ius == 1) n else s"${n}_$c"
  private def named[T <: BaseModule](m: T, n: String, c: Int): T = { m.suggestName(clusterName(n, c)); m }
  // the clusters' IUs are one module: elaborated once, instantiated IUS times
  private val iuDefinition = chisel3.experimental.hierarchy.Definition(new IntersectionUnit(p, axiP.dataBits, p.tusPerIu))
  val ius = Seq.tabulate(p.ius) { c =>
    val i = chisel3.experimental.hierarchy.Instance(iuDefinition)
    i.suggestName(clusterName("iu", c))
    i
  }
  // caches reorder DRAM traffic between the paths: give each path a response buffer (see MemoryController);
  // with several clusters the buffers also keep one cluster's R beats from waiting on another's
  // NODE_BANKS > 0: the clusters' MCs have no node cache (their node path carries nothing), the banks have it
  private val clusterNodeCache = if (p.nodeShared) rtaccel.config.CacheParams() else p.nodeCache
  val mcs = Seq.tabulate(p.ius)(c => named(Module(new MemoryController(p, axiP, pathFactory = CachePath.factory(clusterNodeCache, p.primCache, p.mppl),
    respBufferBeats = if (p.mcResponseBuffers) 2 * McGeometry(p, axiP).maxBeats else 0)), "mc", c))
  // generator parameters only (MPPL is a property of the memory image, not of the circuit)
  private val latencies = rtaccel.iu.PipeLatencies(iuDefinition.boxLatency, iuDefinition.triPipeLatency, tc.prepLatency)
  val regs = Module(new RegFile(RtAccelTop.configWords(p, latencies), RtAccelTop.counterNames, axiP.addrBits, p.nodeCache.maxLevel, p.hw.levelCodeBits,
    p.stepLimit, p.hw.stepBits))
  regs.io.lite <> io.lite
  io.irq := regs.io.irq

  // host stream -> TC
  tc.io.in.valid := io.rays.valid && regs.io.acceptRays
  tc.io.in.bits.id := io.rays.bits.tdata(31, 0)
  for (k <- 0 until 8) tc.io.in.bits.f(k) := io.rays.bits.tdata(32 * k + 63, 32 * k + 32)
  io.rays.ready := tc.io.in.ready && regs.io.acceptRays // rays flow only within a started batch
  io.hits.valid := tc.io.out.valid
  val h = tc.io.out.bits
  io.hits.bits.tdata := Cat(0.U(29.W), h.stepLimit, h.readError, h.overflow, h.v, h.u, h.prim, h.t, h.id)
  // TLAST on the hit that ends the batch (the RAY_COUNT-th of a started batch), so a DMA engine can end its
  // transfer there: hits are counted as they leave; the count clears between batches (RUNNING low)
  val hitsSent = RegInit(0.U(32.W))
  when(!regs.io.running) { hitsSent := 0.U }.elsewhen(io.hits.fire) { hitsSent := hitsSent + 1.U }
  io.hits.bits.tlast := regs.io.running && hitsSent === regs.io.lastHitIndex
  tc.io.out.ready := io.hits.ready

  for ((tu, i) <- tus.zipWithIndex) {
    val (iu, k) = (ius(i / p.tusPerIu), i % p.tusPerIu)
    tu.io.index := k.U
    tu.io.maxSteps := regs.io.maxSteps
    tu.io.ray <> tc.io.tuRay(i)
    tc.io.tuResult(i) <> tu.io.result
    iu.io.req(k) <> tu.io.req
    tu.io.box := iu.io.box
    tu.io.tri := iu.io.tri
  }
  // RAY_STORE=1: the TC hands out at most one ray per cycle; the cluster of the TU that takes it stores it, from the
  // bits of the cycle the TU reads them (tc.rayBitsLag after the handshake)
  for ((iu, c) <- ius.zipWithIndex; w <- iu.io.rays) {
    val mine = tc.io.tuRay.slice(c * p.tusPerIu, (c + 1) * p.tusPerIu)
    val fires = mine.map(_.fire)
    val v = VecInit(fires).asUInt // at most one bit set (v & (v - 1) clears the lowest): no adder left half unused
    assert((v & (v - 1.U)) === 0.U, "the TC handed out two rays in one cycle")
    val slot = if (mine.size == 1) 0.U else OHToUInt(fires)
    w.valid := ShiftRegister(fires.reduce(_ || _), tc.rayBitsLag, false.B, true.B)
    w.bits.slot := ShiftRegister(slot, tc.rayBitsLag)
    w.bits.ray := mine.head.bits.ray // the TC offers every TU the same ray
  }
  val nodeBanks = if (p.nodeShared) Some(Module(new NodeBanks(p, axiP))) else None
  for (((iu, mc), c) <- ius.zip(mcs).zipWithIndex) {
    nodeBanks match {
      case None =>
        mc.io.req <> iu.io.mem.req
        iu.io.mem.resp <> mc.io.resp
      case Some(nb) => // node references to the shared banks, leaves to the cluster's own MC
        val (req, toBanks) = (iu.io.mem.req, nb.io.req(c))
        val leaf = req.bits.childRef(p.refs.refBits - 1)
        mc.io.req.valid := req.valid && leaf
        mc.io.req.bits := req.bits
        toBanks.valid := req.valid && !leaf
        toBanks.bits := req.bits
        req.ready := Mux(leaf, mc.io.req.ready, toBanks.ready)
        iu.io.mem.resp <> nb.io.resp(c)
        mc.io.resp.ready := true.B // the cluster MC's node stream stays empty
        assert(!mc.io.resp.valid, "RtAccelTop: a cluster MC answered a node request with NODE_BANKS")
    }
    for ((i, m) <- iu.io.mem.primResp.zip(mc.io.primResp)) i <> m // RESP_ORDER=path
    mc.io.primBase := regs.io.primBase
    mc.io.maxLevel := regs.io.maxLevel
    mc.io.clearCounters := regs.io.clearCounters
  }
  for (nb <- nodeBanks) {
    nb.io.primBase := regs.io.primBase
    nb.io.maxLevel := regs.io.maxLevel
    nb.io.clearCounters := regs.io.clearCounters
  }
  io.tap.foreach { t =>
    for ((ti, mc) <- t.zip(mcs)) { ti.valid := mc.io.req.fire; ti.bits := mc.io.req.bits.childRef }
    for (nb <- nodeBanks; (ti, bt) <- t.drop(p.ius).zip(nb.io.tap)) ti := bt
  }
  /** The memory channels' ports, channel 0 first. */
  def memPorts: Seq[AxiReadMaster] = io.mem +: io.memMore.toSeq.flatten
  // AXI masters: the clusters' MCs, then the node banks'
  private val masters = mcs.map(_.io.axi) ++ nodeBanks.toSeq.flatMap(_.io.axi)
  if (masters.length == 1 && p.memChannels == 1) io.mem <> masters.head
  else {
    val mux = Module(new AxiReadMux(axiP, masters.length, p.hw.mcOutstanding, p.memChannels, log2Ceil(p.hw.channelInterleaveBytes)))
    for ((m, a) <- mux.io.in.zip(masters)) m <> a
    for ((port, o) <- memPorts.zip(mux.io.out)) port <> o
  }

  // counters
  private val perfNames = RtAccelTop.eventNames ++ RtAccelTop.rayFaultNames
  val perf = Module(new PerfCounters(perfNames, incBits = log2Ceil(p.tus + 1)))
  perf.io.clear := regs.io.clearCounters
  val tuBusy = tus.map(_.io.busy)
  val anyBusy = tuBusy.reduce(_ || _) || tc.io.out.valid
  // With PIPELINE, STATUS.BUSY (the TUs' OR) and the hit events reach the register file through a register: BUSY
  // falls, and DONE and the interrupt rise, a cycle late. The ray event does not: it bounds the rays accepted.
  def late[T <: Data](x: T): T = rtaccel.arb.Slice.late(p, x)
  regs.io.events.busy := late(anyBusy)
  regs.io.events.rayIn := io.rays.fire
  regs.io.events.hitOut := late(io.hits.fire)
  regs.io.events.readError := late(h.readError)
  regs.io.events.overflow := late(h.overflow)
  regs.io.events.stepLimit := late(h.stepLimit)
  def ev(b: UInt): UInt = { // PopCount of the TUs fits: incBits covers p.tus, so nothing is ever truncated
    require(b.getWidth <= perf.incBits, s"a ${b.getWidth}-bit event does not fit the ${perf.incBits}-bit counter increments")
    if (b.getWidth == perf.incBits) b.asUInt else Cat(0.U((perf.incBits - b.getWidth).W), b) // Bool.pad refuses to widen
  }
  // with PIPELINE the events reach the counters through a register, and a count over the TUs takes one more in
  // front of its adder tree: each counter runs a cycle or two late, with the same totals (nothing is read before the
  // batch is done)
  def countOf(bits: Seq[Bool]): UInt = ev(PopCount(late(VecInit(bits))))
  val events = Map(
    "cycles" -> 1.U, "batch_cycles" -> ev(regs.io.running), "busy_cycles" -> ev(anyBusy), "rays_in" -> ev(io.rays.fire), "hits_out" -> ev(io.hits.fire),
    "stall_iu_arbitration" -> countOf(tus.map(t => t.io.req.valid && !t.io.req.ready)),
    "stall_memory_request" -> ev(PopCount(memPorts.map(m => m.ar.valid && !m.ar.ready))),
    // an IU waits for data when one of its collections has a job and no beat (RESP_ORDER=path: either stream)
    "stall_memory_data" -> ev(PopCount(ius.map(iu => (iu.io.mem.resp +: iu.io.mem.primResp.toSeq).map(r => r.ready && !r.valid).reduce(_ || _)))),
    "stall_host_backpressure" -> ev(io.hits.valid && !io.hits.ready),
    "tu_busy_cycles" -> countOf(tuBusy), "step_limit_rays" -> ev(io.hits.fire && h.stepLimit))
  for ((n, i) <- perfNames.zipWithIndex) perf.io.events(i) := late(events(n))
  private def perfValue(n: String) = perf.io.values(perfNames.indexOf(n))
  val mcc = rtaccel.mc.McCounters.sum(mcs.map(_.io.counters) ++ nodeBanks.toSeq.flatMap(_.io.counters)) // in memoryNames order
  regs.io.counters := VecInit(RtAccelTop.eventNames.map(perfValue) ++ Seq(mcc.nodeRequests, mcc.leafRequests, mcc.primsRequested,
    mcc.bytesRequested, mcc.busyBeats, mcc.nodeCache.hits, mcc.nodeCache.misses, mcc.nodeCache.bypasses,
    mcc.primCache.hits, mcc.primCache.misses, mcc.primCache.bypasses, mcc.readErrors, mcc.retries).map(_.pad(64)) ++
    RtAccelTop.rayFaultNames.map(perfValue))
}
