package rtaccel.config

/** Named design points. A sweep is a list of `preset.copy(...)`. */
object Presets {
  /** The board of the paper: QBVH, MPPL 4, 32 TUs at 150 MHz, queue 64, 2^13-entry direct-mapped node
    * cache, DDR2 at 1.2 GB/s peak (~50% sustained), fixed 32-bit references.
    */
  val paper2017: PlatformParams = PlatformParams(
    name = "paper2017", tus = 32, m = 4, mppl = 4, stackDepth = 64, clockMhz = 150.0,
    refs = RefFormat(nodeIdBits = 31, primIndexBits = 27, countBits = 4, levelBits = 0),
    nodeCache = CacheParams(entries = 8192, ways = 1, policy = CachePolicy.Dm),
    memory = MemoryParams(bytesPerSecond = 1.2e9, sustainedEfficiency = 0.5)
  )

  /** Paper Section 7.2: level field in bits 30..27 of a node reference, node id in 26..0. */
  val paper2017Lrp: PlatformParams = paper2017.copy(
    name = "paper2017-lrp",
    refs = RefFormat(nodeIdBits = 27, primIndexBits = 27, countBits = 4, levelBits = 4),
    nodeCache = CacheParams(entries = 8192, ways = 1, policy = CachePolicy.Lrp, maxLevel = 4)
  )

  /** A small platform for quick simulations and unit tests; widths are fitted per scene. */
  val small: PlatformParams = PlatformParams(name = "small", tus = 4, m = 4, mppl = 4, stackDepth = 64)

  val all: Map[String, PlatformParams] = Seq(paper2017, paper2017Lrp, small).map(p => p.name -> p).toMap

  def byName(name: String): PlatformParams = all.getOrElse(name,
    throw new rtaccel.io.InputError(s"unknown CONFIG '$name'; choose one of ${all.keys.toSeq.sorted.mkString(", ")}"))
}
