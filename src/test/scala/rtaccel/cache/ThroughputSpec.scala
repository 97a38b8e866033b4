package rtaccel.cache

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.cache.policy.LevelPolicy
import rtaccel.config.{CacheParams, CachePolicy, HwLimits, Presets}

class ThroughputSpec extends AnyFunSuite {
  test("MVA: one ray in flight takes the whole latency; many approach the busiest resource, never beyond") {
    val (z, d, b) = (300.0, 137.0, 95.0)
    assert(math.abs(Throughput.mva(z, Seq(d, b), 1) - 1 / (z + d + b)) < 1e-15)
    val xs = (1 to 64).map(n => Throughput.mva(z, Seq(d, b), n))
    assert(xs.zip(xs.tail).forall { case (a, c) => c >= a }, "throughput must not fall with more TUs")
    assert(xs.forall(_ <= 1 / d + 1e-12))
    assert(xs.last > 0.99 / d)
    // a pure delay (no shared resource) scales linearly
    assert(math.abs(Throughput.mva(100.0, Seq(0.0), 8) - 8 / 100.0) < 1e-12)
  }

  test("latency and demands from the replay: uncached stream by hand, and a cache adds its path latency") {
    val p = Presets.paper2017 // 128 B nodes, 64 B primitives, 40 cycles latency, 4 B/cycle sustained, 32 B beats
    def sink(cached: Boolean) = {
      val s = new CacheSink(if (cached) Some(new CacheModel(CacheParams(8, 1, CachePolicy.Dm), LevelPolicy.paper)) else None, None, 128, c => c * 64L)
      for (r <- 0 until 2) { s.node(r, 0, 0); s.node(r, 1, 1); s.leaf(r, 0, 3, 2) } // 2 rays: 2 nodes + a 3-prim leaf each
      s
    }
    val u = Throughput.predict(p, sink(cached = false), rays = 2, tus = 1)
    // per ray: 2 node misses x (40 + 32) + 1 leaf x 40 + 192 B / 4 = 144 + 40 + 48
    assert(u.latencyCycles == 232.0)
    assert(u.dramCycles == (2 * 128 + 192) / 4.0)
    assert(u.beatCycles == (2 * 128 + 192) / 32.0)
    assert(math.abs(u.raysPerCycle - 1 / 232.0) < 1e-15)
    // ray 2's nodes hit (4 beats each instead of a DRAM trip); both rays pay the cache path on 2 node accesses:
    // (2 x 232 - 2 x 72 + 2 x 4 + 4 x path) / 2, by hand for two path latencies
    for ((path, expect) <- Seq(8.0 -> 180.0, 5.0 -> 174.0)) {
      val c = Throughput.predict(p.copy(hw = HwLimits(cachePathCycles = path)), sink(cached = true), rays = 2, tus = 1)
      assert(c.latencyCycles == expect, s"cache path of $path cycles")
      assert(c.dramCycles < u.dramCycles)
    }
  }
}
