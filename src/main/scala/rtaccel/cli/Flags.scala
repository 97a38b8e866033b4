package rtaccel.cli

import rtaccel.io.InputError

/** Every command-line flag of the entry points, declared once, and the sets each command accepts.
  * Parsing is scopt's (unknown flags, repeated flags, missing values); values are validated where a
  * command reads them (Args.int etc.), so a message can name the knob and its legal range.
  * A flag that a command does not use is refused rather than ignored: a user who passes NODE_CACHE= to a
  * command without caches must hear that it had no effect.
  */
object Flags {
  final case class Flag(name: String, help: String)
  private def f(name: String, help: String) = Flag(name, help)

  val inputs: Seq[Flag] = Seq(
    f("tris", "triangle file (N x 9 float32 .npy, from tools/tris)"),
    f("rays", "rays.npy (N x 8 float32)"),
    f("scene-label", "scene name recorded in outputs"))
  /** Knobs of PlatformParams, from the registry (config.Knobs: Cli.request checks each value given against its
    * domain; a preset's value is kept unless one is given): the tree, arithmetic, platform and memory knobs ... */
  private def knob(k: rtaccel.config.Knobs.Knob) = f(k.flag, s"${k.help} (${k.make}=; ${k.domain.rule})")
  private val cacheFlags = Set("node-cache", "node-ways", "node-policy", "prim-cache", "prim-ways", "prim-policy", "max-level")
  val model: Seq[Flag] = rtaccel.config.Knobs.all.filterNot(k => cacheFlags(k.flag)).map(knob)
  /** ... and the caches' */
  val cache: Seq[Flag] = rtaccel.config.Knobs.all.filter(k => cacheFlags(k.flag)).map(knob)
  val platform: Seq[Flag] = model ++ cache

  val trace: Seq[Flag] = inputs ++ platform ++ Seq(f("out", "output folder"), f("access-trace", "1 writes trace.npy"),
    f("exhaustive", "the first N rays also against every triangle without boxes: lost_hits counts what a box test lost"))
  val cacheSim: Seq[Flag] = inputs ++ platform ++ Seq(f("sweep-out", "miss-rate grid CSV"), f("repeat", "replays, median timed"))
  val analyze: Seq[Flag] = inputs ++ platform ++ Seq(f("out", "output folder"), f("mppls", "MPPL list"))
  val bench: Seq[Flag] = inputs ++ platform ++ Seq(f("repeat", "repeats, median reported"))
  val simOptions: Seq[Flag] = Seq(f("mem-jitter", "random extra DRAM latency (cycles)"),
    f("host-stall", "host backpressure percentage"), f("seed", "random seed of jitter and stalls"),
    f("work", "simulator build folder"), f("max-cycles", "cycle limit (a run that reaches it timed out)"),
    f("mem-error-rate", "share of DRAM beats answered with SLVERR (MEM_ERROR_RATE, 0..1)"),
    f("mem-error-mode", "transient (a poisoned beat fails its first read only, the default) or sticky (every read) (MEM_ERROR_MODE)"),
    f("waves", "1 writes OUT/waves.vcd (WAVES=)"), f("waves-from", "first cycle of the waveform window"),
    f("waves-to", "last cycle of the waveform window"),
    f("sim-build", "Verilator build profile (SIM_BUILD=, rtaccel.sim.VerilatorBuild)"))
  val simulate: Seq[Flag] = inputs ++ platform ++ simOptions :+ f("out", "output folder")
  val sweepTus: Seq[Flag] = inputs ++ platform ++ Seq(f("out", "output folder"), f("tus-list", "TU counts"))
  val roofline: Seq[Flag] = inputs ++ platform ++ Seq(f("out", "output folder"), f("tus-list", "TU counts of a sweep (ROOFLINE_TUS=)"),
    f("ius-list", "IU counts of a sweep, each with every TU count (ROOFLINE_IUS=)"),
    simOptions.find(_.name == "sim-build").get)
  val verilog: Seq[Flag] = platform :+ f("out", "output folder")
  val area: Seq[Flag] = verilog ++ Seq(f("fidelity", "yosys (a real synthesis) or model (the fitted cost model)"),
    f("unit", "one module to synthesize instead of the board top (UNIT=)"), f("cache", "synthesis cache folder"),
    f("cost-model", "fitted cost model file (default boards/cost-model.json)"))
  val costFit: Seq[Flag] = Seq(f("calibration", "calibration plan (boards/cost-calibration.json)"), f("out", "fitted model file"),
    f("cache", "synthesis cache folder"), f("catalog", "board catalog file"), f("cached-only", "1: fit from the cached syntheses only, leaving out the others"))
  val maxTus: Seq[Flag] = area ++ Seq(f("confirm", "1 (default) confirms the answer with one real synthesis"), f("max", "largest TU count tried"))
  val timing: Seq[Flag] = verilog ++ Seq(f("unit", "one module routed alone inside the timing wrapper instead of the board top (UNIT=)"),
    f("cache", "routing cache folder (default build/timing-cache)"),
    f("seeds", "nextpnr seeds 1..N, the median run reported (TIMING_SEEDS=, default 1)"),
    f("router", "nextpnr's router: router1 (its default) or router2 (TIMING_ROUTER=)"),
    f("placer", "nextpnr's placer: heap (its default), static or sa (TIMING_PLACER=)"),
    f("speed", "ECP5 speed grade 6, 7 or 8 (SPEED=; default the board's)"))
  val timingFit: Seq[Flag] = Seq(f("cache", "routing cache folder (default build/timing-cache)"),
    f("write", "1: write the fitted ecp5 rule into boards/timing.json (WRITE=1)"),
    f("timing", "the timing rules file (default boards/timing.json)"))
  val areaFp: Seq[Flag] = model.filter(fl => Set("board", "catalog", "pipeline", "clock-mhz")(fl.name)) ++ Seq(
    f("ops", "fp32 operations to synthesize, comma-separated (OPS=; default all)"), f("out", "output folder"),
    f("cache", "synthesis cache folder"))

  /** Levenshtein distance, for the "did you mean" of a misspelled flag. */
  def distance(a: String, b: String): Int = {
    val d = Array.tabulate(a.length + 1, b.length + 1)((i, j) => if (i == 0) j else if (j == 0) i else 0)
    for (i <- 1 to a.length; j <- 1 to b.length)
      d(i)(j) = math.min(math.min(d(i - 1)(j) + 1, d(i)(j - 1) + 1), d(i - 1)(j - 1) + (if (a(i - 1) == b(j - 1)) 0 else 1))
    d(a.length)(b.length)
  }

  def nearest(name: String, flags: Seq[Flag]): String = flags.map(_.name).minBy(n => (distance(name, n), n))

  /** `--key value` pairs into Args; the first problem becomes one InputError naming the flag. */
  def parse(argv: Array[String], flags: Seq[Flag]): Args = {
    val builder = scopt.OParser.builder[Map[String, String]]
    import builder._
    val parser = scopt.OParser.sequence(programName("rtaccel"),
      flags.map(fl => opt[String](fl.name).maxOccurs(1).action((v, m) => m + (fl.name -> v)).text(fl.help)): _*)
    val setup = new scopt.DefaultOParserSetup { override def showUsageOnError: Option[Boolean] = Some(false) }
    val (result, effects) = scopt.OParser.runParser(parser, argv.toSeq, Map.empty[String, String], setup)
    val errors = effects.collect { case scopt.OEffect.ReportError(msg) => msg }
    result match {
      case Some(kv) if errors.isEmpty => Args(kv)
      case _ => throw new InputError(explain(errors.headOption.getOrElse("bad arguments"), argv, flags))
    }
  }

  private val UnknownOpt = """Unknown option --(.+)""".r
  private val UnknownArg = """Unknown argument '(.*)'""".r
  private def explain(msg: String, argv: Array[String], flags: Seq[Flag]): String = msg match {
    case UnknownOpt(name) if flags.exists(_.name == name) =>
      s"flag --$name is given more than once; give it once"
    case UnknownOpt(name) =>
      s"unknown flag --$name; did you mean --${nearest(name, flags)}?"
    case UnknownArg(arg) => s"unexpected argument '$arg'; arguments are --flag value pairs"
    case m if m.startsWith("Missing value") => s"${m.toLowerCase}: every flag takes a value"
    case m => m
  }
}
