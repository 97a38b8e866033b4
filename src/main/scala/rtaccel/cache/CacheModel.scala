package rtaccel.cache

import rtaccel.cache.policy.{LevelPolicy, Policies, ReplacementPolicy}
import rtaccel.config.{CacheParams, CachePolicy}

/** Trace-driven cache model (plain arrays, no allocation per access). `lines` lines of one request each
  * (node cache: one node; primitive cache: one leaf of up to MPPL primitives, so lines = CacheParams.lines(MPPL), via
  * `entriesPerLine`). A request's line id is `lineOf(id)`; set index = low log2(sets) bits of the line id,
  * tag = the rest (paper 6.2; the model keeps the whole line id as the tag).
  *
  * banks = k > 1 (NODE_BANKS, the shared node cache): k banks of lines / k lines each, a line in bank
  * (line mod k) at set (line / k) mod (sets / k) of that bank, as the RTL's banks see it (rtaccel.cache.hw.NodeBanks);
  * a bank's sets are kept contiguously, so the model is the RTL's structure set for set. With k dividing every
  * array's sets each line has one set either way, so the counts equal one unbanked cache fed each set's order.
  *
  * Policies (exact rules in docs/caches.md):
  *  - dm, lru, plru: plain set-associative cache (dm = 1 way), every miss fills.
  *  - lrp: LRU sets + LevelPolicy on the victim; a refused fill is a bypass (cache unchanged).
  *  - bf: static buffer preloaded with line ids 0 until lines (breadth-first ids = highest nodes), never replaced.
  *  - hybrid: direct-mapped array of `lines` lines plus an LRP side cache of max(1, lines/8) lines,
  *    min(4, side lines)-way true LRU. Hit in either is a hit; on a miss the DM line is replaced if it is empty or
  *    LevelPolicy.allocate(its level, incoming); otherwise the side cache is offered the line under LRP rules;
  *    refused there too = bypass.
  */
final class CacheModel(val c: CacheParams, code: LevelPolicy.Code, lineOf: Int => Int = identity, entriesPerLine: Int = 1,
                       val banks: Int = 1) {
  require(c.entries > 0, "CacheModel needs entries > 0 (0 means no cache)")
  require(entriesPerLine >= 1, "entries per line must be positive")
  val lines: Int = c.lines(entriesPerLine)
  require(Integer.bitCount(lines) == 1, s"cache lines ($lines) must be a power of two")
  val ways: Int = c.ways
  require(lines % ways == 0, s"cache ways ($ways) must divide its lines ($lines)")
  val policy: ReplacementPolicy = Policies.of(c.policy, ways)
  private val maxLevel = c.maxLevel
  val sets: Int = lines / ways
  require(banks >= 1 && Integer.bitCount(banks) == 1 && sets % banks == 0,
    s"$banks banks must be a power of two dividing the cache's $sets sets")
  private val bankBits = Integer.numberOfTrailingZeros(banks)
  /** the set of `line` in an array of `n` sets: bank (line mod banks), then (line / banks) mod (n / banks) in it */
  private def setIn(line: Int, n: Int): Int =
    if (banks == 1) line & (n - 1) else (line & (banks - 1)) * (n / banks) + ((line >>> bankBits) & (n / banks - 1))
  private val tags = Array.fill(lines)(-1) // line id, -1 = empty
  private val lvls = new Array[Int](lines)
  private val state = Array.fill(sets)(policy.init)
  private val isBf = c.policy == CachePolicy.Bf
  private val isLrp = c.policy == CachePolicy.Lrp
  private val isHybrid = c.policy == CachePolicy.Hybrid

  // hybrid side cache (LRP)
  val sideLines: Int = c.sideLines(lines)
  val sideWays: Int = c.sideWays(lines)
  private val side: ReplacementPolicy = if (isHybrid) Policies.of(CachePolicy.Lru, sideWays) else null
  private val sideSets = if (isHybrid) sideLines / sideWays else 0
  require(!isHybrid || sideSets % banks == 0, s"$banks banks must divide the hybrid side array's $sideSets sets")
  private val sTags = Array.fill(sideLines)(-1)
  private val sLvls = new Array[Int](sideLines)
  private val sState = Array.fill(sideSets)(if (isHybrid) side.init else 0)

  var hits = 0L; var misses = 0L; var bypasses = 0L

  def accesses: Long = hits + misses
  /** The RTL refetched the line the access just hit, because its data was poisoned (rtaccel.cache.hw.CachePath):
    * the hit counts as a miss; the replacement state stays as the hit left it, as in the RTL. */
  def countRefetch(): Unit = { hits -= 1; misses += 1 }
  def missRate: Double = if (accesses == 0) 0.0 else misses.toDouble / accesses

  /** One request; true on a hit. */
  def access(id: Int, level: Int): Boolean = {
    val line = lineOf(id)
    if (isBf) {
      if (line >= 0 && line < lines) { hits += 1; true } else { misses += 1; bypasses += 1; false }
    } else if (isHybrid) accessHybrid(line, level)
    else {
      val set = setIn(line, sets)
      val base = set * ways
      if (lookup(tags, state, policy, base, set, ways, line)) { hits += 1; return true }
      misses += 1
      if (!fill(tags, lvls, state, policy, base, set, ways, line, level, isLrp)) bypasses += 1
      false
    }
  }

  /** Looks `line` up in the set at `base`; a hit updates the set's replacement state. */
  private def lookup(tg: Array[Int], st: Array[Int], pol: ReplacementPolicy, base: Int, set: Int, nWays: Int,
                     line: Int): Boolean = {
    var w = 0
    while (w < nWays && tg(base + w) != line) w += 1
    if (w < nWays) st(set) = pol.touch(st(set), w)
    w < nWays
  }

  /** Fills `line` into the set at `base` (empty way first, lowest first; else the policy victim, subject to the
    * level policy when `lrp`). Returns false for a refused fill (bypass), which leaves everything unchanged.
    */
  private def fill(tg: Array[Int], lv: Array[Int], st: Array[Int], pol: ReplacementPolicy, base: Int, set: Int,
                   nWays: Int, line: Int, level: Int, lrp: Boolean): Boolean = {
    var w = 0
    while (w < nWays && tg(base + w) != -1) w += 1
    if (w == nWays) {
      w = pol.victim(st(set))
      if (lrp && !code.allocate(lv(base + w), level, maxLevel)) return false
    }
    tg(base + w) = line; lv(base + w) = level; st(set) = pol.touch(st(set), w)
    true
  }

  private def accessHybrid(line: Int, level: Int): Boolean = {
    val i = setIn(line, sets)
    if (tags(i) == line) { hits += 1; return true }
    val sset = setIn(line, sideSets)
    val sbase = sset * sideWays
    if (lookup(sTags, sState, side, sbase, sset, sideWays, line)) { hits += 1; return true }
    misses += 1
    if (tags(i) == -1 || code.allocate(lvls(i), level, maxLevel)) { tags(i) = line; lvls(i) = level }
    else if (!fill(sTags, sLvls, sState, side, sbase, sset, sideWays, line, level, lrp = true)) bypasses += 1
    false
  }

  /** Whether a line is currently held (for tests). */
  def contains(id: Int): Boolean = {
    val line = lineOf(id)
    if (isBf) line >= 0 && line < lines
    else {
      val base = setIn(line, sets) * ways
      (0 until ways).exists(w => tags(base + w) == line) ||
        (isHybrid && { val b = setIn(line, sideSets) * sideWays; (0 until sideWays).exists(w => sTags(b + w) == line) })
    }
  }
}
