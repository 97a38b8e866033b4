package rtaccel.config

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

/** Node-cache geometry and policy; entries = 0 means no cache. */
final case class CacheParams(entries: Int = 0, ways: Int = 1, policy: String = "dm", maxLevel: Int = 15) {
  require(entries == 0 || Integer.bitCount(entries) == 1, s"cache entries must be a power of two (got $entries)")
  require(ways >= 1 && (entries == 0 || entries % ways == 0), s"cache ways ($ways) must divide entries ($entries)")
  require(Set("dm", "lru", "plru", "lrp", "bf", "hybrid")(policy), s"unknown cache policy '$policy'; use dm|lru|plru|lrp|bf|hybrid")
  require(maxLevel >= 0 && maxLevel <= 15, s"MAX_LEVEL must be 0..15 (got $maxLevel)")
}

/** The one configuration object for the reference model, analysis and (later) the RTL generators.
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
  divStages: Int = 6
) {
  require(tus >= 1 && tus <= 1024, s"TUS must be in 1..1024 (got $tus)")
  require(Set(2, 4, 8)(m), s"M (MBVH width) must be 2, 4 or 8 (got $m)")
  require(mppl >= 1, s"MPPL must be at least 1 (got $mppl)")
  require(mppl <= refs.maxLeafPrims,
    s"MPPL $mppl does not fit the ${refs.countBits}-bit leaf count field (max ${refs.maxLeafPrims}); lower MPPL or widen countBits")
  require(stackDepth >= 1, s"stack depth must be at least 1 (got $stackDepth)")
  require(clockMhz > 0, "clock must be positive")
  require(sahBins >= 2, "SAH needs at least 2 bins")
  require(Seq(64, 128, 256, 512).contains(axiDataBits), s"AXI data width must be 64, 128, 256 or 512 bits (got $axiDataBits)")
  require(divStages >= 0 && divStages <= 32, s"divider pipeline stages must be 0..32 (got $divStages)")

  /** Bytes one node occupies: M x (6 floats + ref) = 28*M, rounded up to a power of two so a node id
    * maps to an address by a shift (QBVH: 112 B stored in 128 B, as in the paper).
    */
  val nodeBits: Int = m * 7 * 32
  val nodeStrideBytes: Int = Integer.highestOneBit(nodeBits / 8 - 1) << 1
  /** A primitive is 9 floats (288 bits); its 64-byte slot also carries the original triangle id. */
  val primBits: Int = 9 * 32
  val primStrideBytes: Int = 64
  /** Bytes one node fetch moves (paper: 128 B for QBVH); defaults to the node's stored size. */
  val nodeAccessBytes: Int = if (nodeAccessBytesOverride > 0) nodeAccessBytesOverride else nodeStrideBytes
  require(nodeAccessBytes >= nodeBits / 8, s"node access of $nodeAccessBytes B is smaller than a node (${nodeBits / 8} B); raise the node access size")
  val tuBits: Int = math.max(1, 32 - Integer.numberOfLeadingZeros(tus - 1))
  val cyclesPerSecond: Double = clockMhz * 1e6
  val memBytesPerCycle: Double = memory.bytesPerSecond * memory.sustainedEfficiency / cyclesPerSecond
}
