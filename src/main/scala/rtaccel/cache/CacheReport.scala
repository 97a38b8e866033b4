package rtaccel.cache

import rtaccel.bvh.RefCodec
import rtaccel.config.{CacheParams, PlatformParams}

/** The `node_cache` / `prim_cache` objects of make simulate: the RTL's counters beside the trace model fed
  * (a) the RTL's own logged access order, which must give exactly the same counts, and (b) the model's own
  * N-TU interleaving (Replay.interleaved), which is what make cachesim predicts without the RTL.
  */
object CacheReport {
  final case class Report(node: ujson.Value, prim: ujson.Value, matches: ujson.Value)

  /** `refetched(m)`: MC m's logged refetches of poisoned lines, each (path << 31 | its index among the path's lookups),
    * as SimHarness writes them. */
  def simulate(p: PlatformParams, counters: Map[String, Long], logged: Seq[Array[Int]], rows: Array[Int], codec: RefCodec,
               refetched: Seq[Array[Int]] = Nil): Report = {
    val cached = p.nodeCache.entries > 0 || p.primCache.entries > 0
    if (!cached) return Report(absent, absent, ujson.Null)
    require(logged.length == p.memControllers, s"one access log per MC: ${logged.length} logs for IUS=${p.ius} NODE_BANKS=${p.nodeBanks}")
    // each cluster's caches replay that cluster's own log; the RTL's counters are the clusters' sums. NODE_BANKS: the
    // logs after the clusters' are the node banks', each the order its bank saw, replayed into the one shared node
    // cache model (banked as the RTL is: each bank's sets see exactly that bank's order)
    val clusters = new ClusterSinks(p)
    for ((log, c) <- logged.zipWithIndex) {
      val words = refetched.lift(c).getOrElse(Array.empty[Int])
      val byPath = Seq(0, 1).map(path => words.filter(w => (w >>> 31) == path).map(w => (w & 0x7fffffff).toLong).toSet)
      Replay.refs(log, codec, clusters.sinks(math.min(c, p.ius - 1)), byPath)
    }
    val same = clusters.total; val geometry = clusters.sinks.head // the clusters' caches are alike
    val interC = new ClusterSinks(p); Replay.clustered(rows, p, interC); val inter = interC.total
    var ok = clusters.sinks.forall(_.refetchesOnMiss == 0)
    def one(name: String, c: CacheParams, g: Option[CacheModel], sameM: Option[CacheCounts], interM: Option[CacheCounts]): ujson.Value = (g, sameM, interM) match {
      case (Some(g), Some(s), Some(i)) =>
        val h = counters(s"${name}_cache_hits"); val m = counters(s"${name}_cache_misses"); val b = counters(s"${name}_cache_bypasses")
        ok &&= h == s.hits && m == s.misses && b == s.bypasses
        ujson.Obj("entries" -> c.entries, "lines" -> g.lines, "ways" -> c.ways, "policy" -> c.policy.name, "max_level" -> c.maxLevel,
          "hits" -> h.toDouble, "misses" -> m.toDouble, "bypasses" -> b.toDouble,
          "miss_rate" -> (if (h + m == 0) 0.0 else m.toDouble / (h + m)),
          "model_same_order" -> ujson.Obj("hits" -> s.hits.toDouble, "misses" -> s.misses.toDouble, "bypasses" -> s.bypasses.toDouble),
          "model_interleaved" -> ujson.Obj("tus" -> p.tus, "ius" -> p.ius, "hits" -> i.hits.toDouble, "misses" -> i.misses.toDouble,
            "miss_rate" -> i.missRate))
      case _ => absent
    }
    val node = one("node", p.nodeCache, geometry.nodeCache, same.nodeCache, inter.nodeCache)
    val prim = one("prim", p.primCache, geometry.primCache, same.primCache, inter.primCache)
    Report(node, prim, ujson.Bool(ok))
  }

  def absent: ujson.Value = ujson.Obj("entries" -> 0, "hits" -> 0, "misses" -> 0, "bypasses" -> 0)
}
