package rtaccel.cli

import rtaccel.bvh.RefCodec
import rtaccel.cache.{CacheModel, CacheSink, Replay}
import rtaccel.config.{CacheParams, PlatformParams}

/** The `node_cache` / `prim_cache` objects of make simulate: the RTL's counters beside the trace model fed
  * (a) the RTL's own logged access order, which must give exactly the same counts, and (b) the model's own
  * N-TU interleaving (Replay.interleaved), which is what make cachesim predicts without the RTL.
  */
object CacheReport {
  final case class Report(node: ujson.Value, prim: ujson.Value, matches: ujson.Value)

  def simulate(p: PlatformParams, counters: Map[String, Long], logged: Array[Int], rows: Array[Int], codec: RefCodec): Report = {
    val cached = p.nodeCache.entries > 0 || p.primCache.entries > 0
    if (!cached) return Report(absent, absent, ujson.Null)
    val same = CacheSink(p); Replay.refs(logged, codec, same)
    val inter = CacheSink(p); Replay.interleaved(rows, p.tus, inter)
    var ok = true
    def one(name: String, c: CacheParams, sameM: Option[CacheModel], interM: Option[CacheModel]): ujson.Value = (sameM, interM) match {
      case (Some(s), Some(i)) =>
        val h = counters(s"${name}_cache_hits"); val m = counters(s"${name}_cache_misses"); val b = counters(s"${name}_cache_bypasses")
        ok &&= h == s.hits && m == s.misses && b == s.bypasses
        ujson.Obj("entries" -> c.entries, "lines" -> s.lines, "ways" -> c.ways, "policy" -> c.policy.name, "max_level" -> c.maxLevel,
          "hits" -> h.toDouble, "misses" -> m.toDouble, "bypasses" -> b.toDouble,
          "miss_rate" -> (if (h + m == 0) 0.0 else m.toDouble / (h + m)),
          "model_same_order" -> ujson.Obj("hits" -> s.hits.toDouble, "misses" -> s.misses.toDouble, "bypasses" -> s.bypasses.toDouble),
          "model_interleaved" -> ujson.Obj("tus" -> p.tus, "hits" -> i.hits.toDouble, "misses" -> i.misses.toDouble,
            "miss_rate" -> i.missRate))
      case _ => absent
    }
    val node = one("node", p.nodeCache, same.nodeCache, inter.nodeCache)
    val prim = one("prim", p.primCache, same.primCache, inter.primCache)
    Report(node, prim, ujson.Bool(ok))
  }

  def absent: ujson.Value = ujson.Obj("entries" -> 0, "hits" -> 0, "misses" -> 0, "bypasses" -> 0)
}
