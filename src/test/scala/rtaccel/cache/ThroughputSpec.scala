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
    // 128 B nodes, 64 B primitives, 40 cycles latency, 4 B/cycle sustained, 32 B beats; the fixed stages (the fit's)
    val p = Presets.paper2017.copy(pipelining = rtaccel.config.Pipelining.Fixed)
    def sink(cached: Boolean) = {
      val s = new CacheSink(if (cached) Some(new CacheModel(CacheParams(8, 1, CachePolicy.Dm), LevelPolicy.paper)) else None, None, 128, c => c * 64L)
      for (r <- 0 until 2) { s.node(r, 0, 0); s.node(r, 1, 1); s.leaf(r, 0, 3, 2) } // 2 rays: 2 nodes + a 3-prim leaf each
      s.counts
    }
    val u = Throughput.predict(p, sink(cached = false), rays = 2, tus = 1)
    // per ray: 2 node misses x (40 + 32) + 1 leaf x 40 + 192 B / 4 = 144 + 40 + 48
    assert(u.latencyCycles == 232.0)
    assert(u.dramCycles == (2 * 128 + 192) / 4.0)
    assert(u.beatCycles == (2 * 128 + 192) / 32.0)
    assert(math.abs(u.raysPerCycle - 1 / 232.0) < 1e-15)
    // PIPELINE=auto: every node test takes the box pipe's extra cycles, every leaf the triangle pipe's (2 + 1 per ray),
    // and each of the 3 accesses seven cycles of registers (the IU arbiter's registered grant, its slice on the winner, the IU's request slice,
    // its slice on the MC's responses and its register in front of the pipes, the MC's slice after its arbiter, the TU's
    // register on its answer); paper2017 has a node cache, so its MC has response buffers and a path slices of its own
    // (its DRAM read, its beats into and out of the buffer) beside the AR channel's slice: here no access is cached,
    // four cycles more each. The
    // TU applies a leaf's last result a cycle after it arrives (its registered compare with tmax): one more per leaf
    val (bx, tx0) = rtaccel.iu.PipeLatencies.extraOverFixed(Presets.paper2017)
    assert(Presets.paper2017.tuLeafCycles == 1 && p.tuLeafCycles == 0)
    val tx = tx0 + 1
    assert(bx > 0 && tx0 > 0 && Presets.paper2017.accessSliceCycles == 7 && p.accessSliceCycles == 0 && Presets.paper2017.passSliceCycles == 4)
    assert(Throughput.predict(Presets.paper2017, sink(cached = false), rays = 2, tus = 1).latencyCycles == 232.0 + 2 * bx + tx + 3 * 11)
    // without a cache (one cluster, one channel, request order) and without re-reads (MEM_RETRIES=0) there are no
    // response buffers and no path slice, only the AR channel's; re-reads need the buffers
    val bare = Presets.paper2017.copy(nodeCache = CacheParams(), memRetries = 0)
    assert(bare.passSliceCycles == 1 && bare.copy(ius = 2).passSliceCycles == 4 && bare.copy(memRetries = 1).passSliceCycles == 4)
    assert(bare.copy(pipelining = rtaccel.config.Pipelining.Fixed).passSliceCycles == 0)
    assert(Throughput.predict(bare, sink(cached = false), rays = 2, tus = 1).latencyCycles == 232.0 + 2 * bx + tx + 3 * 8)
    // TRI_II / BOX_II at the fixed stages: each node and leaf test takes its shared operators' extra cycles over the
    // pipes of a job per cycle (the latencies of the elaborated pipes, taken here apart from extraOverFixed)
    val shared = p.copy(triInterval = 2, boxInterval = 4)
    val (l1, l2) = (rtaccel.iu.PipeLatencies.of(p), rtaccel.iu.PipeLatencies.of(shared))
    assert(l2.box > l1.box && l2.tri > l1.tri)
    assert(Throughput.predict(shared, sink(cached = false), rays = 2, tus = 1).latencyCycles == 232.0 + 2 * (l2.box - l1.box) + (l2.tri - l1.tri))
    // packed leaves: 2 rays x one 3-primitive leaf of 128 B (120 B of records padded to 4 beats); at TRI_II=2 the
    // LeafAssembler takes 6 cycles for its 3 records, which the port's demand and each leaf's latency take instead of
    // the 4 beats (and the triangle pipe's shared operators their extra cycles)
    def packedSink = { val s = new CacheSink(None, None, 128, c => (c * 40L + 31) / 32 * 32); for (r <- 0 until 2) { s.node(r, 0, 0); s.leaf(r, 0, 3, 2) }; s.counts }
    val pk = p.copy(primPacked = true)
    val (one, two) = (Throughput.predict(pk, packedSink, rays = 2, tus = 1), Throughput.predict(pk.copy(triInterval = 2), packedSink, rays = 2, tus = 1))
    assert(one.beatCycles == (128 + 128) / 32.0 && two.beatCycles == 128 / 32.0 + 6.0, s"${one.beatCycles} ${two.beatCycles}")
    val triExtra = rtaccel.iu.PipeLatencies.of(pk.copy(triInterval = 2)).tri - rtaccel.iu.PipeLatencies.of(pk).tri
    assert(two.latencyCycles - one.latencyCycles == (6.0 - 4.0) + triExtra, s"${two.latencyCycles} ${one.latencyCycles} $triExtra")
    // NODE_FORMAT=q8 pipelined: every node test takes the decoder's registers beyond its two fixed stages too
    val q8 = Presets.paper2017.copy(nodeQuantBits = 8, nodeCache = CacheParams(), memRetries = 0)
    def q8Sink = { val s = new CacheSink(None, None, q8.nodeAccessBytes, c => c * 64L); for (r <- 0 until 2) { s.node(r, 0, 0); s.node(r, 1, 1); s.leaf(r, 0, 3, 2) }; s.counts }
    val dec = rtaccel.iu.NodeDecode.latencyOf(q8.nodes) - rtaccel.iu.NodeDecode.FixedLatency
    assert(dec > 0)
    assert(Throughput.predict(q8, q8Sink, rays = 2, tus = 1).latencyCycles -
      Throughput.predict(q8.copy(pipelining = rtaccel.config.Pipelining.Fixed), q8Sink, rays = 2, tus = 1).latencyCycles == 2 * (bx + dec) + tx + 3 * 8)
    // slot64 at TRI_II=2: two beats a primitive already, nothing but the pipe's latency moves
    assert(Throughput.predict(p.copy(triInterval = 2), sink(cached = false), rays = 2, tus = 1).beatCycles == u.beatCycles)
    // ray 2's nodes hit (4 beats each instead of a DRAM trip); both rays pay the cache path on 2 node accesses:
    // (2 x 232 - 2 x 72 + 2 x 4 + 4 x path) / 2, by hand for two path latencies
    for ((path, expect) <- Seq(8.0 -> 180.0, 5.0 -> 174.0)) {
      val c = Throughput.predict(p, sink(cached = true), rays = 2, tus = 1, cachePathCycles = path)
      assert(c.latencyCycles == expect, s"cache path of $path cycles")
      assert(c.dramCycles < u.dramCycles)
    }
  }

  test("head-of-line blocking: zero with one TU or without hits; by hand for two TUs behind one miss") {
    val (z, d, b) = (300.0, 137.0, 95.0)
    val s = Throughput.InOrder(hits = 20, misses = 3, hitLatency = 12, missLatency = 40)
    // one ray in flight: no other request to wait behind, whatever the stream
    assert(Throughput.mvaInOrder(z, d, b, s, 1) == ((1 / (z + d + b), 0.0)))
    // no hits (an uncached path): no blocking at any TU count
    for (n <- 1 to 32) assert(Throughput.mvaInOrder(z, d, b, s.copy(hits = 0), n)._2 == 0.0)
    // pure delay Z = 100 cycles per ray, one miss (in flight 100 cycles) and one zero-latency hit per ray. With two
    // TUs the other TU's misses are issued at x/2 per cycle (x = both TUs' rays per cycle), Qm = 50 x in flight, the
    // youngest one's age exponential of mean 100 / Qm, so a hit waits 100 (1 - (1 - e^-u) / u) with u = Qm, and
    // x = 2 / (100 + that wait): solved here by bisection, independently of the model's iteration
    val one = Throughput.InOrder(hits = 1, misses = 1, hitLatency = 0, missLatency = 100)
    def waitOf(x: Double) = { val u = 50 * x; 100 * (1 - (1 - math.exp(-u)) / u) }
    var (lo, hi) = (1e-6, 0.02)
    for (_ <- 1 to 200) { val mid = (lo + hi) / 2; if (2 / (100 + waitOf(mid)) > mid) lo = mid else hi = mid }
    val (x2, hol2) = Throughput.mvaInOrder(100.0, 0.0, 0.0, one, 2)
    assert(math.abs(x2 - lo) < 1e-9 * lo, s"$x2 vs $lo")
    assert(math.abs(hol2 - waitOf(lo)) < 1e-6)
    assert(x2 > 1 / 100.0 && x2 < 2 / 100.0) // two TUs gain, but less than twice: the hits wait
    // a hit as slow as the miss never waits for it
    assert(Throughput.mvaInOrder(100.0, 0.0, 0.0, one.copy(hitLatency = 100), 2) == ((2 / 100.0, 0.0)))
    // more TUs never lower throughput, never beyond the busiest server
    val xs = (1 to 64).map(n => Throughput.mvaInOrder(z, d, b, s, n)._1)
    assert(xs.zip(xs.tail).forall { case (a, c) => c >= a * (1 - 1e-12) } && xs.forall(_ <= 1 / d + 1e-15))
  }

  test("RESP_ORDER=path: a stream's hits wait behind its own misses only; two ports; never slower than one stream") {
    val (z, d) = (300.0, 137.0)
    // nodes all hit, leaves all miss: merged, the hits wait behind the leaves' misses; split, nothing waits
    val nodes = Throughput.InOrder(hits = 20, misses = 0, hitLatency = 12, missLatency = 40)
    val leaves = Throughput.InOrder(hits = 0, misses = 3, hitLatency = 0, missLatency = 40)
    val merged = Throughput.InOrder(hits = 20, misses = 3, hitLatency = 12, missLatency = 40)
    for (n <- 2 to 32) {
      val (xm, holM) = Throughput.mvaInOrder(z, d, 95.0, merged, n)
      val (xs, holS) = Throughput.mvaInOrder(z, d, Seq(60.0, 35.0), Seq(nodes, leaves), n)
      assert(holS == 0.0 && holM > 0, s"n=$n: split $holS, merged $holM")
      assert(xs >= xm, s"n=$n: two streams $xs slower than one $xm")
    }
    // one stream over one port is the single-stream model exactly
    assert(Throughput.mvaInOrder(z, d, Seq(95.0), Seq(merged), 16) == Throughput.mvaInOrder(z, d, 95.0, merged, 16))
    // two ports of half the demand each saturate later than one: the bound is the busiest server
    val (x2, _) = Throughput.mvaInOrder(0.0, 1.0, Seq(50.0, 50.0), Seq(leaves), 1024)
    val (x1, _) = Throughput.mvaInOrder(0.0, 1.0, Seq(100.0), Seq(leaves), 1024)
    assert(math.abs(x2 - 1 / 50.0) < 1e-9 && math.abs(x1 - 1 / 100.0) < 1e-9, s"$x2 $x1")
    // predict: with a node cache that hits, path order is at least as fast, and more rays may be in flight
    val sk = new CacheSink(Some(new CacheModel(CacheParams(8, 1, CachePolicy.Dm), LevelPolicy.paper)), None, 128, c => c * 64L)
    for (r <- 0 until 64) { sk.node(r, 0, 0); sk.node(r, 1 + r % 3, 1); sk.leaf(r, r % 5, 3, 2) }
    val p = Presets.paper2017
    for (tus <- Seq(1, 8, 32, 64)) {
      val req = Throughput.predict(p, sk.counts, rays = 64, tus = tus)
      val path = Throughput.predict(p.copy(respByPath = true), sk.counts, rays = 64, tus = tus)
      assert(path.raysPerCycle >= req.raysPerCycle * (1 - 1e-12), s"TUs=$tus: path ${path.raysPerCycle} < request ${req.raysPerCycle}")
      assert(path.inFlightLimit == math.min(tus, 2 * p.hw.iuOutstanding) && req.inFlightLimit == math.min(tus, p.hw.iuOutstanding))
      if (tus == 1) assert(path.raysPerCycle == req.raysPerCycle) // one ray: nothing to overtake
    }
    // RESP_ORDER=tagged: no hit waits, every TU's access may be in flight, at least path's rays
    for (tus <- Seq(1, 8, 32, 64)) {
      val path = Throughput.predict(p.copy(respByPath = true), sk.counts, rays = 64, tus = tus)
      val tagged = Throughput.predict(p.copy(respByPath = true, respTagged = true), sk.counts, rays = 64, tus = tus)
      assert(tagged.holCyclesPerRay == 0.0 && tagged.inFlightLimit == tus, s"TUs=$tus: $tagged")
      assert(tagged.raysPerCycle >= path.raysPerCycle * (1 - 1e-12), s"TUs=$tus: tagged ${tagged.raysPerCycle} < path ${path.raysPerCycle}")
      // however many TUs, never past the DRAM's bound
      assert(tagged.raysPerCycle <= (1 + 1e-12) / tagged.dramCycles, s"TUs=$tus: $tagged")
      if (tus == 1) assert(math.abs(tagged.raysPerCycle - 1 / tagged.latencyCycles) <= 1e-12 / tagged.latencyCycles, s"one TU: 1 / latency, $tagged")
    }
  }

  test("cache tags: one lookup per two cycles bounds a path of one-beat lines, TAG_FORWARD=1 lifts it; longer lines are unchanged") {
    // every node hits a one-beat line after the first ray (32 B nodes on 32 B beats): many TUs approach the path's
    // bound, 1 / (2 lookups x node accesses per ray) with two-cycle tags, 1 / (1 beat x accesses) with one
    val p4 = Presets.paper2017.copy(respByPath = true, respTagged = true)
    val p = p4.copy(m = 2, nodeQuantBits = 6) // M=2 q6: 32 B nodes
    assert(p.nodeAccessBytes == 32 && p4.nodeAccessBytes == 128)
    def sink(nodeBytes: Int) = {
      val s = new CacheSink(Some(new CacheModel(CacheParams(64, 1, CachePolicy.Dm), LevelPolicy.paper)), None, nodeBytes, c => c * 64L)
      for (r <- 0 until 200) { for (k <- 0 until 10) s.node(r, k, k % 4); s.leaf(r, r % 5, 1, 2) }
      s.counts
    }
    val (slow, fast) = (Throughput.predict(p, sink(32), rays = 200, tus = 64), Throughput.predict(p.copy(tagForward = true), sink(32), rays = 200, tus = 64))
    assert(slow.raysPerCycle <= (1 + 1e-12) / (2.0 * 10), s"two-cycle tags: $slow")
    assert(slow.raysPerCycle > 0.9 / (2.0 * 10), s"64 TUs should come near the tag bound: $slow")
    // one-cycle tags: the next resource binds (here the DRAM, 16.4 cycles per ray of leaf misses)
    val next = math.max(10.0, fast.dramCycles)
    assert(fast.raysPerCycle <= (1 + 1e-12) / next && fast.raysPerCycle > 0.95 / next && fast.raysPerCycle > 1.2 * slow.raysPerCycle, s"one-cycle tags: $fast vs $slow")
    // 128 B nodes (4 beats): the beats bind either way, so the knob changes no prediction
    assert(Throughput.predict(p4, sink(128), rays = 200, tus = 64) == Throughput.predict(p4.copy(tagForward = true), sink(128), rays = 200, tus = 64))
  }

  /** An event simulation of the network the model abstracts: n TUs with one access outstanding each; accesses
    * drawn from `mix` (weight, hit, beats, path cycles, DRAM bytes); a hit is ready `path` cycles after issue, a
    * miss starts its transfer at max(issue + path, DRAM free) and its beats leave as it streams in (ready after
    * latency + transfer); responses leave in issue order, one beat per cycle, and a TU issues its next access when
    * its response has left. Accesses per cycle. */
  def inOrderSim(n: Int, mix: Seq[(Double, Boolean, Int, Double, Double)], lat: Double, bpc: Double, accesses: Int, seed: Long): Double = {
    val rng = new scala.util.Random(seed)
    val total = mix.map(_._1).sum
    def draw() = { var r = rng.nextDouble() * total; mix.find { m => r -= m._1; r < 0 }.getOrElse(mix.last) }
    val ready = scala.collection.mutable.PriorityQueue.empty[(Double, Int)](Ordering.by[(Double, Int), Double](-_._1))
    for (t <- 0 until n) ready.enqueue((0.0, t))
    var (dramFree, lastOut, end) = (0.0, 0.0, 0.0)
    for (_ <- 0 until accesses) {
      val (t, tu) = ready.dequeue()
      val (_, hit, beats, path, bytes) = draw()
      val start = if (hit) math.max(t + path, lastOut) else {
        val s = math.max(t + path, dramFree); dramFree = s + bytes / bpc
        math.max(s + lat + bytes / bpc - beats, lastOut)
      }
      lastOut = start + beats; end = lastOut
      ready.enqueue((lastOut, tu))
    }
    accesses / end
  }

  // The model's approximations (Poisson issue of the misses, mean values) against the network itself: within 20 %
  // over random mixes (worst case optimistic at 4-8 TUs), where the plain MVA is off by 30-60 %.
  test("randomized: the model against an event simulation of the in-order network, 1-16 TUs") {
    val (lat, bpc) = (40.0, 4.0) // paper2017: 40 cycles, 4 B per cycle sustained, 32 B beats
    val rng = new scala.util.Random(12)
    var worstNew, worstOld = 0.0
    for (trial <- 0 until 16) {
      val hitRate = if (trial == 0) 0.0 else 0.5 + 0.47 * rng.nextDouble() // trial 0: no cache
      val leafShare = 0.05 + 0.2 * rng.nextDouble()
      val leafPrims = 1 + rng.nextInt(4)
      val nodePath = if (hitRate > 0) 8.0 else 0.0
      // node hit, node miss (128 B), leaf miss (uncached: leafPrims x 64 B); "ray" = one access here
      val mix = Seq((1 - leafShare) * hitRate, (1 - leafShare) * (1 - hitRate), leafShare)
        .zip(Seq((true, 4, nodePath, 0.0), (false, 4, nodePath, 128.0), (false, 2 * leafPrims, 0.0, 64.0 * leafPrims)))
        .map { case (w, (h, bt, pa, by)) => (w, h, bt, pa, by) }.filter(_._1 > 0)
      val hitsW = mix.filter(_._2).map(_._1).sum; val missW = 1 - hitsW
      val latency = mix.map { case (w, h, bt, pa, by) => w * (pa + (if (h) bt else lat + by / bpc)) }.sum
      val dram = mix.map { case (w, _, _, _, by) => w * by / bpc }.sum
      val port = mix.map { case (w, _, bt, _, _) => w * bt }.sum
      val hitLatency = if (hitsW > 0) mix.filter(_._2).map { case (w, _, bt, pa, _) => w * (pa + bt) }.sum / hitsW else 0.0
      val s = Throughput.InOrder(hitsW, missW, hitLatency, lat)
      for (n <- Seq(1, 2, 4, 8, 16)) {
        val sim = inOrderSim(n, mix, lat, bpc, 40000, trial)
        val model = Throughput.mvaInOrder(latency - dram - port, dram, port, s, n)._1
        val old = Throughput.mva(latency - dram - port, Seq(dram, port), n)
        worstNew = math.max(worstNew, math.abs(model / sim - 1)); worstOld = math.max(worstOld, math.abs(old / sim - 1))
        assert(math.abs(model / sim - 1) < 0.2, f"trial $trial hit rate $hitRate%.2f, $n TUs: model $model%.5f vs simulation $sim%.5f")
      }
    }
    info(f"worst error against the simulation: ${100 * worstNew}%.1f %% (plain MVA ${100 * worstOld}%.1f %%)")
    assert(worstOld > 0.3, "the plain MVA should miss the blocking the simulation has")
  }

  test("the outstanding-request limit caps the rays in flight") {
    val p = Presets.paper2017.copy(hw = HwLimits(iuOutstanding = 4))
    val s = new CacheSink(None, None, 128, c => c * 64L)
    for (r <- 0 until 4) { s.node(r, 0, 0); s.leaf(r, 0, 2, 1) }
    val at4 = Throughput.predict(p, s.counts, rays = 4, tus = 4)
    val at32 = Throughput.predict(p, s.counts, rays = 4, tus = 32)
    assert(at32.inFlightLimit == 4 && at32.raysPerCycle == at4.raysPerCycle)
    assert(at32.raysPerCycleNoHol > at4.raysPerCycleNoHol) // the plain MVA had no limit
  }
}
