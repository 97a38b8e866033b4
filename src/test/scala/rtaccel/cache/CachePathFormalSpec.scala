package rtaccel.cache

import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.config.{CacheParams, CachePolicy}
import rtaccel.formal.{EnvBounds, FormalChecks}

/** Bounded proofs of the cache path's answer properties (CachePathFormal, docs/formal.md): 4 sets of 1 way
  * (direct-mapped) and 4 sets of 2 ways (true LRU), with 16 distinct lines requested (4 per set, so hits, misses,
  * conflicts and evictions all occur), every memory and consumer stall of up to `stall` cycles. make test checks
  * `depth` cycles; make regress goes deeper and adds unbounded stalls.
  */
class CachePathFormalSpec extends AnyFlatSpec with FormalChecks {
  behavior of "CachePath (bounded proof)"
  val stall = 1
  val answerBound = CachePathFormalSpec.answerBound
  val live = EnvBounds(Some(stall), Some(stall))
  // (name, cache, depth in make test (0: make regress only), depth in make regress): the solver's time grows
  // steeply with the depth (Yices: the DM path 12 s at 14 cycles, 49 s at 16; z3 did not finish the 2-way LRU at 6
  // in 2 minutes, Yices proves it at 8 in a second: docs/formal.md)
  // (each + `slices`: the cycles PIPELINE's registers add to a hit, so a proof reaches the same behaviour)
  private val slices = CachePathFormalSpec.slices
  // (make test's DM depth takes the tagged path's slices, one cycle short of the in-order head register's: Yices
  // proves 14 cycles in about 12 s, 15 in about 70 s; make regress goes the whole way)
  val configs = Seq(("direct-mapped, 4 sets", CacheParams(4, 1, CachePolicy.Dm), 12 + CachePathFormalSpec.taggedSlices, 14 + slices),
    ("2-way LRU, 4 sets", CacheParams(8, 2, CachePolicy.Lru), 6 + slices, 6 + slices))

  for ((name, c, quick, deep) <- configs if regress || quick > 0) {
    val depth = if (regress) deep else quick
    it should s"answer each request once, in order, with the memory's data, within $answerBound cycles: $name" in
      prove(new CachePathFormal(c, live, answerBound), depth)
    if (regress) it should s"answer once, in order, with the memory's data under unbounded stalls: $name" in
      prove(new CachePathFormal(c, EnvBounds(None, None), answerBound), depth)
  }

  val dm = configs.head._2
  val depth = configs.head._3
  // (a lost `last` took z3 about 80 s to show at this depth, Yices a second)
  for (bug <- Seq(PathBug.Spurious, PathBug.Corrupt, PathBug.NoLast))
    it should s"find a counterexample to a ${bug.name}" in refute(new CachePathFormal(dm, live, answerBound, bug), depth)

  // TAG_FORWARD=1 (one lookup per cycle, the set just written forwarded to the next decision): the same properties,
  // and the mutant on read-first tag RAMs (a lookup that sees the set before the decision just taken) must fail them.
  // Depth 14 is the shortest at which that mutant fails (a line filled, evicted by the next lookup and asked for by
  // the one after: a hit on the other line's data, out at cycle 14), so the proof reaches the hazard; its
  // refutation takes z3 about 2 minutes: make regress. make test proves it 2 cycles short of that (the in-order
  // path's depth, 12 + slices: 15 s against 65 s at the full depth)
  val fwdDepth = if (regress) CachePathFormalSpec.forwardDepth else configs.head._3
  it should s"answer each request once, in order, with the memory's data, within $answerBound cycles, one lookup per cycle (TAG_FORWARD=1): direct-mapped, 4 sets" in
    prove(new CachePathFormal(dm, live, answerBound, forward = true), fwdDepth)
  if (regress) it should "find a counterexample to one lookup per cycle without forwarding (read-first tag RAM)" in
    refute(new CachePathFormal(dm, live, answerBound, PathBug.NoForward, forward = true), fwdDepth)

  // RESP_ORDER=tagged (hits under misses): two requesters, answers in any order; each request answered once, its
  // beats back to back, with the memory's data, within answerBound cycles (CachePathFormal, tagged)
  val taggedConfigs = Seq(("direct-mapped, 4 sets", dm, CachePathFormalSpec.taggedDepth, CachePathFormalSpec.taggedDepth),
    ("2-way LRU, 4 sets", configs(1)._2, 0, 6 + CachePathFormalSpec.taggedSlices))
  for ((name, c, quick, deep) <- taggedConfigs if regress || quick > 0) {
    val d = if (regress) deep else quick
    it should s"answer each tagged request once, back to back, with the memory's data, within ${CachePathFormalSpec.taggedBound} cycles, in any order: $name" in
      prove(new CachePathFormal(c, live, CachePathFormalSpec.taggedBound, tagged = true), d)
  }
  // (a lost `last` needs a longer trace than depth 8 to show: it is refuted on the in-order path above)
  for (bug <- Seq(PathBug.Spurious, PathBug.Corrupt))
    it should s"find a counterexample to a ${bug.name} with tagged answers" in
      refute(new CachePathFormal(dm, live, CachePathFormalSpec.taggedBound, bug, tagged = true), CachePathFormalSpec.taggedDepth)
}

object CachePathFormalSpec {
  /** cycles PIPELINE's registers add to a hit of the proofs' cache path (rtaccel.cache.hw.CachePath) */
  val slices: Int = CachePathFormal.platform(CacheParams(4, 1, CachePolicy.Dm)).cacheSliceCycles
  /** cycles from acceptance to the last beat of the answer the proofs promise (stalls of at most one cycle); in request
    * order with PIPELINE the head ticket's register holds one request more ahead of a new one: its two beats, each
    * stalled a cycle (CachePath) */
  val answerBound: Int = 16 + slices + (if (slices > 0) 4 else 0)
  /** the TAG_FORWARD=1 proof's depth in make regress (make test: the in-order path's) */
  val forwardDepth: Int = 14 + slices
  /** cycles PIPELINE's registers add to a clean tagged hit (the head ticket's register is on the other tickets' way) */
  val taggedSlices: Int = CachePathFormal.platform(CacheParams(4, 1, CachePolicy.Dm), tagged = true).cacheSliceCycles
  /** answerBound with tagged answers (the head ticket's register and the fill check's cycle fit it: 10,000 random
    * cycles, CachePathSimSpec) */
  val taggedBound: Int = 16 + taggedSlices
  /** the tagged proofs' depth in make test */
  val taggedDepth: Int = 8 + taggedSlices
}
