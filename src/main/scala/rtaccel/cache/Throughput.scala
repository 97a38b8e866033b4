package rtaccel.cache

import rtaccel.config.PlatformParams

/** The fast model's rays/s prediction from a replayed access stream: mean value analysis (MVA) of a closed
  * network in which each of the N TUs holds one ray.
  *
  * Per ray, from the replay: a TU alone spends L cycles (its latency: per access a fixed pipeline overhead,
  * then for a miss the DRAM latency plus the transfer at the sustained rate, for a hit the beats from the
  * cache). Two shared resources serve every TU: DRAM (demand D = DRAM bytes / sustained bytes per cycle) and
  * the MC's one-beat-per-cycle response port (demand B = all beats, hits and misses). The rest,
  * Z = L - D - B, is pure delay. MVA over the populations 1..N gives the throughput of N rays in flight;
  * with N = 1 it is 1 / L, for large N it approaches 1 / max(D, B) (and is clipped there).
  *
  * Both servers are FCFS with (nearly) constant service per visit, so an arriving request finds the one in
  * service half done: R = S (1 + Q - U / 2) per visit (Reiser's residual correction of MVA for deterministic
  * service) instead of the exponential server's S (1 + Q).
  *
  * Head-of-line blocking: the MC answers in request order, so a hit cannot leave before every older request,
  * and the one that leaves last is the youngest miss in flight. Seen by an access of the population-k network:
  * the misses of the k - 1 other TUs, issued at (k-1)/k X(k) m per cycle (m misses per ray), each in flight
  * Rm = DRAM latency + its DRAM residence. Taking those issues as a Poisson stream, the youngest one's age is
  * exponential with mean Rm / Qm (Qm = misses in flight, by Little), and a hit whose own latency is c waits
  * E[max(0, Rm - c - age)] = w (1 - (1 - e^-u) / u) cycles more, w = Rm - c, u = w Qm / Rm. That wait joins
  * the ray's delay; X(k) and the wait depend on each other and are solved as a fixed point per population.
  * It is 0 with one TU (nothing else in flight) and without hits (no cache).
  * RESP_ORDER=path: the MC answers nodes and leaves in two streams, each over its own response port (and IU
  * collection); a stream's hits wait behind that stream's youngest miss only, and up to hw.iuOutstanding
  * accesses of each kind are in flight (the IU's two job FIFOs), so the limit is min(TUs, 2 hw.iuOutstanding).
  * RESP_ORDER=tagged: the two streams answer in any order (a hit leaves beside older misses), so no hit waits for
  * head-of-line blocking and every TU may have an access in flight (the IU keeps a job per TU): the limit is TUs.
  * At most min(TUs, hw.iuOutstanding, hw.mcOutstanding) rays have an access in the MC: the rest wait at the
  * IU's arbiter, and since the model's ray time is all memory time, N beyond that limit adds nothing.
  * Measured against the RTL and against an event simulation of the same in-order network in docs/dse.md
  * ("The speed-for-accuracy ladder").
  *
  * `cachePathCycles` (default CachePathCycles) is the extra latency of an access through a cache path (tag lookup, ticket queue, data
  * RAM, output queue), measured on the RTL at one TU (docs/caches.md: 7.5-8.8 cycles per access on sponza and
  * conference); an uncached path adds none (measured -1..0).
  */
object Throughput {
  /** A model constant, measured (see above), not a size of the hardware. */
  val CachePathCycles: Double = 8.0

  /** raysPerCycle: with head-of-line blocking and the outstanding limit; raysPerCycleNoHol: the plain MVA of
    * TUs rays (the model before head-of-line blocking, kept to show what the in-order stream costs). */
  final case class Prediction(latencyCycles: Double, dramCycles: Double, beatCycles: Double, raysPerCycle: Double,
                              raysPerCycleNoHol: Double, holCyclesPerRay: Double, inFlightLimit: Int)

  /** Per ray: hits and misses (accesses), the latency of a lone hit, the DRAM latency of a miss. */
  final case class InOrder(hits: Double, misses: Double, hitLatency: Double, missLatency: Double) {
    require(hits >= 0 && misses >= 0 && hitLatency >= 0 && missLatency >= 0, s"negative in-order stream figures: $this")
  }
  /** The plain exact MVA of n customers over exponential FCFS servers (`demands`) and a pure delay: the model
    * before head-of-line blocking, kept as `raysPerCycleNoHol`. */
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

  /** E[max(0, w - age)] for an exponential age of mean m / q (q misses in flight, each in flight m cycles):
    * the wait of a hit behind the youngest miss. */
  def youngestResidual(w: Double, q: Double, m: Double): Double =
    if (w <= 0 || q <= 0 || m <= 0) 0.0 else {
      val u = w * q / m
      if (u < 1e-6) w * u / 2 else w * (1 - (1 - math.exp(-u)) / u)
    }

  /** Rays per cycle and head-of-line blocking cycles per ray of n rays in flight over the DRAM (demand `dram`
    * per ray) and the response ports (`ports`, one demand per port), all FCFS with constant service per visit,
    * plus `delay`. Each of `streams` is answered in its own order: its hits wait behind its own youngest miss
    * only (RESP_ORDER=request: one stream; path: nodes and leaves). */
  def mvaInOrder(delay: Double, dram: Double, ports: Seq[Double], streams: Seq[InOrder], n: Int): (Double, Double) = {
    require(n >= 1, s"TUs must be at least 1 (got $n)")
    var (qD, uD) = (0.0, 0.0) // queue length and utilisation of the DRAM for the population before
    var qB = ports.map(_ => 0.0); var uB = ports.map(_ => 0.0)
    val misses = streams.map(_.misses).sum
    var x = 0.0; var hol = 0.0
    for (k <- 1 to n) {
      val rD = dram * (1 + qD - uD / 2)
      val rBs = ports.indices.map(i => ports(i) * (1 + qB(i) - uB(i) / 2)); val rB = rBs.sum
      // a miss is in flight its DRAM latency plus its share of the DRAM residence (the DRAM serves every stream)
      def inFlight(st: InOrder) = if (misses > 0) st.missLatency + rD / misses else 0.0
      // the fixed point of X(k) and the blocking it causes (damped: the map is decreasing in X)
      var xk = k / (delay + rD + rB); var it = 0; var done = false
      while (!done && it < 200) {
        hol = streams.map { st =>
          val m = inFlight(st)
          st.hits * youngestResidual(m - st.hitLatency, (k - 1.0) / k * xk * st.misses * m, m)
        }.sum
        val next = k / (delay + hol + rD + rB)
        done = math.abs(next - xk) <= 1e-12 * xk
        xk = if (done) next else (xk + next) / 2
        it += 1
      }
      x = xk
      qD = x * rD; uD = x * dram
      qB = rBs.map(_ * x); uB = ports.map(_ * x)
    }
    val bottleneck = (dram +: ports).max
    (if (bottleneck > 0) math.min(x, 1 / bottleneck) else x, hol)
  }

  /** One in-order stream over one response port (RESP_ORDER=request). */
  def mvaInOrder(delay: Double, dram: Double, port: Double, s: InOrder, n: Int): (Double, Double) =
    mvaInOrder(delay, dram, Seq(port), Seq(s), n)

  def predict(p: PlatformParams, s: SinkCounts, rays: Int, tus: Int, cachePathCycles: Double = CachePathCycles): Prediction = {
    require(cachePathCycles >= 0, s"cache path cycles cannot be negative (got $cachePathCycles)")
    val n = math.max(1, rays).toDouble
    val bpc = p.memBytesPerSecondTotal / p.cyclesPerSecond // all channels (address-interleaved)
    val beatBytes = p.axiDataBits / 8.0
    val lat = p.memory.latencyCycles.toDouble
    val nodeMisses = s.nodeDramBytes / p.nodeAccessBytes.toDouble
    val leafMisses = s.primCache.fold(s.leafAccesses.toDouble)(_.misses.toDouble)
    val nodeHitBytes = (s.nodeAccesses * p.nodeAccessBytes - s.nodeDramBytes).toDouble
    val primHitBytes = (s.primBytesAll - s.primDramBytes).toDouble
    val hitBytes = nodeHitBytes + primHitBytes
    val nodeOverhead = s.nodeCache.fold(0.0)(_ => cachePathCycles) * s.nodeAccesses
    val primOverhead = s.primCache.fold(0.0)(_ => cachePathCycles) * s.leafAccesses
    // PIPELINE's registers lengthen every node and leaf test, and its slices every access (the fit above is of the
    // fixed stages)
    val (boxExtra0, triExtra) = rtaccel.iu.PipeLatencies.extraOverFixed(p)
    // NODE_FORMAT=q<k>: PIPELINE's registers in the node decoder too
    val boxExtra = boxExtra0 + (if (p.nodeQuantBits > 0) rtaccel.iu.NodeDecode.latencyOf(p.nodes) - rtaccel.iu.NodeDecode.FixedLatency else 0)
    def slices(cached: Boolean) = p.accessSliceCycles + (if (cached) p.cacheSliceCycles else p.passSliceCycles)
    val overhead = nodeOverhead + primOverhead + (boxExtra + p.bankSliceCycles + slices(s.nodeCache.isDefined)).toDouble * s.nodeAccesses +
      (triExtra + p.tuLeafCycles + slices(s.primCache.isDefined)).toDouble * s.leafAccesses
    // PRIM_FORMAT=packed with TRI_II=k: the LeafAssembler lets a record out every k cycles at most, so the primitive
    // port takes k cycles a primitive where its beats take fewer (slot64's TRI_II is at most its beats)
    val primBeatsOnly = s.primBytesAll / beatBytes / n
    val primBeats = if (p.primPacked) math.max(primBeatsOnly, p.triInterval.toDouble * s.primTests / n) else primBeatsOnly
    val latency = (nodeMisses * lat + leafMisses * lat + (s.nodeDramBytes + s.primDramBytes) / bpc + hitBytes / beatBytes + overhead) / n +
      (primBeats - primBeatsOnly)
    val dram = (s.nodeDramBytes + s.primDramBytes) / bpc / n
    val nodeBeats = s.nodeAccesses * p.nodeAccessBytes / beatBytes / n
    val beats = (s.nodeAccesses * p.nodeAccessBytes + s.primBytesAll) / beatBytes / n + (primBeats - primBeatsOnly)
    val delay = math.max(0.0, latency - dram - beats)
    // a lone hit: the path's overhead (every access of a cached path pays it) and its beats from the cache
    // (hits given, not derived from accesses - misses: the request-order stream keeps its old arithmetic bit for bit)
    // (RESP_ORDER=tagged: a stream without head-of-line blocking, i.e. no hit waits behind its misses)
    def stream(accesses: Double, hits: Double, misses: Double, over: Double, hb: Double): InOrder =
      if (p.respTagged) InOrder(0.0, misses / n, 0.0, lat)
      else InOrder(hits / n, misses / n, if (hits > 0) over / accesses + hb / beatBytes / hits else 0.0, lat)
    val (nodeAcc, leafAcc) = (s.nodeAccesses.toDouble, s.leafAccesses.toDouble)
    // a cached path's tags take one lookup per two cycles (TAG_FORWARD=1: per cycle), in series with its response
    // port: a path serves at the slower of its beats and its lookups, which are the lookups only for one-beat lines
    // (docs/caches.md, "One lookup per cycle"; no term where every line is two or more beats)
    val tagCycles = p.tagLookupCycles.toDouble
    // NODE_BANKS: the node lookups of every cluster share the banks' tag pipelines, NODE_BANKS / IUS of them per
    // cluster on average (ids spread evenly over the banks)
    val nodeTagShare = if (p.nodeShared) p.ius.toDouble / p.nodeBanks else 1.0
    val nodeTags = s.nodeCache.fold(0.0)(_ => tagCycles * nodeTagShare * s.nodeAccesses / n)
    val primTags = s.primCache.fold(0.0)(_ => tagCycles * s.leafAccesses / n)
    // RESP_ORDER=request: one stream over both paths and one response port; path: a stream and a port per path
    val (ports, streams) =
      if (p.respByPath) (Seq(math.max(nodeBeats, nodeTags), math.max(primBeats, primTags)),
        Seq(stream(nodeAcc, nodeAcc - nodeMisses, nodeMisses, nodeOverhead, nodeHitBytes), stream(leafAcc, leafAcc - leafMisses, leafMisses, primOverhead, primHitBytes)))
      else { val acc = nodeAcc + leafAcc; (Seq(Seq(beats, nodeTags, primTags).max), Seq(stream(acc, acc - nodeMisses - leafMisses, nodeMisses + leafMisses, overhead, hitBytes))) }
    // IUS clusters: each is the network above with TUS / IUS TUs, its own response port and a 1/IUS share of the
    // DRAM (the clusters are alike on average); the platform does IUS times one cluster's rays
    val k = p.ius
    require(tus % k == 0, s"TUS=$tus does not split evenly over IUS=$k intersection units")
    // rays with an access in flight: the IU's job FIFO and the MC's order FIFO (request), a job FIFO per kind (path),
    // or a job per TU (tagged)
    val limit = if (p.respTagged) tus / k else if (p.respByPath) math.min(tus / k, 2 * p.hw.iuOutstanding) else Seq(tus / k, p.hw.iuOutstanding, p.hw.mcOutstanding).min
    val (x, hol) = mvaInOrder(delay, dram * k, ports, streams, limit)
    Prediction(latency, dram, beats, x * k, mva(delay, Seq(dram * k, beats), tus / k) * k, hol, limit)
  }
}
