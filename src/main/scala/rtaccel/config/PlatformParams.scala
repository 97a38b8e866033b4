package rtaccel.config

import rtaccel.io.InputError

/** Width of every field of a 32-bit-word child reference (paper Fig 2), generalised so that a
  * configuration can be fitted to a scene. Bit layout, MSB first:
  *   primitive (leaf): 1 | count-1 (countBits) | first primitive (primIndexBits)
  *   node:             0 | level (levelBits, saturating) | node id (nodeIdBits)
  * Counts are stored minus one so that 4 bits reach the paper's 16 primitives per leaf.
  */
final case class RefFormat(nodeIdBits: Int, primIndexBits: Int, countBits: Int, levelBits: Int) {
  require(nodeIdBits >= 1 && primIndexBits >= 1 && countBits >= 0 && levelBits >= 0, s"field widths must be positive: $this")
  val refBits: Int = 1 + math.max(levelBits + nodeIdBits, countBits + primIndexBits)
  require(refBits <= 32, s"a reference needs $refBits bits but memory words are 32 bits; narrow a field of $this")
  val maxLevelCode: Int = (1 << levelBits) - 1
  val maxLeafPrims: Int = 1 << countBits
}

/** DRAM model parameters (used by the simulation harness and analytic estimates). */
final case class MemoryParams(bytesPerSecond: Double = 1.2e9, sustainedEfficiency: Double = 0.5, latencyCycles: Int = 40) {
  require(bytesPerSecond > 0, "memory bandwidth must be positive")
  require(sustainedEfficiency > 0 && sustainedEfficiency <= 1, "sustained efficiency must be in (0,1]")
  require(latencyCycles >= 0, "memory latency cannot be negative")
}

/** Cache geometry and policy; entries = 0 means no cache. MAX_LEVEL is checked against the level code
  * width by PlatformParams (it is a register of that width).
  */
final case class CacheParams(entries: Int = 0, ways: Int = 1, policy: CachePolicy = CachePolicy.Dm, maxLevel: Int = 15) {
  require(entries == 0 || Integer.bitCount(entries) == 1, s"cache entries must be a power of two (got $entries)")
  require(ways >= 1 && (entries == 0 || entries % ways == 0), s"cache ways ($ways) must divide entries ($entries)")
  require(maxLevel >= 0, s"MAX_LEVEL must be >= 0 (got $maxLevel)")
  /** hybrid: lines of the LRP side cache beside a direct-mapped array of `lines` lines (an eighth, at least one);
    * the trace model, the RTL and the bank check all size it here */
  /** Lines of `entriesPerLine` entries each (a node, or a leaf of MPPL primitives): the largest power of two that
    * fits the entries, so an MPPL that is not a power of two leaves the remainder unused (PRIM_CACHE=64 at MPPL 3:
    * 16 lines of 3, not 21). The RTL (cache.hw.CacheGeometry) and the model (cache.CacheModel) both read it. */
  def lines(entriesPerLine: Int): Int = Integer.highestOneBit(math.max(1, entries / entriesPerLine))
  def sideLines(lines: Int): Int = if (policy == CachePolicy.Hybrid) math.max(1, lines / CacheParams.HybridSideShare) else 0
  /** hybrid: the side cache's ways (true LRU, at most HybridSideWays) */
  def sideWays(lines: Int): Int = math.min(CacheParams.HybridSideWays, sideLines(lines))
}

object CacheParams {
  val HybridSideShare = 8 // the side cache holds 1/8 of the direct-mapped array's lines
  val HybridSideWays = 4
}

/** RESP_ORDER: the order in which the MC answers (PlatformParams.respByPath, respTagged). */
object RespOrder {
  val Request = "request"
  val Path = "path"
  val Tagged = "tagged"
  /** The order's name, checked: request, path or tagged. */
  def parse(name: String): String = name.toLowerCase match {
    case n @ (Request | Path | Tagged) => n
    case _ => throw new InputError(s"RESP_ORDER=$name is not a response order; use $Request (one stream in request order, the paper's), " +
      s"$Path (node and primitive streams, each in its own order) or $Tagged (the two streams, each answered in any order, tagged by the requesting TU)")
  }
  def name(byPath: Boolean, tagged: Boolean = false): String = if (tagged) Tagged else if (byPath) Path else Request
}

/** Fixed sizes of the hardware that no scene changes: bus widths, outstanding-request limits, queue depths,
  * the level code of the level replacement policy, the MC's counter width and the replacement state the RTL
  * tabulates (the throughput model's own constants live with it, in cache/Throughput).
  * Each is checked here; a sweep may copy(...) them like any knob.
  */
final case class HwLimits(
  axiAddrBits: Int = 32,      // byte address of the memory master (4 GB)
  axiIdBits: Int = 4,
  iuOutstanding: Int = 16,    // IU jobs in flight (memory requests issued ahead of their data)
  mcOutstanding: Int = 32,    // MC requests in flight (its path-order FIFO)
  cacheTickets: Int = 32,     // lookups a cache path holds between tag and data stage
  cacheMissQueue: Int = 4,    // DRAM reads a cache path queues
  cacheOutQueue: Int = 4,     // beats a cache path buffers towards the IU (>= 3: the data RAM read pipeline)
  cacheHitQueue: Int = 4,     // RESP_ORDER=tagged: hits a cache path holds for its data RAM beside the misses' tickets
  dramQueueDepth: Int = 16,   // AR requests the simulated DRAM queues
  levelCodeBits: Int = 4,     // paper Section 7.2: node levels 0..14, 15 = 15 and deeper
  mcCounterBits: Int = 48,    // the MC's and its caches' event counters (never cleared by traffic: 2^48 events)
  policyStateBits: Int = 10,  // replacement state per set the RTL tabulates (2^bits rows: true LRU to 4 ways, PLRU to 8)
  // the MAX_STEPS register and each TU's count of the fetches its ray has left: a ray of the largest tree the 32-bit
  // address space holds stays below 2^32 fetches (PlatformParams.stepBound)
  stepBits: Int = 32,
  // MEM_CHANNELS > 1: bytes of one channel's address block (channel = (addr / this) mod channels); a burst never
  // crosses 4 KB (BurstSplitter), so a block of 4 KB or more keeps every burst in one channel
  channelInterleaveBytes: Int = 4096
) {
  require(channelInterleaveBytes >= 4096 && Integer.bitCount(channelInterleaveBytes) == 1,
    s"the channel interleave must be a power of two >= 4096 B, so that no AXI burst spans two channels (got $channelInterleaveBytes)")
  require(axiAddrBits >= 12 && axiAddrBits <= 64, s"AXI address width must be 12..64 bits (got $axiAddrBits)")
  require(axiIdBits >= 1 && axiIdBits <= 16, s"AXI id width must be 1..16 bits (got $axiIdBits)")
  require(iuOutstanding >= 1 && iuOutstanding <= 1024, s"IU outstanding jobs must be 1..1024 (got $iuOutstanding)")
  require(mcOutstanding >= 2 && mcOutstanding <= 1024, s"MC outstanding requests must be 2..1024 (got $mcOutstanding)")
  require(cacheTickets >= 2 && cacheTickets <= 1024, s"cache tickets must be 2..1024 (got $cacheTickets)")
  require(cacheMissQueue >= 1 && cacheMissQueue <= 64, s"cache miss queue must be 1..64 (got $cacheMissQueue)")
  require(cacheOutQueue >= 3 && cacheOutQueue <= 64, s"cache output queue must be 3..64 beats (got $cacheOutQueue): the data RAM pipeline keeps up to 3 beats in flight")
  require(cacheHitQueue >= 1 && cacheHitQueue <= 64, s"cache hit queue must be 1..64 (got $cacheHitQueue)")
  require(dramQueueDepth >= 1 && dramQueueDepth <= 256, s"DRAM queue depth must be 1..256 (got $dramQueueDepth)")
  require(policyStateBits >= 1 && policyStateBits <= 12, s"policy state must be 1..12 bits (got $policyStateBits): the RTL tabulates 2^bits rows per policy function")
  require(mcCounterBits >= 32 && mcCounterBits <= 64, s"MC counters must be 32..64 bits (got $mcCounterBits): the register map reads them as LO/HI words")
  require(levelCodeBits >= 1 && levelCodeBits <= 6, s"level code must be 1..6 bits (got $levelCodeBits); the RTL tabulates 2^bits x 2^bits classes")
  require(stepBits >= 8 && stepBits <= 32, s"the step count must be 8..32 bits (got $stepBits): MAX_STEPS is one 32-bit register")
  /** the highest level code: levels at or beyond it share it */
  val maxLevelCode: Int = (1 << levelCodeBits) - 1
  /** the largest MAX_STEPS the register holds */
  val stepMax: Long = (1L << stepBits) - 1
}

/** The one configuration object for the reference model, analysis, the RTL generators and the cost and timing tools.
  * User-facing knobs first; derived sizes follow; every illegal combination fails here with a message
  * that says what to change.
  */
final case class PlatformParams(
  name: String = "custom",
  tus: Int = 32,
  m: Int = 4,
  mppl: Int = 4,
  stackDepth: Int = 64,
  clockMhz: Double = 150.0,
  nodeAccessBytesOverride: Int = 0,
  primAccessBytes: Int = 64,
  refs: RefFormat = RefFormat(nodeIdBits = 31, primIndexBits = 27, countBits = 4, levelBits = 0),
  nodeCache: CacheParams = CacheParams(),
  primCache: CacheParams = CacheParams(),
  memory: MemoryParams = MemoryParams(),
  sahBins: Int = 16,
  axiDataBits: Int = 256,
  divStages: Int = 6,
  hw: HwLimits = HwLimits(),
  shortStack: Int = 0, // > 0: a ring of that many entries with restart instead of the full stack
  treeLevels: Int = 64, // node levels a TU can walk: the short stack keeps one trail counter per level
  // MAX_STEPS: fetches (node or leaf) a ray may issue; a ray that needs one more is flagged prim -4 and ends there
  // (docs/architecture.md, "Step limit"). None: stepBound, which no ray of an uncorrupted image reaches; 0: no limit
  maxSteps: Option[Int] = None,
  boxFormat: rtaccel.fp.FpFormat = rtaccel.fp.FpFormat.fp32, // arithmetic of the slab test; narrower ones round outward
  triTest: TriTest = TriTest.Mt, // the ray-triangle test (Numerics: the formats every JSON line names)
  nodeQuantBits: Int = 0, // NODE_FORMAT: 0 = full fp32 planes, k = q<k> quantized planes (bvh.Quantize, bvh.QNodeLayout)
  primPacked: Boolean = false, // PRIM_FORMAT=packed: a leaf's triangles back to back, beat-aligned per leaf (docs/numerics.md)
  triFormat: rtaccel.fp.FpFormat = rtaccel.fp.FpFormat.fp32, // TRI_FORMAT: Möller–Trumbore's arithmetic, fp32 or wider (Numerics)
  // TRI_II=k: the triangle pipe takes a primitive every k cycles at most and shares each of its operators among k
  // operations of a primitive (iu.TriPipe, fp.Fold): about 1/k of the multipliers and adders, the same results
  triInterval: Int = 1,
  // BOX_II=k: the box pipe takes a node every k cycles at most and shares each subtractor and multiplier among k
  // planes of a node (iu.BoxPipe, fp.Fold)
  boxInterval: Int = 1,
  ius: Int = 1, // IUS: intersection units, each with its own MC and caches and TUS / IUS TUs (docs/platform.md, "IU clusters")
  memChannels: Int = 1, // MEM_CHANNELS: address-interleaved DRAM channels, each an AXI4 master with MEM_GBPS of its own
  // RESP_ORDER=path: the MC answers node and primitive requests in two streams, each in its own path's order, so a
  // node hit never waits behind an older primitive miss (nor a primitive hit behind a node miss); request = one
  // stream in global request order, the paper's design (docs/platform.md, "Response order")
  respByPath: Boolean = false,
  // RESP_ORDER=tagged (with respByPath): each stream answers in any order, every beat tagged with the requesting TU
  // (each TU has one request in flight), so a cache hit never waits behind an older miss of its own path either
  // (hits under misses; docs/platform.md, "Response order")
  respTagged: Boolean = false,
  // RAY_STORE=1: each IU keeps its TUs' rays in a ray store (one entry per TU, written by the TC as it hands a ray
  // out); a request carries the TU's index, the reference and tmax, not the ray (docs/platform.md, "Ray store")
  rayStore: Boolean = false,
  // TAG_FORWARD=1: every cache path's tag pipeline accepts one lookup per cycle, the set a lookup writes forwarded to
  // the next lookup's decision (read after write); 0: one lookup per two cycles (read, then decide and write), as
  // the paper's pipeline (docs/caches.md, "One lookup per cycle")
  tagForward: Boolean = false,
  // NODE_BANKS=k (k >= 1): one node cache of nodeCache.entries serves every IU, in k banks chosen by the low bits of
  // the node id, each bank a tag pipeline and data RAM of entries / k lines behind a crossbar; 0: each IU cluster has
  // a node cache of its own of nodeCache.entries (docs/caches.md, "Shared node cache")
  nodeBanks: Int = 0,
  // MEM_RETRIES=n: the MC re-reads a burst that the memory answered with SLVERR up to n times before its beats go on
  // marked as errors (the ray is flagged read error); 0 flags at once. Below the caches, so a cache never sees an
  // error a re-read cleared (docs/platform.md, "Memory errors")
  memRetries: Int = 1,
  // PIPELINE: LUT levels allowed between two registers of the datapaths (fp operators, IU pipes, the TC's ray
  // preparation): auto = what the target clock leaves on `family` (docs/timing.md); none = the fixed stages
  pipelining: Pipelining = Pipelining.Auto,
  // the FPGA family the pipelining budget is reckoned for: BOARD='s, else the paper's Virtex-5
  family: String = "xc5v",
  // the target clock of PIPELINE=auto when it is not clockMhz: with CLOCK_MHZ=fmax the circuit is built for the
  // board's clock and then runs at the clock measured for it
  pipelineMhz: Option[Double] = None,
  // where clockMhz came from: given (CLOCK_MHZ=<MHz>) | board (the catalog's, or the paper's board's with no BOARD)
  // | proxy (make area's LUT levels) | routed (make timing); shapes no circuit (area.ClockSource)
  clockSource: String = "board"
) {
  require(!respTagged || respByPath, "RESP_ORDER=tagged answers on the two path streams; set respByPath with respTagged")
  require(triFormat.holds(rtaccel.fp.FpFormat.fp32),
    s"TRI_FORMAT=${triFormat.name} is narrower than fp32; use fp32, fp64 or e<E>m<M> with E >= 8 and M >= 23")
  require(triFormat == rtaccel.fp.FpFormat.fp32 || triTest == TriTest.Mt,
    s"TRI_FORMAT=${triFormat.name} widens Möller–Trumbore only; TRI_TEST=watertight takes TRI_FORMAT=fp32 (its edge signs are exact already)")
  require(triInterval >= 1 && triInterval <= PlatformParams.MaxTriInterval, s"TRI_II must be 1..${PlatformParams.MaxTriInterval} cycles (got $triInterval)")
  require(boxInterval >= 1 && boxInterval <= PlatformParams.MaxBoxInterval, s"BOX_II must be 1..${PlatformParams.MaxBoxInterval} cycles (got $boxInterval)")
  require(nodeQuantBits == 0 || (nodeQuantBits >= 2 && nodeQuantBits <= 16),
    s"NODE_FORMAT=q$nodeQuantBits: a quantized plane takes 2..16 bits (the 16-bit field of the node layout)")
  require(rtaccel.fp.FpFormat.fp32.holds(boxFormat),
    s"BOX_FORMAT=${boxFormat.name} is wider than fp32 in exponent or fraction; the box test takes fp32 inputs, so use a format within e8m23")
  require(shortStack >= 0 && shortStack <= 64, s"SHORT_STACK must be 0 (full stack) or 1..64 entries (got $shortStack)")
  require(treeLevels >= 1 && treeLevels <= 256, s"tree levels must be 1..256 (got $treeLevels)")
  require(tus >= 1 && tus <= 1024, s"TUS must be in 1..1024 (got $tus)")
  require(ius >= 1 && ius <= 64, s"IUS must be in 1..64 (got $ius)")
  require(memChannels >= 1 && memChannels <= 16 && Integer.bitCount(memChannels) == 1,
    s"MEM_CHANNELS must be 1, 2, 4, 8 or 16 (got $memChannels): the channel is address bits above the interleave block")
  require(memRetries >= 0 && memRetries <= PlatformParams.MaxMemRetries,
    s"MEM_RETRIES must be 0..${PlatformParams.MaxMemRetries} (got $memRetries): a transient error clears on its first re-read")
  require(tus % ius == 0, s"TUS=$tus does not split evenly over IUS=$ius intersection units; make TUS a multiple of IUS")
  require(Set(2, 4, 8)(m), s"M (MBVH width) must be 2, 4 or 8 (got $m)")
  require(mppl >= 1, s"MPPL must be at least 1 (got $mppl)")
  require(mppl <= refs.maxLeafPrims,
    s"MPPL $mppl does not fit the ${refs.countBits}-bit leaf count field (max ${refs.maxLeafPrims}); lower MPPL or widen countBits")
  require(stackDepth >= 1, s"stack depth must be at least 1 (got $stackDepth)")
  require(maxSteps.forall(s => s >= 0 && s <= hw.stepMax),
    s"MAX_STEPS must be 0 (no limit) or 1..${hw.stepMax} fetches, the ${hw.stepBits}-bit register (got ${maxSteps.get})")
  require(clockMhz > 0, "clock must be positive")
  require(sahBins >= 2, "SAH needs at least 2 bins")
  require(Seq(64, 128, 256, 512).contains(axiDataBits), s"AXI data width must be 64, 128, 256 or 512 bits (got $axiDataBits)")
  require(divStages >= 0 && divStages <= 32, s"divider pipeline stages must be 0..32 (got $divStages)")
  for ((what, c) <- Seq("NODE" -> nodeCache, "PRIM" -> primCache))
    require(c.maxLevel <= hw.maxLevelCode, s"MAX_LEVEL must be 0..${hw.maxLevelCode} for a ${hw.levelCodeBits}-bit level code (got ${c.maxLevel} on the $what cache)")
  require(refs.levelBits <= 31, "level field too wide")
  require(nodeBanks >= 0 && nodeBanks <= 64 && (nodeBanks == 0 || Integer.bitCount(nodeBanks) == 1),
    s"NODE_BANKS must be 0 (a node cache per IU) or a power of two 1..64 (got $nodeBanks)")
  if (nodeBanks > 0) {
    require(nodeCache.entries > 0, s"NODE_BANKS=$nodeBanks shares the node cache, but NODE_CACHE=0; give NODE_CACHE entries or set NODE_BANKS=0")
    require(respTagged, s"NODE_BANKS=$nodeBanks answers each IU from several banks, in any order; use RESP_ORDER=tagged")
    require(nodeCache.policy != CachePolicy.Bf,
      s"NODE_BANKS=$nodeBanks: the static buffer (NODE_POLICY=bf) preloads by node id and is not banked; use dm|lru|plru|lrp|hybrid or NODE_BANKS=0")
    val sets = nodeCache.entries / nodeCache.ways
    require(sets % nodeBanks == 0,
      s"NODE_BANKS=$nodeBanks must divide the node cache's $sets sets (NODE_CACHE=${nodeCache.entries} / NODE_WAYS=${nodeCache.ways}); use fewer banks or more entries")
    if (nodeCache.policy == CachePolicy.Hybrid) {
      val sideSets = nodeCache.sideLines(nodeCache.entries) / nodeCache.sideWays(nodeCache.entries)
      require(sideSets % nodeBanks == 0,
        s"NODE_BANKS=$nodeBanks must divide the hybrid side array's $sideSets sets (NODE_CACHE=${nodeCache.entries} / ${CacheParams.HybridSideShare * CacheParams.HybridSideWays}); use fewer banks or more entries")
    }
  }

  /** Bytes one node occupies: M x (6 floats + ref) = 28*M, rounded up to a power of two so a node id
    * maps to an address by a shift (QBVH: 112 B stored in 128 B, as in the paper).
    */
  val nodeBits: Int = m * 7 * 32
  val nodeStrideBytes: Int = Integer.highestOneBit(nodeBits / 8 - 1) << 1
  /** A primitive is 9 floats (288 bits); its 64-byte slot also carries the original triangle id. */
  val primBits: Int = 9 * 32
  val primStrideBytes: Int = 64
  // the IU's collection hands the pipe a primitive once all its beats are in: one per primStrideBytes / beat cycles
  // at most. Packed leaves' records span beats unevenly; the LeafAssembler spaces them TRI_II cycles apart itself
  private def primBeats = math.max(1, primStrideBytes * 8 / axiDataBits)
  require(triInterval == 1 || primPacked || primBeats >= triInterval,
    s"TRI_II=$triInterval needs a primitive to take at least $triInterval memory beats (it takes $primBeats at a " +
      s"$axiDataBits-bit bus); use TRI_II=$primBeats or PRIM_FORMAT=packed")
  /** Bytes a node occupies in NODE_FORMAT: the full node's slot, or the quantized node (bvh.Quantize) rounded up to
    * a power of two (M=4, q8: 64 B). The stride of the node array in memory, the node fetch's beats and a node
    * cache line of the RTL.
    */
  val nodeSlotBytes: Int = if (nodeQuantBits == 0) nodeStrideBytes
    else Integer.highestOneBit(math.max(1, (rtaccel.bvh.Quantize.nodeBits(m, nodeQuantBits) + 7) / 8 - 1)) << 1
  // the IU's collection hands the box pipe a node once all its beats are in: one per nodeSlotBytes / beat cycles at most
  private def nodeBeats = math.max(1, nodeSlotBytes * 8 / axiDataBits)
  require(boxInterval <= nodeBeats, s"BOX_II=$boxInterval needs a node to take at least $boxInterval memory beats (it takes $nodeBeats: " +
    s"M=$m, ${if (nodeQuantBits == 0) "full" else s"q$nodeQuantBits"} nodes of $nodeSlotBytes B on a $axiDataBits-bit bus); use BOX_II=$nodeBeats or less")
  /** DRAM bytes of a leaf of `count` primitives: count 64 B slots, or with PRIM_FORMAT=packed the 40 B records
    * (9 floats + id) back to back, rounded up to whole memory beats per leaf (M=4 MPPL=4 on 256-bit beats: 160 B).
    */
  def leafBytes(count: Int): Long =
    if (!primPacked) count.toLong * primAccessBytes
    else { val beat = axiDataBits / 8; (count.toLong * Numerics.packedPrimBytes + beat - 1) / beat * beat }
  /** PRIM_FORMAT=packed: bytes of a leaf's row in the image, so that a leaf's address is primBase + row * rowBytes
    * (a constant multiply, no table); slot64: MPPL slots (what a primitive cache line holds either way).
    */
  val leafRowBytes: Int = if (primPacked) leafBytes(mppl).toInt else mppl * primStrideBytes
  /** Bytes one node fetch moves (paper: 128 B for QBVH); defaults to the node's stored size. */
  val nodeAccessBytes: Int = if (nodeAccessBytesOverride > 0) nodeAccessBytesOverride else nodeSlotBytes
  /** The node cost the tree builder's SAH weighs: the full node's, so that NODE_FORMAT changes the boxes, not the tree. */
  val treeNodeBytes: Int = if (nodeAccessBytesOverride > 0) nodeAccessBytesOverride else nodeStrideBytes
  require(nodeAccessBytes >= (if (nodeQuantBits == 0) nodeBits / 8 else nodeSlotBytes / 2 + 1),
    s"node access of $nodeAccessBytes B is smaller than a node ($nodeSlotBytes B slot); raise the node access size")
  /** Ulps of the box format added to every box's exit distance (tfar) before the hit comparison: none for
    * Möller–Trumbore (the paper's test, bit-exact as before); with the watertight test at least
    * Numerics.watertightBoxSlack relative, so that no box loses a hit the triangle test would find
    * (docs/numerics.md, "The watertight triangle test").
    */
  val boxSlackUlps: Int = {
    val e = boxFormat.manBits + 1 - Numerics.watertightBoxSlackLog2
    if (triTest != TriTest.Watertight) 0 else if (e <= 0) 1 else 1 << e
  }
  /** The default step limit: more fetches than any ray of an uncorrupted image this configuration can address makes.
    * With the full stack a ray fetches each node and each leaf at most once (each is pushed or entered only from its
    * one parent, fetched once), so nodes + leaves bounds it; the short stack's restarts fetch again at most the path
    * from the root (treeLevels nodes and the restart's own) once per finished subtree, hence the factor treeLevels + 2.
    * The counts are bounded by what the references can name and the memory hold: node ids of nodeIdBits, leaves by
    * their first field of primIndexBits (each with a primitive slot, or a packed row, of its own), each within the
    * axiAddrBits address space. CONFIG=fit sizes the fields to the scene (2^bits <= 2 x the count), so the default
    * is 1-2 x nodes + primitives, itself at least nodes + leaves: a loop through a corrupted image ends after about
    * that many fetches, and no correct ray is ever flagged. Capped at the register's largest value, which only a
    * short stack over a tree larger than the address space could need.
    */
  lazy val stepBound: Long = {
    val memBytes = 1L << math.min(hw.axiAddrBits, 62)
    val nodes = math.min(1L << refs.nodeIdBits, memBytes / nodeSlotBytes)
    val leaves = math.min(1L << refs.primIndexBits, memBytes / (if (primPacked) leafRowBytes else primStrideBytes))
    val perVisit = if (shortStack > 0) treeLevels + 2L else 1L
    val b = BigInt(nodes + leaves) * perVisit
    if (b > hw.stepMax) hw.stepMax else b.toLong
  }
  /** The MAX_STEPS register's value after reset: MAX_STEPS= when given, else stepBound (0 = no limit). */
  lazy val stepLimit: Long = maxSteps.fold(stepBound)(_.toLong)
  val tuBits: Int = math.max(1, 32 - Integer.numberOfLeadingZeros(tus - 1))
  /** TUs per IU cluster: TU i belongs to cluster i / tusPerIu (its IU, MC and caches). */
  val tusPerIu: Int = tus / ius
  /** Cycles a cache path's tag stage holds each lookup: read, then decide and write; TAG_FORWARD=1 overlaps the
    * next lookup's read with the write (CachePath; the throughput model's tag rate) */
  val tagLookupCycles: Int = if (tagForward) 1 else 2
  /** RESP_ORDER's name, as outputs record it */
  def respOrder: String = RespOrder.name(respByPath, respTagged)
  /** RESP_ORDER=tagged: bits of a response tag, the requesting TU's index within its IU cluster (0: untagged) */
  val respTagBits: Int = if (respTagged) math.max(1, 32 - Integer.numberOfLeadingZeros(tusPerIu - 1)) else 0
  /** NODE_BANKS > 0: the node cache is one, shared by every IU cluster (rtaccel.cache.hw.NodeBanks) */
  val nodeShared: Boolean = nodeBanks > 0
  /** bits of the bank number, the low bits of a node id (NODE_BANKS = 2^this; 0 without banks) */
  val nodeBankBits: Int = if (nodeBanks > 1) Integer.numberOfTrailingZeros(nodeBanks) else 0
  /** bits naming an IU cluster (0 for one) */
  val clusterBits: Int = if (ius > 1) 32 - Integer.numberOfLeadingZeros(ius - 1) else 0
  /** the memory controllers, each with an access order of its own (simulation logs one per MC): one per IU
    * cluster, then one per node bank */
  val memControllers: Int = ius + nodeBanks
  /** Cycles PIPELINE's registers add to every memory access: the IU arbiter's registered grant, the IU's slice on the
    * winner, its request slice, the MC's after its arbiter, the IU's slice on the MC's responses, its register in
    * front of its pipes and the TU's on its answer (the throughput model adds them; cache.Throughput).
    */
  def accessSliceCycles: Int = if (stageBudget.isDefined) 7 else 0
  /** Cycles PIPELINE adds to each node access with NODE_BANKS: the slices between the crossbar and the bank, on the
    * request and on each side of the answers' crossbar (cache.hw.NodeBanks; the throughput model adds them). */
  def bankSliceCycles: Int = if (stageBudget.isDefined && nodeShared) 3 else 0
  /** Cycles PIPELINE adds to each leaf in the TU: its last result is applied a cycle after it arrives, its compare
    * with tmax registered (tu.TraversalUnit; the throughput model adds it). */
  def tuLeafCycles: Int = if (stageBudget.isDefined) 1 else 0
  /** Whether the cluster MCs give each path a response buffer: caches reorder DRAM traffic between the paths, and
    * with several clusters or channels the buffers keep one's R beats from waiting on another's (MemoryController).
    */
  def mcResponseBuffers: Boolean = nodeCache.entries > 0 || primCache.entries > 0 || ius > 1 || memChannels > 1 || respByPath ||
    memRetries > 0 // a re-read lands in the room its first read reserved, before later reads' beats (MemoryController)
  /** Cycles PIPELINE's slices add to a DRAM read of a path: the AR channel's, and where the MC has response buffers
    * one on the read, one on its beats into and one out of the buffer (a pass-through path pays them on every access,
    * a cache on a miss).
    */
  def passSliceCycles: Int = if (stageBudget.isEmpty) 0 else if (mcResponseBuffers) 4 else 1
  /** Cycles PIPELINE's registers in a cache path add to its hits: a lookup's decision waits a cycle before it enters
    * the queues, a data RAM read or write reaches the block RAMs a cycle after it is decided, and the head ticket waits
    * in a register (rtaccel.cache.hw.CachePath), which a tagged clean hit passes by.
    */
  def cacheSliceCycles: Int = if (stageBudget.isEmpty) 0 else if (respTagged) 2 else 3
  /** PIPELINE's budget: LUT levels at most between two registers of a datapath (None: the fixed stages). */
  lazy val stageBudget: Option[Int] = pipelining.budget(family, pipelineMhz.getOrElse(clockMhz))
  /** The board family's DSP block (boards/timing.json): with a budget, multipliers are cut into its products. */
  lazy val dspShape: rtaccel.fp.DspShape = rtaccel.area.Timing.forFamily(family).dsp
  /** A register placer for one module's datapath at this budget (each module takes its own). */
  def pipe: rtaccel.fp.Stager = pipes.pipe
  /** The view the IU's arithmetic pipes take: only what shapes them. */
  lazy val pipes: rtaccel.iu.PipeParams = rtaccel.iu.PipeParams(m, tuBits, boxFormat, boxSlackUlps, triTest, triFormat, divStages,
    stageBudget, stageBudget.map(_ => dspShape), stageBudget.flatMap(_ => delayRamCycles),
    stageBudget.fold(rtaccel.fp.Depth.LutInputs)(_ => rtaccel.area.Timing.forFamily(family).lutInputs), triInterval, boxInterval)
  /** The view a node's way into the box pipe takes (iu.NodeJob, iu.NodeDecode). */
  lazy val nodes: rtaccel.iu.NodeParams = rtaccel.iu.NodeParams(pipes, nodeQuantBits, nodeSlotBytes)
  /** The view a traversal unit takes (tu.TraversalUnit and its stacks). */
  lazy val traversal: rtaccel.tu.TuParams = rtaccel.tu.TuParams(pipes, refs.refBits, stackDepth, shortStack, treeLevels, hw.stepBits, rayStore)
  /** The view the packed leaves' assembly takes (iu.LeafAssembler). */
  lazy val leaves: rtaccel.iu.LeafParams = rtaccel.iu.LeafParams(pipes, refs.countBits)
  /** With a budget, on a family without shift-register LUTs (boards/timing.json `delay_ram_cycles`): delays of at
    * least this many cycles in LUT RAM (fp.Stager.chain). */
  lazy val delayRamCycles: Option[Int] = rtaccel.area.Timing.forFamily(family).delayRamCycles
  val cyclesPerSecond: Double = clockMhz * 1e6
  /** Sustained DRAM bytes per cycle of ONE channel: MEM_GBPS is per channel, since each of the MEM_CHANNELS is an
    * AXI4 master with a DRAM of its own, and the simulator models each channel alone (sim.DramModel at this rate).
    */
  val memBytesPerCycle: Double = memory.bytesPerSecond * memory.sustainedEfficiency / cyclesPerSecond
  /** Peak DRAM bytes per second over ALL channels: address interleaving spreads the accesses over every channel,
    * so the platform's bandwidth is the channels' sum. The one place that scales MEM_GBPS by MEM_CHANNELS: the
    * figures of the whole platform (bandwidth bounds, roofline, throughput model, utilisation) derive from it.
    */
  val memPeakBytesPerSecondTotal: Double = memory.bytesPerSecond * memChannels
  /** Its sustained share (MemoryParams.sustainedEfficiency), what the DRAM model delivers over all channels. */
  val memBytesPerSecondTotal: Double = memPeakBytesPerSecondTotal * memory.sustainedEfficiency
}

object PlatformParams {
  /** MEM_RETRIES' largest value: the register map's field (FORMATS2.MEM_RETRIES) has two bits. A transient error
    * clears on the first re-read; more re-reads only delay the flag of an error that stays. */
  val MaxMemRetries = 3
  /** TRI_II's largest value: a slot64 primitive is four beats of a 128-bit bus (INTERVALS.TRI_II has four bits). */
  val MaxTriInterval = 4
  /** BOX_II's largest value: an M=8 node of fp32 planes is eight beats of a 256-bit bus. */
  val MaxBoxInterval = 8
}
