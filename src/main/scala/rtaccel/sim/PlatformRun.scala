package rtaccel.sim

import java.nio.file.{Files, Path, Paths}
import chisel3._
import chiseltest._
import chiseltest.internal.CachingAnnotation
import chiseltest.simulator.VerilatorBackendAnnotation
import firrtl2.options.TargetDirAnnotation
import rtaccel.bvh.MemoryImage
import rtaccel.config.{Numerics, PlatformParams}
import rtaccel.io.InputError
import rtaccel.mc.AxiParams
import rtaccel.cache.CacheReport
import rtaccel.cache.hw.CachePath
import rtaccel.model.{AccessRecorder, AccessSink, MemFaults, RayStats, Traversal}
import rtaccel.scene.{Hits, Rays}
import rtaccel.host.{HostDriver, HostSession, ImageFile, RaysFile}

/** One run of the platform RTL (Verilator) on rays, as make simulate, roofline and the tests do it: the simulator
  * built (or found by its key), the memory image and rays driven through the register map as a host would, the hit
  * stream read back and compared ray by ray with the reference model, the caches' counts with the trace model's, and
  * the metrics JSON with its checks (cli.Simulate reads the flags and writes the files).
  */
object PlatformRun {
  /** `vcd`: the whole run's trace when WAVES=1 (main0 cuts its window into OUT/waves.vcd). */
  final case class Outcome(json: ujson.Obj, hits: Hits, vcd: Option[(Path, (Long, Long))] = None) {
    def failures: Seq[String] = json("failures").arr.map(_.str).toSeq
    def ok: Boolean = json("ok").bool
  }

  /** The checks of one run, each by the name it has in the JSON (README: "Checks are exit statuses"). */
  def failures(j: ujson.Obj): Seq[String] = Seq(
    "mismatch_vs_model" -> (j("mismatch_vs_model").num > 0), "lost" -> (j("lost").num > 0),
    "duplicated" -> (j("duplicated").num > 0), "timeout" -> j("timed_out").bool,
    "overflow_vs_model" -> (j("overflow_disagreements").num > 0),
    "status_done" -> !j("status")("done").bool,
    "status_read_error" -> (j("status")("read_error").bool != (j("read_errors").num > 0)),
    "status_overflow" -> (j("status")("overflow").bool != (j("overflowed").num > 0)), "read_errors_vs_model" -> (j("read_error_disagreements").num > 0),
    "step_limit_vs_model" -> (j("step_limit_disagreements").num > 0),
    "status_step_limit" -> (j("status")("step_limit").bool != (j("step_limit_rays").num > 0)),
    // TLAST on exactly one hit beat, the batch's last (none for an empty batch)
    "hit_tlast" -> (j("hit_tlast")("beats").num != math.min(1, j("rays").num) || j("hit_tlast")("at").num != math.max(0, j("rays").num - 1)),
    // null when there is no cache to compare
    "cache_counts_match_model" -> (j("cache_counts_match_model") == ujson.False)).collect { case (n, true) => n }

  /** Options of one run that do not change the platform. */
  final case class SimOptions(label: String, memJitter: Int = 0, hostStall: Int = 0, seed: Int = 1,
                              work: String = "build/sim", maxCycles: Option[Long] = None, scaleExp: Int = 0,
                              memErrorRate: Double = 0.0, waves: Option[(Long, Long)] = None,
                              build: Option[rtaccel.sim.VerilatorBuild] = None, // None: VerilatorBuild.auto
                              memErrorMode: String = MemFaults.Transient) {
    val errorThreshold: Int = rtaccel.model.MemFaults.threshold(memErrorRate)
    val errorSticky: Boolean = MemFaults.sticky(memErrorMode)
  }

  /** The hit stream as the host captured it, by ray id: each record, how often it came, its fault flags. */
  final case class RtlHits(hits: Hits, seen: Array[Int], overflow: Array[Boolean], readError: Array[Boolean], stepLimit: Array[Boolean])

  private def readHits(dut: FirtoolShell[SimHarnessIO], received: Long, count: Int): RtlHits = {
    val r = RtlHits(Hits.empty(count), new Array[Int](count), new Array[Boolean](count), new Array[Boolean](count), new Array[Boolean](count))
    for (k <- 0 until math.min(received, count.toLong).toInt) {
      dut.io.readIdx.poke(k.U)
      val w = dut.io.readData.peek().litValue
      def word(i: Int) = ((w >> (32 * i)) & 0xffffffffL).toLong.toInt
      val id = word(0)
      if (id >= 0 && id < count) {
        r.seen(id) += 1
        r.hits.t(id) = java.lang.Float.intBitsToFloat(word(1)); r.hits.prim(id) = word(2)
        r.hits.u(id) = java.lang.Float.intBitsToFloat(word(3)); r.hits.v(id) = java.lang.Float.intBitsToFloat(word(4))
        r.overflow(id) = (word(5) & 1) != 0; r.readError(id) = (word(5) & 2) != 0; r.stepLimit(id) = (word(5) & 4) != 0
      }
    }
    r
  }

  /** RTL against the model, ray by ray: raw bits of every field, and each fault flag against the model's record. */
  final case class Comparison(mismatch: Int, lost: Int, overflowDisagree: Int, readErrorDisagree: Int, stepLimitDisagree: Int,
                              examples: ujson.Arr)

  /** How many differing rays a run's JSON shows side by side (enough to see a pattern, short enough for a log's tail). */
  val mismatchExamples = 4

  /** `mayFail`: MEM_ERROR_MODE=transient with MEM_RETRIES=0, where which ray first reads a poisoned beat depends on
    * timing: the rays that may come back flagged read error (those whose traversal reads a poisoned beat). Such a ray
    * agrees when the RTL flagged it (its traversal stopped there, whatever else it met) or returned the model's record;
    * every other ray must equal the model. */
  private def compare(rtl: RtlHits, model: Hits, flags: RayStats, mayFail: Option[scala.collection.BitSet]): Comparison = {
    def bits(f: Float) = java.lang.Float.floatToRawIntBits(f)
    val h = rtl.hits; val got = rtl.seen.indices.filter(rtl.seen(_) >= 1)
    val excused = (i: Int) => mayFail.exists(m => m(i) && rtl.readError(i) && h.prim(i) == rtaccel.scene.Hits.ReadError)
    val differs = got.filter(i => !excused(i) && (h.prim(i) != model.prim(i) || bits(h.t(i)) != bits(model.t(i)) ||
      bits(h.u(i)) != bits(model.u(i)) || bits(h.v(i)) != bits(model.v(i))))
    // a record as raw bits (t, u, v in hex) and its fault flags, the RTL's and the model's
    def record(x: Hits, i: Int, ov: Boolean, re: Boolean, sl: Boolean) =
      f"prim ${x.prim(i)} t ${bits(x.t(i))}%08x u ${bits(x.u(i))}%08x v ${bits(x.v(i))}%08x${if (ov) " overflow" else ""}" +
        s"${if (re) " read_error" else ""}${if (sl) " step_limit" else ""}"
    Comparison(
      mismatch = differs.length,
      lost = rtl.seen.count(_ == 0),
      // each flag against the model's own flag: a ray that overflowed and read an error carries both
      overflowDisagree = got.count(i => !excused(i) && rtl.overflow(i) != flags.overflowRays(i)),
      readErrorDisagree = got.count(i => !excused(i) && rtl.readError(i) != flags.readErrorRays(i)),
      stepLimitDisagree = got.count(i => !excused(i) && rtl.stepLimit(i) != flags.stepLimitRays(i)),
      examples = ujson.Arr.from(differs.take(mismatchExamples).map(i => ujson.Obj("ray" -> i,
        "rtl" -> record(h, i, rtl.overflow(i), rtl.readError(i), rtl.stepLimit(i)),
        "model" -> record(model, i, flags.overflowRays(i), flags.readErrorRays(i), flags.stepLimitRays(i))))))
  }

  /** A digest of every parameter, beside the build key's readable part: a knob that part does not name still gets a
    * build of its own instead of a stale one. The preset's name, where the clock came from and the knobs the registry
    * says shape no circuit (config.Knobs.circuitView: the DRAM's figures) are left out.
    */
  def paramsDigest(p: PlatformParams): String =
    // the clock, the family and PIPELINE's mode shape the circuit only through the budget (auto at 150 MHz and the
    // number it gives are one circuit) and, with one, the family's DSP block, delay chains and LUTs' inputs, which
    // are hashed in their place
    rtaccel.io.Digest.hexOf(5, rtaccel.config.Knobs.circuitView(p).copy(name = "", clockMhz = 1, clockSource = "", family = "",
      pipelineMhz = None, pipelining = rtaccel.config.Pipelining.Fixed).toString + s" budget ${p.stageBudget}" + p.stageBudget.fold("")(_ => s" dsp ${p.dspShape} ram ${p.delayRamCycles} lut ${p.pipes.lutInputs}"))

  /** Simulates `rays` on the platform of `b.params` over the tree `b.bvh` (scene and rays already normalised).
    * `image`: the memory image to load instead of the tree's (a test's corrupted copy); the model then traverses
    * memory as the platform reads it (ImageFile.asRead), stray references included.
    */
  def run(b: rtaccel.config.Built, rays: Rays, o: SimOptions, image: Option[MemoryImage] = None): Outcome = {
    val p = b.params
    CachePath.validate(p)
    val cached = p.nodeCache.entries > 0 || p.primCache.entries > 0
    val img = image.getOrElse(MemoryImage.pack(b.bvh, b.scene, p))
    require(img.p == p, "the image was packed for another configuration")
    val axi = AxiParams.of(p)
    val lay0 = ImageFile.layout(img, axi)
    val imageBytes = img.nodes.length * 4L + 4096 + img.prims.length * 4L
    val wordCap = SimSetup.capacity((imageBytes + axi.beatBytes - 1) / axi.beatBytes, SimSetup.minImageBytes / axi.beatBytes)
    val modelImg = if (image.isEmpty) img else ImageFile.asRead(img, lay0, axi, wordCap.toLong * axi.beatBytes)
    // the poisoned beats the DRAM model will answer with SLVERR (MEM_ERROR_RATE), known to the model
    val faults = MemFaults(o.errorThreshold, o.seed, axi.beatBytes, p.nodeSlotBytes, lay0.primBaseBytes, p.primStrideBytes)
    val tModel = System.nanoTime()
    val stats = new RayStats
    val rec = new AccessRecorder
    // what the rays see (MEM_ERROR_MODE, docs/platform.md "Memory errors"): a sticky error stays through every re-read
    // and cache, so exactly the rays that read a poisoned beat are flagged; a transient one fails one read and its
    // re-read is clean, so with MEM_RETRIES > 0 no ray is, and with 0 the ray that reads it first (timing decides
    // which: any ray that reads a poisoned beat may be flagged, and the others equal the fault-free model)
    val seen = if (o.errorSticky) faults else MemFaults.none
    val model = new Traversal(modelImg, seen).traceAll(rays, if (cached) rec else AccessSink.none, stats)
    val mayFail = if (o.errorSticky || p.memRetries > 0 || !faults.enabled) None else {
      val s = new RayStats
      new Traversal(modelImg, faults).traceAll(rays, AccessSink.none, s)
      Some(s.readErrorRays)
    }
    val accessRows = rec.toArray
    // the RTL logs its access order only when a cache is present; it makes exactly the model's accesses
    val logCap = if (cached) SimSetup.capacity(accessRows.length / 5, SimSetup.minLogEntries) else 0
    val label = o.label
    val build = o.build.getOrElse(rtaccel.sim.VerilatorBuild.auto(rays.count))
    val den = 1000
    val dram = DramConfig(latencyCycles = p.memory.latencyCycles, bytesPerCycleNum = math.round(p.memBytesPerCycle * den).toInt,
      bytesPerCycleDen = den, randomExtraLatency = o.memJitter, seed = o.seed, errorThreshold = o.errorThreshold, errorSeed = o.seed)
    // One folder per simulator build: everything that changes the circuit is in its name.
    val rayCap = SimSetup.capacity(rays.count, SimSetup.minRays)
    val r = p.refs
    val key = s"tus${p.tus}" + (if (p.ius > 1) s"-ius${p.ius}" else "") + (if (p.memChannels > 1) s"-ch${p.memChannels}.${p.hw.channelInterleaveBytes}" else "") + s"-m${p.m}-refs${r.nodeIdBits}.${r.primIndexBits}.${r.countBits}.${r.levelBits}-stack${p.stackDepth}" +
      s"-axi${p.axiDataBits}-div${p.divStages}-rays$rayCap-words$wordCap-lat${dram.latencyCycles}-bw${dram.bytesPerCycleNum}" +
      s"-jit${dram.randomExtraLatency}-stall${o.hostStall}-seed${o.seed}" + (if (o.errorThreshold > 0) s"-err${o.errorThreshold}" else "") +
      (if (p.shortStack > 0) s"-short${p.shortStack}.${p.treeLevels}" else "") +
      (if (p.boxFormat != rtaccel.fp.FpFormat.fp32) s"-box${p.boxFormat.name}" else "") +
      (if (p.triTest != rtaccel.config.TriTest.Mt) s"-tri${p.triTest.name}" else "") +
      (if (p.triFormat != rtaccel.fp.FpFormat.fp32) s"-tri${p.triFormat.name}" else "") +
      (if (p.respByPath) s"-r${p.respOrder}" else "") + (if (p.rayStore) "-raystore" else "") + (if (p.tagForward) "-tagfwd" else "") + (if (p.nodeShared) s"-banks${p.nodeBanks}" else "") +
      (if (p.primPacked) s"-packed${p.mppl}" else "") + // the leaf row (MPPL records) is a constant of the MC
      (if (p.nodeQuantBits > 0) s"-node${Numerics.nodeFormatName(p.nodeQuantBits)}" else "") +
      s"-${build.name}" + (if (o.waves.isDefined) "-vcd" else "") + // HwLimits: in the digest
      (if (cached) Seq(p.nodeCache, p.primCache).map(c => s"-c${c.entries}.${c.ways}.${c.policy}").mkString + s"-mppl${p.mppl}-log$logCap" else "") +
      // MAX_STEPS is only the register's reset value, and the host writes the register before every batch
      // (HostSession.configure): the simulator is built with the fit's reset value, so one serves every limit
      s"-p${paramsDigest(p.copy(maxSteps = None))}"
    val work = Paths.get(o.work).resolve(key) // relative: chiseltest wants a relative target folder
    Files.createDirectories(work)
    // the memory image and the rays, whose absolute names the harness's $readmemh holds (SimSetup.maxFileNameChars)
    val inputs = SimSetup.inputDir(Paths.get(o.work), key).toAbsolutePath
    Files.createDirectories(inputs)
    val layout = ImageFile.write(img, axi, inputs.resolve("image.hex"))
    require(layout.words <= wordCap, s"image of ${layout.words} words exceeds the simulator's $wordCap")
    require(layout == lay0, "the image layout the model's fault map assumed differs from the one written")
    RaysFile.write(rays, inputs.resolve("rays.hex"))
    val setup = SimSetup(rayCap, inputs.resolve("rays.hex").toString, inputs.resolve("image.hex").toString,
      wordCap, dram, hostStallPercent = o.hostStall, seed = o.seed, accessLogCapacity = logCap)
    val maxCycles = o.maxCycles.getOrElse(1000000L + 200000L * rays.count)
    System.err.println(s"[simulate] ${rays.count} rays, ${p.tus} TUs, M=${p.m}, MPPL=${p.mppl}: Verilator build (${build.name}) in $work")

    var result: Outcome = null
    val t0 = System.nanoTime()
    val modelWall = (t0 - tModel) / 1e9 // the reference model, the memory image and the input files
    val harnessParams = p.copy(maxSteps = None)
    val shell = FirtoolHarness.shellOnce((harnessParams, setup), new SimHarness(harnessParams, setup), work.resolve("harness"))(_.io)
    RawTester.test(shell.gen(), Seq(VerilatorBackendAnnotation, TargetDirAnnotation(work.resolve("rtl").toString),
      CachingAnnotation) ++ build.withSources(shell.sources) ++ o.waves.map(_ => WriteVcdAnnotation)) { dut =>
      dut.clock.setTimeout(0)
      dut.io.readIdx.poke(0.U)
      dut.io.rayCount.poke(rays.count.U) // what the host's stream holds
      dut.io.errorSticky.poke(o.errorSticky.B)
      // The host driver's sequence (docs/registers.md, "Driver contract"): the image is in DRAM already.
      val host = new HostDriver(dut.io.lite, dut.clock)
      host.idle()
      val regs = HostSession.configure(host, p, layout.primBaseBytes, rays.count)
      // CPU time of this thread (the model steps in it): cycles per CPU second hardly move with the machine's load
      val threads = java.lang.management.ManagementFactory.getThreadMXBean
      val cpuSim = threads.getCurrentThreadCpuTime
      val tSim = System.nanoTime()
      var stepped = 0L
      val chunk = 20000
      var lastReport = System.nanoTime()
      while (!dut.io.irq.peek().litToBoolean && stepped < maxCycles) {
        val n = math.min(chunk.toLong, maxCycles - stepped).toInt // the cycle limit is exact
        dut.clock.step(n); stepped += n
        if (System.nanoTime() - lastReport > 5e9) {
          System.err.println(f"[simulate] ${stepped / 1e6}%.1fM cycles, ${dut.io.received.peek().litValue}/${rays.count} hits")
          lastReport = System.nanoTime()
        }
      }
      dut.clock.step(256) // a hit beyond the batch would show up here as a duplicate
      val tEnd = System.nanoTime()
      val simWall = (tEnd - tSim) / 1e9
      val simCpu = (threads.getCurrentThreadCpuTime - cpuSim) / 1e9
      val received = dut.io.received.peek().litValue.toLong
      val (tlasts, tlastAt) = (dut.io.tlasts.peek().litValue.toLong, dut.io.tlastAt.peek().litValue.toLong)
      val finish = HostSession.finish(host)
      val counters = finish.counters
      val cycles = counters("batch_cycles")
      val rtl = readHits(dut, received, rays.count)
      val hits = rtl.hits
      val tHits = System.nanoTime()
      val cmp = compare(rtl, model, stats, mayFail)
      import cmp.{lost, mismatch, overflowDisagree, readErrorDisagree, stepLimitDisagree}
      val (rtlOverflow, rtlReadError, rtlStepLimit) = (rtl.overflow, rtl.readError, rtl.stepLimit)
      // caches: the RTL's counts against the trace model replaying the RTL's own access order (must be equal)
      // and against the model's N-TU interleaved order (the fast model's prediction)
      // one log per IU cluster, each the order its own caches saw
      val logged = if (!cached) Seq.fill(p.memControllers)(Array.empty[Int]) else Seq.tabulate(p.memControllers) { c =>
        val nLog = dut.io.logCount(c).peek().litValue.toInt
        if (nLog > logCap) throw new InputError(s"the RTL made $nLog accesses, more than the model's ${accessRows.length / 5}")
        val w = SimSetup.logWords; val a = new Array[Int](nLog)
        for (row <- 0 until (nLog + w - 1) / w) {
          dut.io.readIdx.poke(row.U); val bits = dut.io.logData(c).peek().litValue
          for (k <- 0 until math.min(w, nLog - row * w)) a(row * w + k) = ((bits >> (32 * k)) & 0xffffffffL).toLong.toInt
        }
        a
      }
      // the lookups the caches turned into refetches of a poisoned line, per MC
      val refetched = if (!cached) Nil else Seq.tabulate(p.memControllers) { c =>
        val n = dut.io.refetchCount(c).peek().litValue.toInt
        if (n > logCap) throw new InputError(s"the caches refetched $n poisoned lines, more than the ${logCap} lookups the simulator logs")
        (0 until n).map { k => dut.io.readIdx.poke(k.U); dut.io.refetchData(c).peek().litValue.toInt }.toArray
      }
      val tLog = System.nanoTime()
      val cacheJson = CacheReport.simulate(p, counters, logged, accessRows, img.codec, refetched)
      System.err.println(f"[simulate] readout: hits ${(tHits - tEnd) / 1e9}%.1f s, access log ${(tLog - tHits) / 1e9}%.1f s " +
        f"(${logged.map(_.length).sum} entries), cache check ${(System.nanoTime() - tLog) / 1e9}%.1f s")
      val duplicated = rtl.seen.count(_ > 1) + math.max(0L, received - rays.count).toInt
      // what the host got: a ray is usable when its record came back without a fault flag ("ok" says only that the
      // hardware did what the model says; a run whose every ray read an error is ok, and not healthy)
      val usable = (0 until rays.count).count(i => rtl.seen(i) > 0 && !rtlOverflow(i) && !rtlReadError(i) && !rtlStepLimit(i))
      val (nOverflow, nReadError, nStepLimit) = (rtlOverflow.count(identity), rtlReadError.count(identity), rtlStepLimit.count(identity))
      System.err.println(s"[simulate] usable: $usable of ${rays.count} rays ($nReadError read errors, " +
        s"$nOverflow stack overflows, $nStepLimit step limits, ${rays.count - rtl.seen.count(_ > 0)} not returned)")
      val n = rays.count.toDouble
      val peakBytesPerCycle = p.memPeakBytesPerSecondTotal / p.cyclesPerSecond
      // the knobs as the circuit ran them (config.Knobs.echo), then the run's own figures
      val json = ujson.Obj.from(rtaccel.config.Knobs.echo(p, "simulate") ++ Seq[(String, ujson.Value)](
        "rays" -> rays.count, "cycles" -> cycles.toDouble,
        "rays_per_s_at_clock" -> n / math.max(1, cycles) * p.cyclesPerSecond,
        "mismatch_vs_model" -> mismatch, "mismatch_examples" -> cmp.examples, "lost" -> lost, "duplicated" -> duplicated,
        "node_bytes_per_ray" -> counters("node_requests") * p.nodeAccessBytes / n,
        // packed: the MC's requested bytes less the nodes' (leafBytes per leaf, whole beats)
        "prim_bytes_per_ray" -> (if (p.primPacked) (counters("mem_bytes") - counters("node_requests") * p.nodeStrideBytes).toDouble
          else (counters("prim_requests") * p.primAccessBytes).toDouble) / n,
        "mem_utilisation" -> counters("mem_busy_beats") * axi.beatBytes / (math.max(1, cycles) * peakBytesPerCycle),
        "sim_cycles_per_wall_s" -> stepped / simWall, "sim_wall_s" -> simWall, "sim_build" -> build.name,
        "sim_cycles_per_cpu_s" -> stepped / math.max(1e-9, simCpu), "sim_cpu_s" -> simCpu,
        // where the wall time went: model + inputs, simulator build (or cache load) + host setup, the run, readout and checks
        "wall_model_s" -> modelWall, "wall_build_s" -> (tSim - t0) / 1e9, "wall_readout_s" -> (System.nanoTime() - tEnd) / 1e9,
        "scene" -> label, "model_restarts" -> stats.restarts.toDouble, "overflowed" -> nOverflow, "model_overflowed" -> stats.overflows,
        "stack_overflow_rays" -> nOverflow, "model_stack_overflow_rays" -> stats.overflows,
        "overflow_disagreements" -> overflowDisagree, "read_errors" -> nReadError,
        "model_read_errors" -> stats.readErrors, "read_error_disagreements" -> readErrorDisagree,
        "mem_error_rate" -> o.memErrorRate, "mem_error_beats" -> counters("mem_read_errors").toDouble,
        "step_limit_rays" -> nStepLimit, "model_step_limit_rays" -> stats.stepLimits,
        "step_limit_disagreements" -> stepLimitDisagree,
        "mem_error_mode" -> (if (o.errorSticky) MemFaults.Sticky else MemFaults.Transient),
        "mem_retries" -> counters("mem_retries").toDouble,
        // lookups that found their line poisoned (an errored fill) and read it again (null without a cache)
        "poison_refetches" -> (if (cached) ujson.Num(refetched.map(_.length).sum) else ujson.Null),
        "health" -> ujson.Obj("usable" -> usable, "read_error" -> nReadError, "overflow" -> nOverflow,
          "step_limit" -> nStepLimit, "retries" -> counters("mem_retries").toDouble, "error_beats" -> counters("mem_read_errors").toDouble),
        "hit_tlast" -> ujson.Obj("beats" -> tlasts.toDouble, "at" -> tlastAt.toDouble),
        "node_requests" -> counters("node_requests").toDouble, "model_node_fetches" -> stats.nodeFetches.toDouble,
        "prim_requests" -> counters("prim_requests").toDouble, "model_prim_tests" -> stats.primTests.toDouble,
        "timed_out" -> (received < rays.count || !finish.irqDone), "normalize_exponent" -> o.scaleExp,
        "mem_jitter" -> dram.randomExtraLatency, "host_stall_percent" -> setup.hostStallPercent,
        "counters" -> ujson.Obj.from(counters.map { case (k, v) => k -> ujson.Num(v.toDouble) }),
        "status" -> finish.statusJson, "irq_done" -> finish.irqDone,
        "dram_bytes_per_ray" -> counters("mem_busy_beats") * axi.beatBytes / n,
        "node_cache" -> cacheJson.node, "prim_cache" -> cacheJson.prim, "cache_counts_match_model" -> cacheJson.matches,
        // per IU cluster: the accesses its MC accepted (logged with a cache only): how the TC balanced the clusters
        "cluster_accesses" -> (if (cached) ujson.Arr.from(logged.take(p.ius).map(l => ujson.Num(l.length))) else ujson.Null),
        // NODE_BANKS: the node references each bank of the shared node cache accepted (how evenly the ids spread)
        "bank_accesses" -> (if (cached && p.nodeShared) ujson.Arr.from(logged.drop(p.ius).map(l => ujson.Num(l.length))) else ujson.Null),
        "wall_s" -> (System.nanoTime() - t0) / 1e9, "rtaccel" -> rtaccel.config.Version.current))
      json("roofline") = if (rays.count == 0 || cycles == 0) ujson.Null // docs/roofline.md
        else rtaccel.perf.Roofline.of(p, rtaccel.perf.Roofline.Run.fromCounters(rays.count, counters)).json
      val failed = failures(json)
      json("ok") = failed.isEmpty; json("failures") = ujson.Arr.from(failed.map(ujson.Str(_)))
      result = Outcome(json, hits)
    }
    if (result == null) throw new InputError("simulation did not complete")
    o.waves match {
      case Some(win) =>
        val vcds = Files.walk(work.resolve("rtl")).toArray.map(_.asInstanceOf[Path]).filter(_.toString.endsWith(".vcd"))
        if (vcds.isEmpty) throw new InputError(s"WAVES=1 but the simulator wrote no VCD under $work/rtl")
        result.copy(vcd = Some(vcds.maxBy(f => Files.getLastModifiedTime(f).toMillis) -> win))
      case None => result
    }
  }
}
