package rtaccel.cache

/** What one cache counted, without its contents: one cluster's cache, or the sum over the IU clusters' caches
  * (what the RTL's counters show), which has no contents of its own to hold.
  */
final case class CacheCounts(hits: Long, misses: Long, bypasses: Long) {
  def accesses: Long = hits + misses
  def missRate: Double = if (accesses == 0) 0.0 else misses.toDouble / accesses
  def +(o: CacheCounts): CacheCounts = CacheCounts(hits + o.hits, misses + o.misses, bypasses + o.bypasses)
}

object CacheCounts {
  def of(m: CacheModel): CacheCounts = CacheCounts(m.hits, m.misses, m.bypasses)
}

/** A CacheSink's counters without its caches (None where a cache is absent): one IU cluster's, or with `+` the
  * platform's sum (ClusterSinks.total), what make cachesim reports and the throughput model reads.
  */
final case class SinkCounts(nodeAccesses: Long, leafAccesses: Long, nodeDramBytes: Long, primDramBytes: Long, primTests: Long,
                            primBytesAll: Long, nodeCache: Option[CacheCounts], primCache: Option[CacheCounts]) {
  def +(o: SinkCounts): SinkCounts = {
    // the clusters are built alike, so a cache is present in both or in neither
    def sum(a: Option[CacheCounts], b: Option[CacheCounts]) = { require(a.isDefined == b.isDefined, "summing unlike sinks"); a.zip(b).map { case (x, y) => x + y } }
    SinkCounts(nodeAccesses + o.nodeAccesses, leafAccesses + o.leafAccesses, nodeDramBytes + o.nodeDramBytes,
      primDramBytes + o.primDramBytes, primTests + o.primTests, primBytesAll + o.primBytesAll,
      sum(nodeCache, o.nodeCache), sum(primCache, o.primCache))
  }
}
