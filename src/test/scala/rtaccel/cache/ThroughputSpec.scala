package rtaccel.cache

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.config.{CacheParams, Presets}

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
      val s = new CacheSink(if (cached) Some(new CacheModel(CacheParams(8, 1, "dm"))) else None, None, 128, 64)
      for (r <- 0 until 2) { s.node(r, 0, 0); s.node(r, 1, 1); s.leaf(r, 0, 3, 2) } // 2 rays: 2 nodes + a 3-prim leaf each
      s
    }
    val u = Throughput.predict(p, sink(cached = false), rays = 2, tus = 1)
    // per ray: 2 node misses x (40 + 32) + 1 leaf x 40 + 192 B / 4 = 144 + 40 + 48
    assert(u.latencyCycles == 232.0)
    assert(u.dramCycles == (2 * 128 + 192) / 4.0)
    assert(u.beatCycles == (2 * 128 + 192) / 32.0)
    assert(math.abs(u.raysPerCycle - 1 / 232.0) < 1e-15)
    val c = Throughput.predict(p, sink(cached = true), rays = 2, tus = 1)
    // ray 2's nodes hit (4 beats each instead of a DRAM trip); both rays pay the cache path on 2 node accesses
    val expect = (232.0 * 2 - 2 * 72 + 2 * 4 + 4 * Throughput.cachePathCycles) / 2
    assert(c.latencyCycles == expect)
    assert(c.dramCycles < u.dramCycles)
  }
}
