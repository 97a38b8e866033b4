package rtaccel.cache

import rtaccel.config.PlatformParams

/** The fast model's rays/s prediction from a replayed access stream: mean value analysis (MVA) of a closed
  * network in which each of the N TUs holds one ray.
  *
  * Per ray, from the replay: a TU alone spends L cycles (its latency: per access a fixed pipeline overhead,
  * then for a miss the DRAM latency plus the transfer at the sustained rate, for a hit the beats from the
  * cache). Two shared resources serve every TU: DRAM (demand D = DRAM bytes / sustained bytes per cycle) and
  * the MC's one-beat-per-cycle response port (demand B = all beats, hits and misses). The rest,
  * Z = L - D - B, is pure delay. MVA gives the throughput of N rays in flight; with N = 1 it is 1 / L,
  * for large N it approaches 1 / max(D, B).
  *
  * `p.hw.cachePathCycles` is the extra latency of an access through a cache path (tag lookup, ticket queue, data
  * RAM, output queue), measured on the RTL at one TU (docs/caches.md: 7.5-8.8 cycles per access on sponza and
  * conference); an uncached path adds none (measured -1..0). Head-of-line blocking in the in-order MC (a hit
  * waiting behind another TU's miss) is not modelled: the prediction is optimistic at mid TU counts.
  */
object Throughput {

  final case class Prediction(latencyCycles: Double, dramCycles: Double, beatCycles: Double, raysPerCycle: Double)

  def mva(delay: Double, demands: Seq[Double], n: Int): Double = {
    require(n >= 1, s"TUs must be at least 1 (got $n)")
    var q = demands.map(_ => 0.0); var x = 0.0
    for (k <- 1 to n) {
      val r = demands.zip(q).map { case (d, qq) => d * (1 + qq) }
      x = k / (delay + r.sum)
      q = r.map(_ * x)
    }
    x
  }

  def predict(p: PlatformParams, s: CacheSink, rays: Int, tus: Int): Prediction = {
    val n = math.max(1, rays).toDouble
    val bpc = p.memBytesPerCycle
    val beatBytes = p.axiDataBits / 8.0
    val lat = p.memory.latencyCycles.toDouble
    val nodeMisses = s.nodeDramBytes / p.nodeAccessBytes.toDouble
    val leafMisses = s.primCache.fold(s.leafAccesses.toDouble)(_.misses.toDouble)
    val hitBytes = (s.nodeAccesses * p.nodeAccessBytes - s.nodeDramBytes) + (s.primBytesAll - s.primDramBytes)
    val cachePathCycles = p.hw.cachePathCycles
    val overhead = s.nodeCache.fold(0.0)(_ => cachePathCycles) * s.nodeAccesses + s.primCache.fold(0.0)(_ => cachePathCycles) * s.leafAccesses
    val latency = (nodeMisses * lat + leafMisses * lat + (s.nodeDramBytes + s.primDramBytes) / bpc + hitBytes / beatBytes + overhead) / n
    val dram = (s.nodeDramBytes + s.primDramBytes) / bpc / n
    val beats = (s.nodeAccesses * p.nodeAccessBytes + s.primBytesAll) / beatBytes / n
    Prediction(latency, dram, beats, mva(math.max(0.0, latency - dram - beats), Seq(dram, beats), tus))
  }
}
