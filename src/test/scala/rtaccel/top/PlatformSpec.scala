package rtaccel.top

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.cli.{Cli, Simulate}
import rtaccel.config.TriTest
import rtaccel.config.{RespOrder, CacheParams, CachePolicy, Pipelining, Presets}
import rtaccel.model.MemFaults
import rtaccel.scene.{Rays, Scene}

/** Whole-platform RTL (Verilator) against the reference model, ray by ray, bit for bit.
  * `make test` runs a quick subset of the grid; `make regress` (RTACCEL_REGRESS=full) the whole
  * TUs {1,2,4,8,32} x M {2,4,8} x MPPL {1,2,4,8,16}. The paper's fixed 32-bit reference layout is used so
  * that MPPL changes only the memory image and a compiled simulator serves every MPPL. Every run builds the `quick`
  * Verilator profile (no C++ optimisation): a few hundred rays simulate in seconds, the build is the test's time.
  * make test keeps one case per feature (the formats all in one circuit) at 4 TUs at most, since the C++ build grows
  * with the TUs and is the case's time; make regress runs each on its own too, at 8 TUs where make test runs 4.
  */
class PlatformSpec extends AnyFunSuite {
  private val full = rtaccel.Regress.full
  // PIPELINE: every case at the presets' auto (registers for 150 MHz on the paper's Virtex-5) but one grid point
  // at none (the fixed stages); make regress adds a deep budget
  // (the family the budget is reckoned for: ecp5's circuit differs in its DSP tiles and its delay chains in LUT RAM)
  // (the last: TRI_II and BOX_II, the IU pipes' initiation interval, their operators shared by that many operations of a job)
  private val grid: Seq[(Int, Int, Seq[Int], Pipelining, String, Int)] =
    if (full) (for (t <- Seq(1, 2, 4, 8, 32); m <- Seq(2, 4, 8)) yield (t, m, Seq(1, 2, 4, 8, 16), Pipelining.Auto, "xc5v", 1)) ++
      Seq((4, 2, Seq(2), Pipelining.Fixed, "xc5v", 1), (2, 4, Seq(4), Pipelining.Levels(3), "xc5v", 1), (2, 4, Seq(4), Pipelining.Auto, "ecp5", 1),
        (2, 2, Seq(16), Pipelining.Auto, "ecp5", 2), (4, 4, Seq(4), Pipelining.Fixed, "xc5v", 2))
    // make test: two TUs with the longest leaves on ecp5's circuit at M=2 and TRI_II=BOX_II=2 (its 18x18 tiles make
    // the largest model of make test; M=4 and intervals of 1 there are make regress's), four TUs with one primitive per leaf at
    // the fixed stages; every other case of make test runs the Virtex-5 circuit at auto and M=4
    else Seq((2, 2, Seq(16), Pipelining.Auto, "ecp5", 2), (4, 2, Seq(1), Pipelining.Fixed, "xc5v", 1))

  private val scene = TestScenes.soup(31, 400)
  private val rays = {
    val r = TestScenes.rays(32, 160).data
    // Hand-made rays the golden exporter never produces: axis-parallel with signed zeros, a [tmin, tmax)
    // window that cuts through the soup, origins exactly on vertices.
    val extra = Seq(
      Array(-1f, 5f, 5f, 1f, 0f, -0f, 0f, Float.PositiveInfinity),
      Array(5f, 11f, 5f, -0f, -1f, 0f, 0f, Float.PositiveInfinity),
      Array(5f, 5f, -1f, 0f, 0f, 1f, 3f, 7f),
      Array(scene.v(0, 0, 0), scene.v(0, 0, 1), scene.v(0, 0, 2), 1f, 1f, 1f, 0f, Float.PositiveInfinity),
      Array(scene.v(5, 1, 0), scene.v(5, 1, 1), scene.v(5, 1, 2), -1f, 0.5f, 0.25f, 1e-3f, 1e3f))
    Rays(r ++ extra.flatten)
  }

  private def runOne(tus: Int, m: Int, mppl: Int, rays: Rays, scene: Scene, jitter: Int = 0, stall: Int = 0,
                     node: CacheParams = CacheParams(), prim: CacheParams = CacheParams(), stack: Int = 64, errorRate: Double = 0.0, seed: Int = 1,
                     short: Int = 0, box: rtaccel.fp.FpFormat = rtaccel.fp.FpFormat.fp32, tri: TriTest = TriTest.Mt,
                     packed: Boolean = false, nodeQuant: Int = 0, triFormat: rtaccel.fp.FpFormat = rtaccel.fp.FpFormat.fp32, ius: Int = 1, channels: Int = 1,
                     order: String = RespOrder.Request, rayStore: Boolean = false, forward: Boolean = false, banks: Int = 0,
                     pipeline: Pipelining = Pipelining.Auto, family: String = "xc5v", errorMode: String = MemFaults.Sticky, retries: Int = 1, steps: Option[Int] = None,
                     ii: Int = 1) = {
    // level-aware node caches read the level field of the paper's Section 7.2 layout
    val base = if (node.policy.levelAware && node.entries > 0) Presets.paper2017Lrp else Presets.paper2017
    val p = base.copy(name = base.name, tus = tus, m = m, mppl = mppl, stackDepth = stack, nodeCache = node, primCache = prim,
      shortStack = short, boxFormat = box, triTest = tri, primPacked = packed, nodeQuantBits = nodeQuant, triFormat = triFormat, ius = ius, memChannels = channels,
      respByPath = order != RespOrder.Request, respTagged = order == RespOrder.Tagged, rayStore = rayStore, tagForward = forward, nodeBanks = banks,
      pipelining = pipeline, family = family, memRetries = retries, maxSteps = steps, triInterval = ii, boxInterval = ii)
    val b = Cli.build(scene, p, fit = false, stack = Some(stack))
    val o = rtaccel.sim.PlatformRun.run(b, rays, rtaccel.sim.PlatformRun.SimOptions(s"soup-t$tus-m$m-k$mppl-i$ius-c$channels-b$banks", memJitter = jitter, hostStall = stall,
      memErrorRate = errorRate, seed = seed, build = Some(rtaccel.sim.VerilatorBuild.quick), work = "build/sim-test/PlatformSpec",
      memErrorMode = errorMode))
    val j = o.json
    info(f"TUs=$tus M=$m MPPL=$mppl: ${j("cycles").num}%.0f cycles, ${j("sim_cycles_per_wall_s").num}%.0f cycles/s, " +
      f"mismatch ${j("mismatch_vs_model").num}%.0f lost ${j("lost").num}%.0f dup ${j("duplicated").num}%.0f")
    assert(j("timed_out").bool == false, "the platform did not finish")
    assert(j("mismatch_vs_model").num == 0 && j("lost").num == 0 && j("duplicated").num == 0, brief(j))
    assert(j("overflowed").num == j("model_overflowed").num && j("overflow_disagreements").num == 0)
    // transient errors without re-reads: timing decides which ray reads a poisoned beat first (PlatformRun excuses
    // exactly the rays that read one), so only the flags' agreement is checked
    val exact = errorMode == MemFaults.Sticky || retries > 0
    if (exact) assert(j("read_errors").num == j("model_read_errors").num)
    assert(j("read_error_disagreements").num == 0)
    assert(j("health")("retries").num == j("counters")("mem_retries").num && j("mem_retry_limit").num == retries)
    assert(j("step_limit_rays").num == j("model_step_limit_rays").num && j("step_limit_disagreements").num == 0)
    assert(j("ok").bool && j("failures").arr.isEmpty, brief(j))
    // the hit stream's TLAST on the batch's last hit only; "usable" counts the records without a fault flag
    assert(j("hit_tlast")("beats").num == 1 && j("hit_tlast")("at").num == rays.count - 1, ujson.write(j("hit_tlast")))
    assert(j("health")("usable").num == (0 until rays.count).count(i => o.hits.prim(i) >= -1), ujson.write(j("health")))
    // (transient errors without re-reads: a flagged ray stops where it read the error, the model's goes on)
    if (exact) assert(j("node_requests").num == j("model_node_fetches").num, "the RTL fetched a different number of nodes")
    else assert(j("node_requests").num <= j("model_node_fetches").num, "the RTL fetched more nodes than the fault-free model")
    if (exact) assert(j("prim_requests").num == j("model_prim_tests").num, "the RTL fetched a different number of primitives")
    if (node.entries > 0 || prim.entries > 0) {
      assert(j("cache_counts_match_model").bool, s"cache counts differ from the trace model on the RTL's order: ${ujson.write(j)}")
      for ((c, k) <- Seq(node -> "node_cache", prim -> "prim_cache") if c.entries > 0) {
        info(f"$k ${c.entries} x${c.ways} ${c.policy}: hits ${j(k)("hits").num}%.0f misses ${j(k)("misses").num}%.0f bypasses ${j(k)("bypasses").num}%.0f")
        assert(j(k)("hits").num > 0 && j(k)("misses").num > 0, s"$k: a test cache must both hit and miss")
      }
    } else assert(j("node_cache")("entries").num == 0 && j("prim_cache")("entries").num == 0, "an uncached run must build no cache")
    o
  }

  /** A failed run's figures first, then its whole JSON: make test's log keeps only a failure message's start. */
  private def brief(j: ujson.Value): String = {
    def n(k: String) = f"${j(k).num}%.0f"
    s"${j("mem_error_mode").str} errors at rate ${j("mem_error_rate").num}, mismatch ${n("mismatch_vs_model")} lost ${n("lost")} " +
      s"dup ${n("duplicated")}, read errors ${n("read_errors")} (model ${n("model_read_errors")}), retries ${n("mem_retries")}, " +
      s"failures ${ujson.write(j("failures"))}, first differing rays ${ujson.write(j("mismatch_examples"))}; ${ujson.write(j)}"
  }

  // make test: the fixed-stage grid circuit has a 3-entry stack, so that the rays that overflow it (prim -3) are
  // flagged exactly as the model's in the same build as the MAX_STEPS case below (make regress: "a stack too small")
  private val smallStack = 3
  private def gridStack(pl: Pipelining) = if (!full && pl == Pipelining.Fixed) smallStack else 64
  for ((tus, m, mppls, pl, fam, ii) <- grid; mppl <- mppls)
    test(s"bit-exact against the reference model: TUs=$tus M=$m MPPL=$mppl PIPELINE=${pl.name}${if (fam != "xc5v") s" for $fam" else ""}${if (ii > 1) s" TRI_II=BOX_II=$ii" else ""}${if (gridStack(pl) < 64) s"; a ${gridStack(pl)}-entry stack overflows exactly the model's rays" else ""}") {
      val j = runOne(tus, m, mppl, rays, scene, pipeline = pl, family = fam, stack = gridStack(pl), ii = ii).json
      assert(j("tri_ii").num == ii && j("box_ii").num == ii, "the JSON line names TRI_II and BOX_II")
      if (gridStack(pl) < 64) someOverflowed(j, gridStack(pl))
      assert(j("pipeline")("mode").str == pl.name && j("pipeline")("budget_levels").isNull == (pl == Pipelining.Fixed), ujson.write(j("pipeline")))
      assert(j("pipeline")("family").str == fam, ujson.write(j("pipeline")))
    }

  // Caches (docs/caches.md): whole scene bit-exact, counts equal the model on the logged order, and no stale
  // line under random DRAM latency and host backpressure (a wrong beat would change a hit).
  // make test: these caches under jitter and backpressure in the short-stack case's circuit
  private val cacheCases = if (!full) Nil else Seq(
    ("LRP 2-way node cache (MAX_LEVEL 3) + 2-way LRU primitive cache, jitter + backpressure", 8,
      CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 37, 40),
    ("direct-mapped node + primitive caches", 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(64, 1, CachePolicy.Dm), 0, 0),
    ("hybrid node cache (MAX_LEVEL 2) + PLRU 4-way primitive cache, jitter + backpressure", 4,
      CacheParams(64, 1, CachePolicy.Hybrid, maxLevel = 2), CacheParams(64, 4, CachePolicy.Plru), 23, 30),
    ("breadth-first static node buffer (preloaded)", 2, CacheParams(16, 1, CachePolicy.Bf), CacheParams(), 11, 0))
  for ((what, tus, node, prim, jitter, stall) <- cacheCases)
    test(s"caches, bit-exact and counting like the model: $what") {
      runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim)
    }

  private def someOverflowed(j: ujson.Value, stack: Int): Unit = {
    info(s"${j("overflowed").num.toInt} of ${rays.count} rays overflowed a $stack-entry stack")
    assert(j("model_overflowed").num > 0 && j("model_overflowed").num < rays.count, "the test stack must overflow some rays, not all")
  }
  // make test: in the grid's fixed-stage circuit above
  if (full) test("a stack too small for the scene: the RTL flags exactly the model's overflowed rays, bit for bit") {
    someOverflowed(runOne(2, 8, 1, rays, scene, stack = 2).json, 2)
  }

  // Memory read errors (poisoned beats, the same set in the DRAM model and the model; docs/platform.md "Memory
  // errors"). Sticky: exactly the rays that read one are flagged prim -2 (a re-read fails again, and a cached beat
  // keeps its error), every other ray stays bit-exact. Transient (the same circuit: the mode is the DRAM model's
  // input): the MC's re-read is clean, so no ray is flagged and every ray equals the fault-free model.
  // make test: in the all-formats circuit below (the error mode and rate are the DRAM model's inputs, not the circuit's)
  private val errorRate = 0.003
  /** A seed whose poison at errorRate spares the root node (a poisoned root fails every ray, which tests less). */
  private lazy val errorSeed = rootSpared(errorRate)
  /** A sticky and a transient run of one circuit at errorRate and errorSeed (the mode is the DRAM model's input). */
  private def checkReadErrors(j: ujson.Value, t: ujson.Value, cached: Boolean): Unit = {
    info(f"sticky: ${j("read_errors").num}%.0f of ${rays.count} rays read a poisoned beat (${j("mem_error_beats").num}%.0f error beats, ${j("mem_retries").num}%.0f re-reads)")
    assert(j("model_read_errors").num > 0 && j("model_read_errors").num < rays.count, "the rate must hit some rays, not all")
    assert(j("mem_error_beats").num > 0 && j("mem_error_beats").num == j("counters")("mem_read_errors").num)
    // every failed read is read once more and fails again: as many error beats again as re-reads bring
    assert(j("mem_retries").num > 0 && j("mem_error_beats").num >= 2 * j("mem_retries").num, ujson.write(j))
    // no errored fill stays a good line: later lookups refetch it (and fail again), replayed by the trace model
    if (cached) assert(j("poison_refetches").num > 0, "no lookup met a poisoned line")
    info(f"transient: ${t("read_errors").num}%.0f rays flagged, ${t("mem_error_beats").num}%.0f error beats, ${t("mem_retries").num}%.0f re-reads, ${t("health")("usable").num}%.0f usable")
    assert(t("read_errors").num == 0 && t("model_read_errors").num == 0 && t("mem_error_mode").str == "transient", ujson.write(t))
    assert(t("mem_retries").num > 0 && t("mem_error_beats").num > 0, "the transient run met no error")
  }
  if (full) for ((what, tus, node, prim) <- Seq(("DM node + 2-way LRU primitive caches", 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(64, 2, CachePolicy.Lru)),
      ("no cache", 4, CacheParams(), CacheParams())))
    test(s"memory read errors: sticky ones flag exactly the affected rays, transient ones are re-read and flag none, the rest bit-exact: $what") {
      def run(mode: String) = runOne(tus, 4, 4, rays, scene, jitter = 13, node = node, prim = prim, errorRate = errorRate, seed = errorSeed,
        errorMode = mode).json
      checkReadErrors(run(MemFaults.Sticky), run(MemFaults.Transient), node.entries > 0)
    }
  // MEM_RETRIES=0 keeps the flag at once: sticky errors flag the model's rays, transient ones the rays that read a
  // poisoned beat first (timing decides which; each of them one the model says reads one)
  if (full) test("memory read errors with MEM_RETRIES=0: sticky ones flag exactly the model's rays, transient ones only rays that read a poisoned beat") {
    val rate = 0.003
    val seed = rootSpared(rate)
    for (mode <- MemFaults.modes) {
      val j = runOne(4, 4, 4, rays, scene, jitter = 13, node = CacheParams(64, 1, CachePolicy.Dm), errorRate = rate, seed = seed,
        errorMode = mode, retries = 0).json
      info(f"$mode: ${j("read_errors").num}%.0f rays flagged (the model: ${j("model_read_errors").num}%.0f), ${j("mem_error_beats").num}%.0f error beats")
      assert(j("mem_retries").num == 0 && j("read_errors").num > 0)
    }
  }

  // Short stack with restart in the TUs: the RTL's fetches (counted and replayed through the caches) and hits
  // equal model.traceShort's, and its hits the full stack's.
  // make test: a ring of 1 in the NODE_BANKS case's circuit below (LRP node banks, jitter, backpressure and memory
  // errors); make regress: 8 TUs with the LRP node and LRU primitive caches, and 1 TU with a ring of 2
  private def checkShort(sh: rtaccel.sim.PlatformRun.Outcome, tus: Int, ring: Int): Unit = {
    val j = sh.json
    // the full stack's side from the model alone (RTL == model is what runOne checks)
    val (fo, fullNodes) = modelRun(Presets.paper2017.copy(tus = tus)) // caches and clusters change no fetch of the model
    def bits(h: rtaccel.scene.Hits, i: Int) = Seq(h.t(i), h.u(i), h.v(i)).map(java.lang.Float.floatToRawIntBits) :+ h.prim(i)
    for (i <- 0 until rays.count) assert(bits(sh.hits, i) == bits(fo, i), s"ray $i: the short stack's hit differs from the full stack's")
    info(f"ring $ring: ${j("model_restarts").num}%.0f restarts, ${j("node_requests").num}%.0f node fetches vs $fullNodes with the full stack")
    assert(j("model_restarts").num > 0 && j("node_requests").num > fullNodes, "the test ring must restart")
    assert(j("short_stack").num == ring && j("overflowed").num == 0)
  }
  if (full) for ((tus, ring, node, prim, jitter, stall) <- Seq((8, 1, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 37, 40),
      (1, 2, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 2, CachePolicy.Lru), 0, 0)))
    test(s"short stack of $ring with restart at $tus TU(s) with caches (node ${node.entries} ${node.policy}, prim ${prim.entries} ${prim.policy}, jitter $jitter, stall $stall): bit-exact, counts equal the model, hits equal the full stack's") {
      checkShort(runOne(tus, 4, 4, rays, scene, jitter, stall, node = node, prim = prim, short = ring), tus, ring)
    }

  // BOX_FORMAT: the outward-rounded box test in the IU equals model.RayBoxOutward in the model's traversal;
  // it can only add traversal work, so the RTL fetches at least the fp32 platform's nodes.
  if (full) test("BOX_FORMAT=bf16 at 4 TUs with a DM node cache: bit-exact against the model, no fewer node fetches than fp32") {
    val bf = runOne(4, 4, 4, rays, scene, node = CacheParams(64, 1, CachePolicy.Dm), box = rtaccel.fp.FpFormat.parse("bf16"))
    val (fp, fpNodes) = modelRun(Presets.paper2017.copy(tus = 4)) // fp32 boxes, model only
    info(f"node fetches: bf16 ${bf.json("node_requests").num}%.0f, fp32 $fpNodes")
    assert(bf.json("node_requests").num >= fpNodes && bf.json("box_format").str == "bf16")
    val agree = (0 until rays.count).count(i => bf.hits.prim(i) == fp.prim(i))
    info(s"$agree of ${rays.count} rays hit the same primitive as with fp32 boxes")
  }

  // TRI_FORMAT=fp64: the widened TriPipe in the IU and the TU's fp32 check of its rounded t equal the model's
  // traversal (RayTriangleWide); make regress only (a whole platform with the wide pipe is a long build)
  if (rtaccel.Regress.full)
    test("TRI_FORMAT=fp64 at 4 TUs with a DM node cache: bit-exact against the model") {
      val w = runOne(4, 4, 4, rays, scene, node = CacheParams(64, 1, CachePolicy.Dm), triFormat = rtaccel.fp.FpFormat.fp64)
      assert(w.json("numerics")("tri_format").str == "fp64")
      val (fp, _) = modelRun(Presets.paper2017.copy(tus = 4))
      val agree = (0 until rays.count).count(i => w.hits.prim(i) == fp.prim(i))
      info(s"$agree of ${rays.count} rays hit the same primitive as with fp32 triangle arithmetic")
    }

  // TRI_TEST=watertight: the watertight pipe and the box slack in the IU equal the model's traversal; the slack
  // can only add work. make regress: 8 TUs and 1 TU with other caches (make test: the all-formats case below).
  private val watertightCases = if (!full) Nil else
    Seq((8, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 31), (1, CacheParams(64, 1, CachePolicy.Dm), CacheParams(64, 1, CachePolicy.Dm), 0))
  for ((tus, node, prim, jitter) <- watertightCases)
    test(s"TRI_TEST=watertight at $tus TU(s) with caches: bit-exact against the model, no fewer node fetches than Möller–Trumbore") {
      val wt = runOne(tus, 4, 4, rays, scene, jitter, node = node, prim = prim, tri = TriTest.Watertight)
      val (mt, mtNodes) = modelRun(Presets.paper2017.copy(tus = tus))
      val j = wt.json
      info(f"node fetches: watertight ${j("node_requests").num}%.0f, Möller–Trumbore $mtNodes")
      assert(j("node_requests").num >= mtNodes && j("numerics")("tri_test").str == "watertight")
      val agree = (0 until rays.count).count(i => wt.hits.prim(i) == mt.prim(i))
      info(s"$agree of ${rays.count} rays hit the same primitive as with Möller–Trumbore")
      assert(agree > rays.count * 9 / 10, "the two triangle tests should disagree only at edges")
    }

  // PRIM_FORMAT=packed: 40 B records across beats (the IU's LeafAssembler), a leaf per row; the same work and hits as
  // slot64 (the model of each format on its own image), fewer DRAM bytes per leaf. The primitive cache's line is a row.
  private val packedCases =
    (if (full) Seq(("8 TUs, DM node cache + 2-way LRU primitive cache, jitter + backpressure", 8, 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 2, CachePolicy.Lru), 29, 30, 0.0),
      ("1 TU, no cache", 1, 4, CacheParams(), CacheParams(), 0, 0, 0.0),
      ("1 TU, DM node + DM primitive caches, MPPL 3", 1, 3, CacheParams(64, 1, CachePolicy.Dm), CacheParams(64, 1, CachePolicy.Dm), 0, 0, 0.0),
      ("4 TUs, MPPL 16, 4-way PLRU primitive cache", 4, 16, CacheParams(), CacheParams(128, 4, CachePolicy.Plru), 17, 0, 0.0),
      ("4 TUs, memory read errors, 2-way LRU primitive cache", 4, 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(64, 2, CachePolicy.Lru), 13, 0, 0.003))
    else Nil)
  for ((what, tus, mppl, node, prim, jitter, stall, rate) <- packedCases)
    test(s"PRIM_FORMAT=packed, $what: bit-exact against the model, the slot64 hits, leafBytes per leaf") {
      val seed = if (rate == 0) 1 else rootSpared(rate)
      val pk = runOne(tus, 4, mppl, rays, scene, jitter, stall, node, prim, errorRate = rate, seed = seed, packed = true); val j = pk.json
      assert(j("numerics")("prim_format").str == "packed")
      val (slot, _) = modelRun(Presets.paper2017.copy(tus = tus, mppl = mppl))
      if (rate == 0) for (i <- 0 until rays.count)
        assert(pk.hits.prim(i) == slot.prim(i) && java.lang.Float.floatToRawIntBits(pk.hits.t(i)) == java.lang.Float.floatToRawIntBits(slot.t(i)),
          s"ray $i: the packed image's hit differs from slot64's")
      checkLeafBytes(j, Presets.paper2017.copy(tus = tus, mppl = mppl, primPacked = true), rate, seed)
    }

  /** The DRAM bytes the MC requested for leaves (all bytes less the node slots) are the model's leafBytes(count)
    * summed over its leaf fetches, and fewer than slot64's 64 B per primitive.
    */
  private def checkLeafBytes(j: ujson.Value, p: rtaccel.config.PlatformParams, rate: Double = 0, seed: Int = 1): Unit = {
    val b = Cli.build(scene, p, fit = false, stack = Some(64))
    val st = new rtaccel.model.RayStats
    val img = rtaccel.bvh.MemoryImage.pack(b.bvh, scene, b.params)
    // the run's sticky errors (runOne's mode): a ray reads no child of a poisoned node, so it fetches fewer leaves
    val axi = rtaccel.mc.AxiParams.of(b.params)
    val faults = MemFaults(MemFaults.threshold(rate), seed, axi.beatBytes, b.params.nodeSlotBytes,
      rtaccel.host.ImageFile.layout(img, axi).primBaseBytes, b.params.primStrideBytes)
    new rtaccel.model.Traversal(img, faults).traceAll(rays, stats = st)
    val leafBytes = j("counters")("mem_bytes").num - j("node_requests").num * b.params.nodeSlotBytes
    info(f"primitive bytes per ray: packed ${leafBytes / rays.count}%.1f, slot64 ${st.primTests * 64.0 / rays.count}%.1f")
    assert(leafBytes == st.primBytes.toDouble && leafBytes < st.primTests * 64.0, "leaf bytes differ from the model's leafBytes")
  }

  // NODE_FORMAT=q<k>: the IU decodes the quantized image (NodeDecode) to the planes the model's traversal decodes;
  // a node fetch moves the 64 B slot. make regress: 8 TUs with a node cache, 1 TU, q4 with both caches.
  private val quantCases =
    (if (full) Seq((8, 8, CacheParams(64, 2, CachePolicy.Lru), CacheParams(), 17), (1, 8, CacheParams(), CacheParams(), 0), (4, 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 2, CachePolicy.Lru), 31)) else Nil)
  for ((tus, k, node, prim, jitter) <- quantCases)
    test(s"NODE_FORMAT=q$k at $tus TU(s)${if (node.entries > 0) " with caches" else ""}: bit-exact against the model, half the node bytes") {
      val q = runOne(tus, 4, 4, rays, scene, jitter, node = node, prim = prim, nodeQuant = k)
      val (fp, fullNodes) = modelRun(Presets.paper2017.copy(tus = tus))
      val j = q.json
      info(f"node fetches: q$k ${j("node_requests").num}%.0f, full $fullNodes; node bytes/ray q$k ${j("node_bytes_per_ray").num}%.1f")
      assert(j("numerics")("node_format").str == s"q$k" && j("counters")("mem_bytes").num ==
        j("node_requests").num * 64 + j("prim_requests").num * 64, "a quantized node fetch moves its 64 B slot")
      val agree = (0 until rays.count).count(i => q.hits.prim(i) == fp.prim(i))
      info(s"$agree of ${rays.count} rays hit the same primitive as with full nodes")
      assert(agree > rays.count * 9 / 10, "larger boxes should change hits only at ties and edges")
    }

  // Every format at once in one circuit (make test's case of each): bf16 boxes, the watertight test and its slack,
  // q8 nodes through NodeDecode, packed leaves through LeafAssembler, both caches, DRAM jitter and host backpressure,
  // at TRI_II=BOX_II=2 (the LeafAssembler spaces its records two cycles apart; the pipes assert the spacing).
  // make test: its DRAM poisons beats, transient (every error is re-read clean, so each ray equals the fault-free
  // model and the comparisons below hold) then sticky on the same build (exactly the model's rays flagged, the leaf
  // bytes of the faulty model); make regress: fault-free here and the errors on their own above
  private val formatTus = if (full) 8 else 4
  test(s"all formats in one circuit (bf16, watertight, q8, packed; TRI_II=BOX_II=2) at $formatTus TUs with both caches: bit-exact, counts equal the model${if (full) "" else "; memory read errors, transient and sticky"}") {
    val (rate, seed) = if (full) (0.0, 1) else (errorRate, errorSeed)
    val params = Presets.paper2017.copy(tus = formatTus, boxFormat = rtaccel.fp.FpFormat.parse("bf16"), triTest = TriTest.Watertight,
      primPacked = true, nodeQuantBits = 8, triInterval = 2, boxInterval = 2)
    def formats(mode: String) = runOne(formatTus, 4, 4, rays, scene, jitter = 29, stall = 30,
      node = CacheParams(64, 2, CachePolicy.Lru), prim = CacheParams(32, 2, CachePolicy.Lru), box = params.boxFormat,
      tri = params.triTest, packed = true, nodeQuant = 8, errorRate = rate, seed = seed, errorMode = mode, ii = 2)
    val r = formats(MemFaults.Transient)
    assert(r.json("tri_ii").num == 2 && r.json("box_ii").num == 2)
    val n = r.json("numerics")
    assert(n("box_format").str == "bf16" && n("tri_test").str == "watertight" && n("node_format").str == "q8" &&
      n("prim_format").str == "packed", ujson.write(n))
    val (fp, fullNodes) = modelRun(Presets.paper2017.copy(tus = formatTus))
    info(f"node fetches: all formats ${r.json("node_requests").num}%.0f, fp32 full $fullNodes")
    val agree = (0 until rays.count).count(i => r.hits.prim(i) == fp.prim(i))
    assert(agree > rays.count * 9 / 10, s"only $agree of ${rays.count} rays hit fp32 Möller–Trumbore's primitive")
    if (full) checkLeafBytes(r.json, params)
    else {
      val sticky = formats(MemFaults.Sticky).json
      checkReadErrors(sticky, r.json, cached = true)
      checkLeafBytes(sticky, params, rate, seed)
    }
  }

  /** The reference model alone on this spec's scene and rays: its hits and node fetches. */
  private def modelRun(p: rtaccel.config.PlatformParams): (rtaccel.scene.Hits, Long) = {
    val b = Cli.build(scene, p, fit = false, stack = Some(64))
    val st = new rtaccel.model.RayStats
    (new rtaccel.model.Traversal(rtaccel.bvh.MemoryImage.pack(b.bvh, scene, b.params)).traceAll(rays, stats = st), st.nodeFetches)
  }

  // IUS clusters (docs/architecture.md): each cluster's caches see only its own TUs' accesses, so the counts equal
  // the model replaying each cluster's log through its own caches; both clusters must have worked.
  // MEM_CHANNELS: each channel its own DRAM model (own jitter). make test runs IUS=2 over 2 channels in its
  // NODE_BANKS case below (one circuit for them all); make regress each here with request order.
  private val iusCases = if (!full) Nil else Seq((2, 2, 8, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 31, 35),
      (2, 1, 8, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 31, 35),
      (1, 2, 4, CacheParams(), CacheParams(), 17, 0), (1, 4, 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(), 23, 10),
      (2, 1, 4, CacheParams(), CacheParams(), 17, 0), (4, 1, 8, CacheParams(64, 1, CachePolicy.Dm), CacheParams(), 23, 20),
      (4, 1, 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(64, 1, CachePolicy.Dm), 0, 0), (2, 1, 2, CacheParams(), CacheParams(), 0, 0))
  for ((ius, ch, tus, node, prim, jitter, stall) <- iusCases)
    test(s"IUS=$ius clusters, MEM_CHANNELS=$ch at $tus TUs (node ${node.entries}, prim ${prim.entries}, jitter $jitter, stall $stall): bit-exact, counts per cluster equal the model") {
      val j = runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim, ius = ius, channels = ch).json
      checkClusters(j, ius, ch, node, prim)
    }

  // RESP_ORDER=path and tagged (docs/platform.md): node and leaf responses in two streams (tagged: each in any
  // order, hits under misses); bit-exact, and the caches' counts still equal the model replaying the RTL's own
  // order. make test: tagged in the NODE_BANKS case below (with RAY_STORE=1 and two clusters over MEM_CHANNELS=2); the
  // path order at the IU (IntersectionUnitSpec) and the MC (MemoryControllerSpec); make regress here.
  private val (path, tagged) = (RespOrder.Path, RespOrder.Tagged)
  private val pathCases = if (!full) Nil else Seq((path, 2, 2, 8, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 31, 35)) ++
    (Seq((tagged, 1, 1, 8, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), 29, 30),(path, 1, 1, 4, CacheParams(), CacheParams(), 17, 20), (path, 1, 1, 4, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 2, CachePolicy.Lru), 23, 10),
      (path, 2, 1, 4, CacheParams(), CacheParams(), 0, 0), (tagged, 1, 1, 4, CacheParams(), CacheParams(), 17, 20),
      (tagged, 2, 1, 8, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 1, CachePolicy.Dm), 41, 25),
      (tagged, 1, 1, 8, CacheParams(32, 1, CachePolicy.Hybrid), CacheParams(16, 4, CachePolicy.Plru), 0, 0)))
  for ((order, ius, ch, tus, node, prim, jitter, stall) <- pathCases)
    test(s"RESP_ORDER=$order, IUS=$ius${if (ch > 1) s", MEM_CHANNELS=$ch" else ""} at $tus TUs (node ${node.entries}${if (node.entries > 0) " " + node.policy else ""}, prim ${prim.entries}, jitter $jitter, stall $stall): bit-exact, counts ${if (ch > 1) "per cluster " else ""}equal the model") {
      val j = runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim, ius = ius, channels = ch, order = order).json
      assert(j("resp_order").str == order, ujson.write(j))
      checkClusters(j, ius, ch, node, prim)
    }

  // RAY_STORE=1 (docs/platform.md, "Ray store"): the rays wait in each cluster's store instead of travelling with
  // every request; nothing else changes, so the run is bit-exact and (make regress) takes the very same cycles as
  // without the store. make test: two clusters (the TC's write goes to the right cluster's store), tagged, caches,
  // and TAG_FORWARD=1 in the NODE_BANKS case's circuit below (one lookup per cycle: docs/caches.md); make regress
  // each of these and the store alone.
  private val storeCases = if (!full) Nil else Seq((tagged, 2, 8, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 1, CachePolicy.Dm), 41, 25, true)) ++
    (Seq((RespOrder.Request, 1, 4, CacheParams(), CacheParams(), 17, 20, false),
      (tagged, 2, 8, CacheParams(64, 1, CachePolicy.Dm), CacheParams(32, 1, CachePolicy.Dm), 41, 25, false)))
  for ((order, ius, tus, node, prim, jitter, stall, fwd) <- storeCases)
    test(s"RAY_STORE=1, RESP_ORDER=$order, IUS=$ius${if (fwd) ", TAG_FORWARD=1" else ""} at $tus TUs (node ${node.entries}, prim ${prim.entries}, jitter $jitter, stall $stall): " +
        s"bit-exact, counts equal the model${if (full) ", the same cycles as without the store" else ""}") {
      val j = runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim, ius = ius, order = order, rayStore = true, forward = fwd).json
      assert(j("ray_store").bool && j("resp_order").str == order && j("tag_forward").bool == fwd, ujson.write(j))
      checkClusters(j, ius, 1, node, prim)
      if (full) {
        val without = runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim, ius = ius, order = order, forward = fwd).json
        assert(without("cycles").num == j("cycles").num, s"RAY_STORE=1 took ${j("cycles").num} cycles, without the store ${without("cycles").num}")
      }
    }

  // NODE_BANKS=k (docs/caches.md, "Shared node cache"): one node cache for every cluster, in banks behind a crossbar;
  // the banks' counts equal the banked trace model replaying each bank's own order, and the platform stays bit-exact.
  // make test: two clusters on two banks over two memory channels with one lookup per cycle and the rays in the
  // clusters' stores (RAY_STORE=1: the TC's write goes to the right cluster's store), jitter and backpressure; make
  // regress: the same on one channel, more banks than
  // clusters (hybrid), one bank for four clusters, two memory channels, each without the store.
  // The make test case's DRAM poisons beats (docs/platform.md, "Memory errors"): transient, so every read error is
  // re-read and the run stays bit-exact with the fault-free model, then sticky on the same circuit, where exactly the
  // model's rays are flagged: re-reads and poison refetches under two clusters, banks and tagged answers. Its TUs
  // keep a short stack of 1 with restart (make regress: the short stack's own cases above, these without).
  private val bankErrorRate = 0.003
  private val bankCases = Seq((2, 2, if (full) 1 else 2, if (full) 8 else 4, CacheParams(64, 2, CachePolicy.Lrp, maxLevel = 3), CacheParams(32, 1, CachePolicy.Dm), 41, 25, true, !full)) ++
    (if (!full) Nil else Seq((2, 4, 1, 8, CacheParams(128, 1, CachePolicy.Hybrid, maxLevel = 2), CacheParams(16, 2, CachePolicy.Lru), 23, 30, false, false),
      (4, 1, 1, 8, CacheParams(64, 1, CachePolicy.Dm), CacheParams(), 0, 0, true, false),
      (2, 2, 2, 4, CacheParams(64, 2, CachePolicy.Lru), CacheParams(32, 1, CachePolicy.Dm), 17, 20, false, false)))
  for (((ius, banks, ch, tus, node, prim, jitter, stall, fwd, store), k) <- bankCases.zipWithIndex) {
    val short = if (k == 0 && !full) 1 else 0
    test(s"NODE_BANKS=$banks shared by IUS=$ius${if (ch > 1) s", MEM_CHANNELS=$ch" else ""}${if (fwd) ", TAG_FORWARD=1" else ""}${if (store) ", RAY_STORE=1" else ""} at $tus TUs (node ${node.entries} ${node.policy}, " +
        s"prim ${prim.entries}, jitter $jitter, stall $stall${if (k == 0) ", memory errors" else ""}${if (short > 0) s", a short stack of $short" else ""}): " +
        s"bit-exact, bank counts equal the banked model${if (short > 0) ", hits equal the full stack's" else ""}") {
      val (rate, seed) = if (k == 0) (bankErrorRate, rootSpared(bankErrorRate)) else (0.0, 1)
      val o = runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim, ius = ius, channels = ch, order = tagged, forward = fwd, banks = banks,
        rayStore = store, errorRate = rate, seed = seed, errorMode = MemFaults.Transient, short = short)
      val j = o.json
      // transient errors are all re-read: the hits are the fault-free ones, which the full stack's must equal
      if (short > 0) checkShort(o, tus, short)
      if (rate > 0) {
        assert(j("mem_retries").num > 0 && j("read_errors").num == 0, ujson.write(j))
        val s = runOne(tus, 4, 4, rays, scene, jitter, stall, node, prim, ius = ius, channels = ch, order = tagged, forward = fwd, banks = banks,
          rayStore = store, errorRate = rate, seed = seed, errorMode = MemFaults.Sticky, short = short).json
        info(f"sticky errors: ${s("read_errors").num}%.0f rays flagged as the model, ${s("mem_retries").num}%.0f re-reads, ${s("poison_refetches").num}%.0f refetches")
        assert(s("read_errors").num > 0 && s("mem_retries").num > 0, ujson.write(s))
      }
      assert(j("node_banks").num == banks && j("ray_store").bool == store && j("tag_forward").bool == fwd, ujson.write(j))
      checkClusters(j, ius, ch, node, prim, banks)
      // the clusters' MCs saw only leaves: every node reference went through a bank
      assert(j("cluster_accesses").arr.map(_.num).sum == j("counters")("leaf_requests").num, ujson.write(j))
    }
  }

  /** A seed whose poison at `rate` spares the root node (a poisoned root fails every ray, which tests less). */
  private def rootSpared(rate: Double): Int = (1 to 1000).find(s => !MemFaults(MemFaults.threshold(rate), s, 32, 128, 0, 64).nodeBad(0)).get

  private def checkClusters(j: ujson.Value, ius: Int, ch: Int, node: CacheParams, prim: CacheParams, banks: Int = 0): Unit = {
    assert(j("ius").num == ius && j("roofline")("ius").num == ius && j("mem_channels").num == ch && j("roofline")("mem_channels").num == ch, ujson.write(j))
    if (node.entries > 0 || prim.entries > 0) {
      val per = j("cluster_accesses").arr.map(_.num.toLong)
      val perBank = if (banks > 0) j("bank_accesses").arr.map(_.num.toLong).toSeq else Nil
      info(s"accesses per cluster: ${per.mkString(", ")}${if (banks > 0) s"; per node bank: ${perBank.mkString(", ")}" else ""}")
      assert(per.length == ius && per.forall(_ > 0), s"every cluster must have worked: $per")
      assert(perBank.length == banks && perBank.forall(_ > 0), s"every bank must have worked: $perBank")
      assert(per.sum + perBank.sum == j("node_requests").num + j("counters")("leaf_requests").num, "the logs must hold every access")
    }
  }

  // The step limit through the whole platform (register, TUs, hit word, status, counter, health) on the grid's 4-TU
  // circuit: MAX_STEPS is the register's reset value only and the host writes it, so the build is the grid's own
  test("MAX_STEPS written by the host: the rays that need more fetches end flagged prim -4, exactly the model's; STATUS, counter and health agree") {
    val o = runOne(4, 2, 1, rays, scene, pipeline = Pipelining.Fixed, steps = Some(6), stack = gridStack(Pipelining.Fixed))
    val j = o.json
    val limited = (0 until rays.count).filter(o.hits.prim(_) == rtaccel.scene.Hits.StepLimit)
    info(s"${limited.length} of ${rays.count} rays needed more than 6 fetches")
    assert(limited.nonEmpty && limited.length < rays.count, "some rays need more than 6 fetches, not all")
    assert(j("max_steps").num == 6 && j("step_limit_rays").num == limited.length && j("health")("step_limit").num == limited.length)
    assert(j("counters")("step_limit_rays").num == limited.length && j("status")("step_limit").bool)
    assert(limited.forall(i => o.hits.t(i) == Float.PositiveInfinity && o.hits.u(i) == 0f && o.hits.v(i) == 0f))
    // (make test's grid circuit has a small stack: its overflowed rays are not usable either)
    val overflowedOnly = (0 until rays.count).count(i => o.hits.prim(i) == rtaccel.scene.Hits.Overflow)
    assert(j("health")("usable").num + limited.length + overflowedOnly == rays.count)
  }

  // a memory image with silent bit flips (seeded) on the whole platform, at the default step limit of a fitted circuit
  // (its own build: make regress only; make test checks the same flips at the TU, TraversalUnitSpec)
  if (full) test("a loop and random silent bit flips in the memory image: the platform never hangs, every ray returns once, RTL == model with every flag") {
    val p0 = Presets.paper2017.copy(tus = 4, m = 4, mppl = 4, nodeCache = CacheParams())
    val b = Cli.build(scene, p0, fit = true)
    val clean = rtaccel.bvh.MemoryImage.pack(b.bvh, b.scene, b.params)
    var limited = 0.0
    for (run <- 0 until 8) {
      // a loop for certain, and the random flips around it
      val img = TestScenes.flipBits(TestScenes.withLoop(clean, 300L + run), 300L + run, 60 + 20 * run)
      val o = rtaccel.sim.PlatformRun.run(b, rays, rtaccel.sim.PlatformRun.SimOptions(s"soup-flips-$run", build = Some(rtaccel.sim.VerilatorBuild.quick),
        work = "build/sim-test/PlatformSpec"), image = Some(img))
      val j = o.json
      info(f"run $run: ${j("step_limit_rays").num}%.0f step limits (limit ${b.params.stepLimit}), ${j("overflowed").num}%.0f overflows, " +
        f"${j("health")("usable").num}%.0f usable of ${rays.count}, ${j("cycles").num}%.0f cycles")
      assert(!j("timed_out").bool && j("lost").num == 0 && j("duplicated").num == 0, ujson.write(j))
      assert(j("mismatch_vs_model").num == 0 && j("step_limit_disagreements").num == 0 && j("overflow_disagreements").num == 0, ujson.write(j))
      assert(j("ok").bool, ujson.write(j("failures")))
      limited += j("step_limit_rays").num
    }
    assert(limited > 0, "some flips must make a loop that rays enter")
  }

  // make regress: make test's cache, IUS and all-formats cases run under jitter and backpressure already
  if (full) test("random memory latency and host backpressure change no result") {
    // the quiet run is the grid's 4-TU circuit (the same build folder)
    val quiet = runOne(4, 2, 2, rays, scene).json
    val noisy = runOne(4, 2, 2, rays, scene, jitter = 37, stall = 40).json
    assert(noisy("cycles").num > quiet("cycles").num, "stalls must cost cycles")
    assert(noisy("counters")("stall_host_backpressure").num > 0)
  }
}
