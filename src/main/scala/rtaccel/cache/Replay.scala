package rtaccel.cache

import rtaccel.model.AccessSink

/** Node and primitive caches in front of DRAM, fed with traversal accesses. Either may be absent (None).
  * Counts the DRAM traffic left after the caches: a node miss moves `nodeBytes`, a leaf miss moves
  * `leafBytes(count)` (the leaf's primitives, PlatformParams.leafBytes), as in make trace's bytes per ray.
  */
final class CacheSink(val nodeCache: Option[CacheModel], val primCache: Option[CacheModel], nodeBytes: Int, leafBytes: Int => Long)
    extends AccessSink {
  var nodeAccesses = 0L; var leafAccesses = 0L
  var nodeDramBytes = 0L; var primDramBytes = 0L
  var primTests = 0L
  /** Primitive bytes of every leaf access, cached or not (what DRAM would move without the primitive cache). */
  var primBytesAll = 0L
  /** Lookups the RTL refetched (a poisoned line) that the model did not hit: the replay went astray. */
  var refetchesOnMiss = 0L
  private def lookup(c: Option[CacheModel], id: Int, level: Int, refetch: Boolean): Boolean = c match {
    case Some(m) =>
      val hit = m.access(id, level)
      if (refetch && !hit) refetchesOnMiss += 1
      if (refetch && hit) { m.countRefetch(); false } else hit
    case None => false
  }
  def node(ray: Int, id: Int, level: Int): Unit = node(ray, id, level, refetch = false)
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = leaf(ray, firstPrim, count, level, refetch = false)
  /** `refetch`: the RTL's lookup found the line poisoned and read it again (CacheReport replays the RTL's log) */
  def node(ray: Int, id: Int, level: Int, refetch: Boolean): Unit = {
    nodeAccesses += 1
    val hit = lookup(nodeCache, id, level, refetch)
    if (!hit) nodeDramBytes += nodeBytes
  }
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int, refetch: Boolean): Unit = {
    leafAccesses += 1; primTests += count
    val bytes = leafBytes(count); primBytesAll += bytes
    val hit = lookup(primCache, firstPrim, level, refetch)
    if (!hit) primDramBytes += bytes
  }
  def counts: SinkCounts = SinkCounts(nodeAccesses, leafAccesses, nodeDramBytes, primDramBytes, primTests, primBytesAll,
    nodeCache.map(CacheCounts.of), primCache.map(CacheCounts.of))
}

/** IUS > 1: each IU cluster has its own caches (rtaccel.top.RtAccelTop); `sinks(c)` is cluster c's.
  * NODE_BANKS > 0: the clusters share one banked node cache (`shared`, in every cluster's sink) and keep their own
  * primitive caches.
  */
final class ClusterSinks(p: rtaccel.config.PlatformParams) {
  val shared: Option[CacheModel] = if (p.nodeShared) CacheSink.nodeModel(p) else None
  val sinks: IndexedSeq[CacheSink] = IndexedSeq.fill(p.ius)(shared.fold(CacheSink(p))(s => CacheSink(p, Some(s))))
  /** The platform's view: the clusters' counts summed (what the RTL's counters show); a shared node cache once. */
  def total: SinkCounts = {
    val t = sinks.map(_.counts).reduce(_ + _)
    shared.fold(t)(s => t.copy(nodeCache = Some(CacheCounts.of(s))))
  }
}

object CacheSink {
  /** The node and primitive cache models of a configuration (None where entries = 0). The primitive cache's
    * lines hold one leaf of up to MPPL primitives. Throws on bad geometry.
    */
  def apply(p: rtaccel.config.PlatformParams): CacheSink = apply(p, nodeModel(p))
  /** The same with a given node cache model (NODE_BANKS: the one every cluster shares). */
  def apply(p: rtaccel.config.PlatformParams, node: Option[CacheModel]): CacheSink = new CacheSink(node,
    if (p.primCache.entries > 0) Some(new CacheModel(p.primCache, code(p), identity, p.mppl)) else None,
    p.nodeAccessBytes, p.leafBytes)
  /** The node cache model of a configuration (None without one): NODE_BANKS > 0 banks it as the RTL does. */
  def nodeModel(p: rtaccel.config.PlatformParams): Option[CacheModel] =
    if (p.nodeCache.entries > 0) Some(new CacheModel(p.nodeCache, code(p), identity, 1, math.max(1, p.nodeBanks))) else None
  /** the level code the platform's caches use */
  def code(p: rtaccel.config.PlatformParams): rtaccel.cache.policy.LevelPolicy.Code = rtaccel.cache.policy.LevelPolicy.Code(p.hw.levelCodeBits)
}

/** Replays a recorded access trace (AccessRecorder rows: ray, kind, id/first, level, count) into a sink.
  *
  * Model of N traversal units: N ray slots are active at once; the replay visits slots round-robin and issues
  * ONE access (node or leaf) of the slot's ray per visit, in that ray's own (single-TU) order. When a ray's last
  * access has been issued, the slot takes the next ray not yet started (rays in file order) at its next visit.
  * The replay ends when every ray is finished. N = 1 is exactly the per-ray order of one TU.
  * This ignores timing (a TU waiting on a miss, leaves taking longer than nodes): it models the interleaving
  * of N concurrent rays' access streams at a shared cache, not cycle-accurate arbitration.
  */
object Replay {
  /** Replays child references in the order the RTL's memory controller accepted them (its access log): node
    * refs carry their level field (the cache model saturates it to its level code, as the MC does for the RTL
    * caches), leaf refs their first slot and count. Ray numbers are not in the log (-1).
    * `refetched(path)`: the indices, among that path's lookups (FetchPath.Node / Prim), of those the RTL's cache
    * turned into refetches of a poisoned line (SimHarness logs them).
    */
  def refs(log: Array[Int], codec: rtaccel.bvh.RefCodec, sink: AccessSink,
           refetched: Seq[Set[Long]] = Seq(Set.empty, Set.empty)): Unit = {
    var i = 0
    val k = Array(0L, 0L)
    while (i < log.length) {
      val r = log(i)
      val path = if (codec.isPrim(r)) rtaccel.mc.FetchPath.Prim else rtaccel.mc.FetchPath.Node
      val refetch = refetched(path)(k(path)); k(path) += 1
      (sink, path) match {
        case (c: CacheSink, rtaccel.mc.FetchPath.Prim) => c.leaf(-1, codec.firstPrim(r), codec.count(r), 0, refetch)
        case (c: CacheSink, _) => c.node(-1, codec.nodeId(r), codec.level(r), refetch)
        case (s, rtaccel.mc.FetchPath.Prim) => require(!refetch, "refetches replay into cache models only"); s.leaf(-1, codec.firstPrim(r), codec.count(r), 0)
        case (s, _) => require(!refetch, "refetches replay into cache models only"); s.node(-1, codec.nodeId(r), codec.level(r))
      }
      i += 1
    }
  }

  /** One TU's order (tus = 1) or `tus` TUs interleaved, every access into `sink`. */
  def interleaved(rows: Array[Int], tus: Int, sink: AccessSink): Unit = slots(rows, Array.fill(math.max(0, tus))(sink))

  /** The same for IU clusters: slot s is TU s, of cluster s / tusPerIu; each cluster's accesses go to its own caches. */
  def clustered(rows: Array[Int], p: rtaccel.config.PlatformParams, sinks: ClusterSinks): Unit =
    slots(rows, Array.tabulate(p.tus)(s => sinks.sinks(s / p.tusPerIu)))

  /** The round-robin over slotSinks.length TU slots, slot s issuing into slotSinks(s): the route of an access
    * is fixed per slot, so the loop looks up no cluster per access.
    */
  def slots(rows: Array[Int], slotSinks: Array[AccessSink]): Unit = {
    val tus = slotSinks.length
    require(tus >= 1, s"TUS must be at least 1 (got $tus)")
    val n = rows.length / 5
    // start row of each run of consecutive rows with the same ray (traversal records rays one after another)
    val startsB = Array.newBuilder[Int]
    var r = 0
    while (r < n) { if (r == 0 || rows(5 * r) != rows(5 * (r - 1))) startsB += r; r += 1 }
    val starts = startsB.result()
    val nRays = starts.length
    def end(k: Int): Int = if (k + 1 < nRays) starts(k + 1) else n
    val pos = Array.fill(tus)(-1); val stop = Array.fill(tus)(-1)
    var next = 0; var active = 0
    var s = 0
    while (s < tus && next < nRays) { pos(s) = starts(next); stop(s) = end(next); next += 1; active += 1; s += 1 }
    s = 0
    while (active > 0) {
      if (pos(s) >= 0) {
        val b = 5 * pos(s)
        val sink = slotSinks(s)
        if (rows(b + 1) == 0) sink.node(rows(b), rows(b + 2), rows(b + 3))
        else sink.leaf(rows(b), rows(b + 2), rows(b + 4), rows(b + 3))
        pos(s) += 1
        if (pos(s) == stop(s)) {
          if (next < nRays) { pos(s) = starts(next); stop(s) = end(next); next += 1 }
          else { pos(s) = -1; active -= 1 }
        }
      }
      s += 1; if (s == tus) s = 0
    }
  }
}
