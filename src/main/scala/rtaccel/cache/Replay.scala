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
  def node(ray: Int, id: Int, level: Int): Unit = {
    nodeAccesses += 1
    val hit = nodeCache match { case Some(c) => c.access(id, level); case None => false }
    if (!hit) nodeDramBytes += nodeBytes
  }
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = {
    leafAccesses += 1; primTests += count
    val bytes = leafBytes(count); primBytesAll += bytes
    val hit = primCache match { case Some(c) => c.access(firstPrim, level); case None => false }
    if (!hit) primDramBytes += bytes
  }
}

/** IUS > 1: each IU cluster has its own caches (rtaccel.top.RtAccelTop). `cluster` says whose caches the next
  * access goes to; `total` is the platform's view, the clusters' counts summed (what the RTL's counters show).
  */
final class ClusterSinks(p: rtaccel.config.PlatformParams) extends AccessSink {
  val sinks: IndexedSeq[CacheSink] = IndexedSeq.fill(p.ius)(CacheSink(p))
  var cluster = 0
  def node(ray: Int, id: Int, level: Int): Unit = sinks(cluster).node(ray, id, level)
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = sinks(cluster).leaf(ray, firstPrim, count, level)
  /** A sink holding the sums of every cluster's counters (its caches' contents are empty; only counts are meant). */
  def total: CacheSink = if (sinks.length == 1) sinks.head else {
    val t = CacheSink(p)
    t.nodeAccesses = sinks.map(_.nodeAccesses).sum; t.leafAccesses = sinks.map(_.leafAccesses).sum
    t.nodeDramBytes = sinks.map(_.nodeDramBytes).sum; t.primDramBytes = sinks.map(_.primDramBytes).sum
    t.primTests = sinks.map(_.primTests).sum; t.primBytesAll = sinks.map(_.primBytesAll).sum
    t.nodeCache.foreach(_.addCounts(sinks.flatMap(_.nodeCache))); t.primCache.foreach(_.addCounts(sinks.flatMap(_.primCache)))
    t
  }
}

object CacheSink {
  /** The node and primitive cache models of a configuration (None where entries = 0). The primitive cache's
    * lines hold one leaf of up to MPPL primitives. Throws on bad geometry.
    */
  def apply(p: rtaccel.config.PlatformParams): CacheSink = new CacheSink(
    if (p.nodeCache.entries > 0) Some(new CacheModel(p.nodeCache, code(p))) else None,
    if (p.primCache.entries > 0) Some(new CacheModel(p.primCache, code(p), identity, p.mppl)) else None,
    p.nodeAccessBytes, p.leafBytes)
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
    */
  def refs(log: Array[Int], codec: rtaccel.bvh.RefCodec, sink: AccessSink): Unit = {
    var i = 0
    while (i < log.length) {
      val r = log(i)
      if (codec.isPrim(r)) sink.leaf(-1, codec.firstPrim(r), codec.count(r), 0)
      else sink.node(-1, codec.nodeId(r), codec.level(r))
      i += 1
    }
  }

  def interleaved(rows: Array[Int], tus: Int, sink: AccessSink): Unit = interleaved(rows, tus, sink, _ => ())

  /** The same for IU clusters: slot s is TU s, of cluster s / tusPerIu; each cluster's accesses go to its own caches. */
  def clustered(rows: Array[Int], p: rtaccel.config.PlatformParams, sinks: ClusterSinks): Unit =
    interleaved(rows, p.tus, sinks, s => sinks.cluster = s / p.tusPerIu)

  /** `select(s)` runs before slot s issues its access (IU clusters route it to their caches). */
  def interleaved(rows: Array[Int], tus: Int, sink: AccessSink, select: Int => Unit): Unit = {
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
        select(s)
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
