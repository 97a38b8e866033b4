package rtaccel.cli

import java.nio.file.{Path, Paths}
import rtaccel.config.{BoxRange, CacheParams, CachePolicy, Fit, Numerics, PlatformParams, Pipelining, Presets, RequestedParams, RespOrder, TriTest}
import rtaccel.bvh.Mbvh
import rtaccel.io.{InputError, Npy}
import rtaccel.scene.{Normalize, Rays, Scene}

/** Shared plumbing of the command-line entry points the Makefile calls. */
object Cli {
  val version: String = rtaccel.config.Version.current

  /** Runs a command body; user errors become one `error:` line and status 2 (returned for tests). */
  def status(args: Array[String], flags: Seq[Flags.Flag])(body: Args => Unit): Int =
    try { body(Flags.parse(args, flags)); 0 }
    catch {
      case e: CheckFailed => Console.err.println(s"error: check failed: ${e.failures.mkString(", ")}"); 3
      case e: InputError => Console.err.println(s"error: ${e.getMessage}"); 2
      case e: IllegalArgumentException =>
        Console.err.println(s"error: ${e.getMessage.stripPrefix("requirement failed: ")}")
        if (sys.env.contains("RTACCEL_DEBUG")) e.printStackTrace()
        2
    }
    finally System.out.flush()

  /** `main` of an entry point: exits with the status when it is not 0. */
  def run(args: Array[String], flags: Seq[Flags.Flag])(body: Args => Unit): Unit = {
    val code = status(args, flags)(body)
    if (code != 0) sys.exit(code)
  }

  /** What the command line asks for (config.RequestedParams). A preset is the whole platform it names, caches included (paper2017: its 2^13-entry DM node cache);
    * every flag given overrides one field (--node-cache 0 removes the cache). CONFIG=<preset> keeps the
    * preset's fixed widths and refuses scenes that exceed them; CONFIG=fit (default) starts from paper2017
    * and fits field widths and stack depth to the scene. An explicit --stack-depth (STACK=) is kept even
    * below what the scene needs: rays that need more are flagged overflow (see Cli.build).
    */
  def request(a: Args): RequestedParams = {
    for (k <- rtaccel.config.Knobs.all; v <- a.opt(k.flag)) rtaccel.config.Knobs.check(k, v)
    val cfg = a.get("config", "fit")
    val preset = if (cfg == "fit") Presets.paper2017.copy(name = "fit") else Presets.byName(cfg)
    // BOARD= brings its memory bandwidth and clock; MEM_GBPS= / CLOCK_MHZ= override either
    val board = a.opt("board").map(b => rtaccel.area.Boards.byName(b, a.opt("catalog").map(Paths.get(_)).getOrElse(rtaccel.area.Boards.defaultPath)))
    val gbps = a.opt("mem-gbps").map(_ => a.double("mem-gbps", 0)).orElse(board.map(_.dramGbps))
    // CLOCK_MHZ=fmax is resolved below, once the circuit is known; a preset's own clock is its paper board's
    val fmax = a.opt("clock-mhz").contains("fmax")
    val mhz = a.opt("clock-mhz").filter(_ => !fmax).map(_ => a.double("clock-mhz", 0) -> "given").orElse(board.map(_.clockMhz -> "board"))
    val base = preset.copy(memory = gbps.fold(preset.memory)(g => preset.memory.copy(bytesPerSecond = g * 1e9)),
      clockMhz = mhz.fold(preset.clockMhz)(_._1), clockSource = mhz.fold("board")(_._2), family = board.map(_.family).getOrElse(preset.family),
      pipelining = a.opt("pipeline").map(Pipelining.parse).getOrElse(preset.pipelining))
    val respOrder = a.opt("resp-order").map(RespOrder.parse)
    val p = base.copy(m = a.int("m", base.m), mppl = a.int("mppl", base.mppl), tus = a.int("tus", base.tus), ius = a.int("ius", base.ius), memChannels = a.int("mem-channels", base.memChannels),
      respByPath = respOrder.fold(base.respByPath)(_ != RespOrder.Request),
      respTagged = respOrder.fold(base.respTagged)(_ == RespOrder.Tagged),
      rayStore = a.switch("ray-store", "RAY_STORE", base.rayStore,
        "1 (rays kept in each IU's ray store, requests carry the TU's index) or 0 (every request carries its ray, the paper's)"),
      tagForward = a.switch("tag-forward", "TAG_FORWARD", base.tagForward,
        "1 (cache tags take one lookup per cycle, forwarding the set just written) or 0 (one lookup per two cycles)"),
      nodeBanks = a.int("node-banks", base.nodeBanks),
      memRetries = a.int("mem-retries", base.memRetries),
      nodeAccessBytesOverride = a.int("node-bytes", base.nodeAccessBytesOverride),
      primAccessBytes = a.int("prim-bytes", base.primAccessBytes),
      stackDepth = a.int("stack-depth", base.stackDepth), shortStack = a.int("short-stack", base.shortStack),
      maxSteps = a.opt("max-steps").map(_ => a.int("max-steps", 0)).orElse(base.maxSteps),
      // m<M> (boxFit below): the exponent fitted to the scene in build()
      boxFormat = a.opt("box-format").filter(BoxRange.fitRequest(_).isEmpty).map(rtaccel.fp.FpFormat.parse).getOrElse(base.boxFormat),
      triTest = a.opt("tri-test").map(TriTest.parse).getOrElse(base.triTest),
      triFormat = a.opt("tri-format").map(Numerics.parseTriFormat).getOrElse(base.triFormat),
      triInterval = a.int("tri-ii", base.triInterval), boxInterval = a.int("box-ii", base.boxInterval),
      // fit: the narrowest quantization the scene needs, chosen in build()
      nodeQuantBits = a.opt("node-format").filter(_ != "fit").map(Numerics.parseNodeFormat).getOrElse(base.nodeQuantBits),
      primPacked = a.opt("prim-format").map(Numerics.parsePrimFormat).getOrElse(base.primPacked),
      nodeCache = cacheArg(a, "node", base.nodeCache), primCache = cacheArg(a, "prim", base.primCache))
    val req = RequestedParams(p, fitWidths = cfg == "fit", boxFit = a.opt("box-format").flatMap(BoxRange.fitRequest),
      nodeFit = a.opt("node-format").contains("fit"), stackGiven = a.opt("stack-depth").nonEmpty)
    if (!fmax) req
    else {
      if (cfg == "fit") throw new InputError("CLOCK_MHZ=fmax needs CONFIG=<preset>: a fitted configuration's circuit depends on the scene, " +
        "so no routed or synthesized clock of it can be cached; give CONFIG=paper2017 (or another preset) or CLOCK_MHZ=<MHz>")
      // the clock measured belongs to one circuit: a format the scene fits is not known yet
      val q = req.withoutScene("CLOCK_MHZ=fmax")
      val b = board.getOrElse(rtaccel.area.Boards.byName("xc5vlx330t", a.opt("catalog").map(Paths.get(_)).getOrElse(rtaccel.area.Boards.defaultPath)))
      val (f, src) = rtaccel.area.ClockSource.resolve(q, b, makeArgs(a))
      Console.err.println(f"[clock] CLOCK_MHZ=fmax: $f%.1f MHz ($src, ${b.name})")
      // the circuit stays the one built for the target clock (PIPELINE=auto's budget), now timed at its measured clock
      req.map(_ => q.copy(clockMhz = f, clockSource = src, pipelineMhz = Some(q.pipelineMhz.getOrElse(q.clockMhz))))
    }
  }

  /** The platform of a preset as the command line asks for it, for a command that builds a circuit without a scene
    * (`what` names it: make verilog, area, timing, max-tus, the cost fit): refused when a part of it needs a scene
    * (RequestedParams.withoutScene) or when the RTL cannot build its caches. */
  def preset(a: Args, what: String): PlatformParams = {
    val p = request(a).withoutScene(what)
    rtaccel.cache.hw.CachePath.validate(p)
    p
  }

  /** The platform knobs of `a` as the make variables that set them (CONFIG first; BOARD and CLOCK_MHZ left out),
    * for a message that names the command to run. */
  def makeArgs(a: Args): String = {
    val skip = Set("config", "board", "clock-mhz", "catalog", "node-bytes", "prim-bytes")
    val knobs = rtaccel.config.Knobs.all.filterNot(k => skip(k.flag)).flatMap(k => a.opt(k.flag).map(v => s"${k.make}=$v"))
    (s"CONFIG=${a.get("config", "fit")}" +: knobs).mkString(" ")
  }

  /** NODE_CACHE/NODE_WAYS/NODE_POLICY (or PRIM_...) and MAX_LEVEL over the preset's cache `base`. Without
    * a policy flag the preset's policy is kept, unless the preset had no cache or the ways make it
    * meaningless (dm with several ways): then dm for one way, lru otherwise.
    */
  def cacheArg(a: Args, prefix: String, base: CacheParams): CacheParams = {
    val entries = a.int(s"$prefix-cache", base.entries)
    if (entries < 0) throw new InputError(s"--$prefix-cache must be >= 0 (got $entries)")
    val ways = a.int(s"$prefix-ways", base.ways)
    val inherited = base.entries > 0 && !(base.policy == CachePolicy.Dm && ways > 1)
    val pol = a.opt(s"$prefix-policy").map(CachePolicy.parse)
      .getOrElse(if (inherited) base.policy else if (ways == 1) CachePolicy.Dm else CachePolicy.Lru)
    CacheParams(entries = entries, ways = ways, policy = pol, maxLevel = a.int("max-level", base.maxLevel))
  }

  type Built = rtaccel.config.Built
  val Built: rtaccel.config.Built.type = rtaccel.config.Built

  /** Builds the tree and fits (or checks) the configuration. `stack` = an explicit STACK=, kept as given:
    * below the scene's bound it is a warning, not a refusal, so that overflow can be provoked and tested.
    */
  def build(scene: Scene, p0: PlatformParams, fit: Boolean, stack: Option[Int] = None): Built = {
    val t0 = System.nanoTime()
    // the tree depends on the scene and these fields only (Mbvh.build); Serve keeps it between requests
    val bvh = Memo("bvh", (new Memo.Id(scene), p0.m, p0.mppl, p0.sahBins, p0.treeNodeBytes, p0.primAccessBytes))(Mbvh.build(scene, p0))
    val secs = (System.nanoTime() - t0) / 1e9
    val need = Fit.needs(bvh).stackDepth
    val p = stack match {
      case Some(s) =>
        val q = (if (fit) Fit.fitTo(p0, bvh) else p0).copy(stackDepth = s)
        if (!fit) Fit.check(q.copy(stackDepth = math.max(s, need)), bvh, scene.name)
        if (s < need) Console.err.println(s"[warn] STACK=$s is below the $need entries this tree can need: rays that " +
          "need more are flagged overflow (prim -3)")
        q
      case None => if (fit) Fit.fitTo(p0, bvh) else { Fit.check(p0, bvh, scene.name); p0 }
    }
    Built(scene, p, bvh, secs)
  }

  /** The request resolved on a scene and its rays: the tree built, the widths fitted (CONFIG=fit) or checked, the box
    * format fitted (BOX_FORMAT=m<M>) or checked against the depth of the scene along these rays (config.BoxRange), and
    * NODE_FORMAT=fit's narrowest quantization (model.FormatFit).
    */
  def build(scene: Scene, rays: Rays, req: RequestedParams): Built = {
    val b = build(scene, req.unfitted, req.fitWidths, if (req.stackGiven) Some(req.base.stackDepth) else None)
    val depth = Memo("box-depth", (new Memo.Id(scene), new Memo.Id(rays)))(BoxRange.depth(scene, rays))
    def measure(m: Int, d: Double) = rtaccel.model.FormatFit.boxExponent(rtaccel.bvh.MemoryImage.pack(b.bvh, b.scene, b.params), rays, m, d)
    val boxed = BoxRange.fit(b.params, req.boxFit, depth, scene.name, measure)
    b.copy(params = if (req.nodeFit) rtaccel.model.FormatFit.nodeFormat(b.bvh, b.scene, boxed, rays) else boxed)
  }

  /** The scene and rays as the host driver uploads them: scaled by one power of two (see Normalize). */
  def inputs(a: Args): (Scene, Rays, Int) = {
    // Serve keeps both between requests (Memo); the scene is the same object then, so its tree is found too
    val (scene, e) = Memo.file("scene", a.path("tris")) {
      val raw = Scene.load(a.path("tris")); val e = Normalize.exponent(raw); (Normalize.scene(raw, e), e)
    }
    val rays = Memo.file("rays", a.path("rays"), e)(Normalize.rays(Rays.load(a.path("rays")), e))
    (scene, rays, e)
  }

  def writeText(path: Path, text: String): Unit = Npy.atomicWrite(path, text.getBytes("UTF-8"))
}

/** `--key value` arguments; every value a command reads is validated where it is read. */
final case class Args(kv: Map[String, String]) {
  def get(k: String, default: String): String = kv.getOrElse(k, default)
  def opt(k: String): Option[String] = kv.get(k).filter(_.nonEmpty)
  def need(k: String): String = opt(k).getOrElse(throw new InputError(s"missing --$k"))
  def path(k: String): Path = Paths.get(need(k))
  def int(k: String, default: Int): Int = opt(k).map(v => v.toIntOption.getOrElse(
    throw new InputError(s"--$k must be an integer (got '$v')"))).getOrElse(default)
  /** A 0/1 knob (make variable `name`); `meaning` says what each value does in the error for any other value. */
  def switch(k: String, name: String, default: Boolean, meaning: String): Boolean = opt(k).map {
    case "0" => false
    case "1" => true
    case v => throw new InputError(s"$name=$v: use $meaning")
  }.getOrElse(default)
  def double(k: String, default: Double): Double = opt(k).map(v => v.toDoubleOption.filter(!_.isNaN).getOrElse(
    throw new InputError(s"--$k must be a number (got '$v')"))).getOrElse(default)
}

/** A check of a run that completed failed (exit status 3); the run's outputs and JSON are already written. */
final class CheckFailed(val failures: Seq[String]) extends Exception(failures.mkString(", "))
