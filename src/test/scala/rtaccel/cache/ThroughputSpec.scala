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
      val s = new CacheSink(if (cached) Some(new CacheModel(CacheParams(8, 1, CachePolicy.Dm), LevelPolicy.paper)) else None, None, 128, 64)
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

  test("head-of-line blocking: zero with one TU or without hits; by hand for two TUs behind one miss") {
    val (z, d, b) = (300.0, 137.0, 95.0)
    val s = Throughput.InOrder(hits = 20, misses = 3, hitLatency = 12, missLatency = 40)
    // one ray in flight: no other request to wait behind, whatever the stream
    assert(Throughput.mvaInOrder(z, d, Seq(b), s, 1) == ((1 / (z + d + b), 0.0)))
    // no hits (an uncached path): bit-for-bit the plain MVA at every TU count
    for (n <- 1 to 32)
      assert(Throughput.mvaInOrder(z, d, Seq(b), s.copy(hits = 0), n)._1 == Throughput.mva(z, Seq(d, b), n))
    // pure delay Z = 100 cycles per ray, one miss (in flight 100 cycles) and one zero-latency hit per ray:
    // alone, 1/100 rays per cycle; with two TUs the other TU's miss is in flight with mean 1/100 x 1 x 100 = 1,
    // its issue age exponential of mean 100, so a hit waits E[max(0, 100 - age)] = 100 e^-1 cycles.
    val one = Throughput.InOrder(hits = 1, misses = 1, hitLatency = 0, missLatency = 100)
    val (x2, hol2) = Throughput.mvaInOrder(100.0, 0.0, Seq(0.0), one, 2)
    assert(math.abs(hol2 - 100 * math.exp(-1)) < 1e-9)
    assert(math.abs(x2 - 2 / (100 + 100 * math.exp(-1))) < 1e-12)
    // a hit as slow as the miss never waits for it
    assert(Throughput.mvaInOrder(100.0, 0.0, Seq(0.0), one.copy(hitLatency = 100), 2)._2 == 0.0)
    // blocking only ever lowers throughput, and more TUs never lower it
    val xs = (1 to 32).map(n => Throughput.mvaInOrder(z, d, Seq(b), s, n))
    assert(xs.zip(1 to 32).forall { case ((x, _), n) => x <= Throughput.mva(z, Seq(d, b), n) + 1e-15 })
    assert(xs.zip(xs.tail).forall { case (a, c) => c._1 >= a._1 })
  }

  test("the outstanding-request limit caps the rays in flight") {
    val p = Presets.paper2017.copy(hw = HwLimits(iuOutstanding = 4))
    val s = new CacheSink(None, None, 128, 64)
    for (r <- 0 until 4) { s.node(r, 0, 0); s.leaf(r, 0, 2, 1) }
    val at4 = Throughput.predict(p, s, rays = 4, tus = 4)
    val at32 = Throughput.predict(p, s, rays = 4, tus = 32)
    assert(at32.inFlightLimit == 4 && at32.raysPerCycle == at4.raysPerCycle)
    assert(at32.raysPerCycleNoHol > at4.raysPerCycleNoHol) // the plain MVA had no limit
  }
}
