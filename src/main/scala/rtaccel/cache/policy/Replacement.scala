package rtaccel.cache.policy

/** Replacement state of one cache set as a small integer, with pure transition functions so that the RTL can
  * tabulate them: next = touch(state, way) and victim(state) over all states of `stateBits` bits.
  * Rules (exact, see docs/caches.md):
  *  - an access that hits, and a fill, both `touch` the way;
  *  - a refused allocation (level policy bypass) leaves the state unchanged;
  *  - empty ways are filled first, lowest-numbered first; `victim` is consulted only when the set is full.
  */
trait ReplacementPolicy {
  def ways: Int
  def stateBits: Int
  def init: Int
  def touch(state: Int, way: Int): Int
  def victim(state: Int): Int
  /** States the transition functions can reach from `init` (the rows of the RTL table). */
  def states: Seq[Int]
}

private[policy] object Log2 {
  def exact(n: Int, what: String): Int = {
    require(n >= 1 && Integer.bitCount(n) == 1, s"$what must be a power of two (got $n)")
    Integer.numberOfTrailingZeros(n)
  }
  def ceil(n: Int): Int = if (n <= 1) 0 else 32 - Integer.numberOfLeadingZeros(n - 1)
}

/** One way, no state. */
object DirectMapped extends ReplacementPolicy {
  val ways = 1; val stateBits = 0; val init = 0
  def touch(state: Int, way: Int): Int = { require(way == 0, s"direct-mapped has one way (got $way)"); 0 }
  def victim(state: Int): Int = 0
  def states: Seq[Int] = Seq(0)
}

/** True LRU. State = the recency order as a list of way numbers, `w = ceil(log2 ways)` bits each:
  * field i (bits [i*w, i*w+w)) holds the way at recency position i, position 0 = most recently used,
  * position ways-1 = least recently used (the victim). init = order (ways-1, ..., 1, 0) from MRU to LRU,
  * so an untouched set evicts way 0 first, then 1, ... (matches fill-empty-lowest-first).
  * stateBits = ways * w (ways 2: 2 bits, 4: 8 bits, 8: 24 bits); only permutations are reachable.
  */
final case class TrueLru(ways: Int) extends ReplacementPolicy {
  require(ways >= 1 && ways <= 8, s"true LRU supports 1..8 ways in an Int state (got $ways)")
  private val w = Log2.ceil(ways)
  private val mask = (1 << w) - 1
  val stateBits: Int = ways * w
  @inline private def at(s: Int, i: Int): Int = (s >>> (i * w)) & mask
  val init: Int = (0 until ways).foldLeft(0)((s, i) => s | ((ways - 1 - i) << (i * w)))
  /** Moves `way` to position 0, shifting the more recent ones down by one position. */
  def touch(state: Int, way: Int): Int = {
    require(way >= 0 && way < ways, s"way $way out of 0..${ways - 1}")
    var pos = 0
    while (pos < ways && at(state, pos) != way) pos += 1
    require(pos < ways, s"state $state is not a permutation")
    val keepMask = if ((pos + 1) * w >= 32) 0 else -1 << ((pos + 1) * w)
    val below = state & ((1 << (pos * w)) - 1) // positions 0..pos-1
    (state & keepMask) | (below << w) | way
  }
  def victim(state: Int): Int = at(state, ways - 1)
  def states: Seq[Int] = (0 until ways).permutations.map(_.zipWithIndex.foldLeft(0) { case (s, (way, i)) => s | (way << (i * w)) }).toSeq
}

/** Tree pseudo-LRU over a power-of-two number of ways, ways-1 bits. Node k (heap numbering, root 1, children
  * 2k and 2k+1) is bit k-1 of the state; bit = 0 means the victim lies in the left (lower-numbered) half,
  * 1 the right half. touch(way) sets every bit on the way's path to point away from it; victim follows the
  * bits from the root. init = 0 (victim way 0).
  */
final case class TreePlru(ways: Int) extends ReplacementPolicy {
  private val levels = Log2.exact(ways, "PLRU ways")
  require(ways <= 32, s"tree PLRU supports up to 32 ways (got $ways)")
  val stateBits: Int = ways - 1
  val init = 0
  def touch(state: Int, way: Int): Int = {
    require(way >= 0 && way < ways, s"way $way out of 0..${ways - 1}")
    var s = state; var node = 1; var d = levels - 1
    while (d >= 0) {
      val dir = (way >>> d) & 1
      s = if (dir == 0) s | (1 << (node - 1)) else s & ~(1 << (node - 1))
      node = 2 * node + dir; d -= 1
    }
    s
  }
  def victim(state: Int): Int = {
    var node = 1; var way = 0; var d = 0
    while (d < levels) { val dir = (state >>> (node - 1)) & 1; way = 2 * way + dir; node = 2 * node + dir; d += 1 }
    way
  }
  def states: Seq[Int] = 0 until (1 << stateBits)
}

/** The level replacement policy (paper Section 7; our exact rule, Section 7.1 of our copy is missing).
  * Levels are first encoded as the hardware field of `bits` bits (paper: 4, so 0..14 as is, 15 and deeper as
  * 15), then put in a priority class: class(l) = min(l, maxLevel + 1). A missing line may replace the victim
  * only if its class is the same or higher (numerically <=) than the victim's; otherwise the access bypasses
  * the cache. Within one class the replacement policy (LRU) alone decides. An empty victim is always replaced.
  */
object LevelPolicy {
  final case class Code(bits: Int) {
    require(bits >= 1 && bits <= 6, s"level code must be 1..6 bits (got $bits)")
    val max: Int = (1 << bits) - 1
    def encode(level: Int): Int = if (level < 0) 0 else if (level > max) max else level
    def cls(level: Int, maxLevel: Int): Int = math.min(encode(level), maxLevel + 1)
    def allocate(victimLevel: Int, incomingLevel: Int, maxLevel: Int): Boolean =
      cls(incomingLevel, maxLevel) <= cls(victimLevel, maxLevel)
  }
  /** the paper's 4-bit code (PlatformParams.hw.levelCodeBits default) */
  val paper: Code = Code(4)
  def encode(level: Int): Int = paper.encode(level)
  def cls(level: Int, maxLevel: Int): Int = paper.cls(level, maxLevel)
  def allocate(victimLevel: Int, incomingLevel: Int, maxLevel: Int): Boolean = paper.allocate(victimLevel, incomingLevel, maxLevel)
}

object Policies {
  import rtaccel.config.CachePolicy._
  /** Replacement policy of one set for a cache policy. lrp uses true LRU (plus LevelPolicy on allocation),
    * hybrid's main array is direct-mapped, bf never replaces (its static buffer keeps DirectMapped's trivial state).
    */
  def of(policy: rtaccel.config.CachePolicy, ways: Int): ReplacementPolicy = policy match {
    case Dm | Bf | Hybrid =>
      require(ways == 1, s"policy '$policy' is direct-mapped/static: ways must be 1 (got $ways)"); DirectMapped
    case Lru | Lrp => if (ways == 1) DirectMapped else TrueLru(ways)
    case Plru => if (ways == 1) DirectMapped else TreePlru(ways)
  }
}
