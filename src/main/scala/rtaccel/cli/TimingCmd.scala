package rtaccel.cli

import java.nio.file.{Files, Path, Paths, StandardCopyOption}
import rtaccel.area.{Boards, Route, Routed, Timing}
import rtaccel.io.InputError

/** make timing: the routed clock of a configuration (the board top) or of one unit alone (UNIT=), from the open
  * ECP5 flow (area.Route: Yosys synth_ecp5, nextpnr-ecp5), inside the wrapper that makes every path register to
  * register (area.TimingWrap). Exit 3 when the clock misses its target (CLOCK_MHZ, else the board's) or the
  * design does not fit the part; the JSON line is printed last either way. Cached per circuit and seed.
  */
object TimingCmd {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.timing)(main0)

  /** The board routed on when BOARD= is not given. */
  val DefaultBoard = "ecp5-85"

  def main0(asked: Args): Unit = {
    val t0 = System.nanoTime()
    // the default board stands for BOARD= everywhere, the circuit's PIPELINE budget included: without it the preset
    // would be pipelined for its own board's family and clock, and routed on another
    val a = if (asked.opt("board").isDefined) asked else Args(asked.kv + ("board" -> DefaultBoard))
    val catalog = a.opt("catalog").map(Paths.get(_)).getOrElse(Boards.defaultPath)
    val board = Boards.byName(a.need("board"), catalog)
    val part = board.ecp5.getOrElse(throw new InputError(s"BOARD=${board.name} is a ${board.family} board; make timing routes " +
      s"ECP5 parts only (nextpnr-ecp5): give BOARD=${Boards.ecp5Names(catalog).mkString(" or BOARD=")}"))
    val seeds = a.int("seeds", 1)
    if (seeds < 1 || seeds > 32) throw new InputError(s"TIMING_SEEDS=$seeds: give 1..32 seeds")
    val router = a.get("router", Route.DefaultRouter)
    if (!Route.Routers.contains(router)) throw new InputError(s"TIMING_ROUTER=$router: give ${Route.Routers.mkString(" or ")}")
    val placer = a.get("placer", Route.DefaultPlacer)
    if (!Route.Placers.contains(placer)) throw new InputError(s"TIMING_PLACER=$placer: give ${Route.Placers.mkString(", ")}")
    val speed = a.int("speed", part.speedGrade)
    // nextpnr knows -6, -7 and -8 for LFE5U / LFE5UM parts and -8 alone for the 5G parts (their only grade)
    val grades = if (part.device.startsWith("um5g")) Set(8) else Set(6, 7, 8)
    if (!grades(speed)) throw new InputError(s"SPEED=$speed: ${board.name} (${board.part}) comes in speed grade " +
      s"${grades.toSeq.sorted.mkString(", ")} only${if (grades.size == 1) " (nextpnr has no other for the 5G parts)" else ""}")
    val p = Cli.preset(a, "make timing")
    val unit = a.get("unit", "RtAccelTop")
    // the clock to meet: CLOCK_MHZ (a number, or fmax: a measured one) if given, else the board's
    val target = if (a.opt("clock-mhz").isDefined) p.clockMhz else board.clockMhz
    val cache = Paths.get(a.get("cache", "build/timing-cache"))
    val out = Paths.get(a.get("out", s"build/timing/${p.name}-${board.name}${a.opt("unit").fold("")("-" + _)}"))
    val say = (l: String) => Console.err.println(s"[timing] ${l.take(160)}")

    // emitted beside the cache, not into OUT: a bad UNIT writes nothing
    Files.createDirectories(cache)
    val rtl = Files.createTempDirectory(cache, "rtl")
    val runs = try {
      val files = EmitVerilog.emit(p, rtl).filter(_.toString.endsWith(".sv"))
      val modules = files.map(_.getFileName.toString.stripSuffix(".sv")).toSet
      if (!modules(unit))
        throw new InputError(s"UNIT=$unit is not a module of config '${p.name}'; choose one of ${modules.toSeq.sorted.mkString(", ")}")
      (1 to seeds).map(s => Route.run(Route.Job(files, unit, board, part, speed, s, router, placer), cache, s"$unit of '${p.name}'", say))
    } finally Files.walk(rtl).toArray.map(_.asInstanceOf[Path]).sortBy(-_.getNameCount).foreach(Files.delete)

    // the median run (the lower of the middle two for an even count): a real run whose path is reported whole
    val ranked = runs.sortBy(_.fmaxMhz.getOrElse(0.0))
    val shown = ranked((ranked.length - 1) / 2)
    val j = ujson.Obj.from(rtaccel.config.Knobs.echo(p, "timing") ++
      Seq[(String, ujson.Value)]("board" -> board.name, "family" -> board.family, "unit" -> unit))
    val r = shown.result
    j("fmax_mhz") = r("fmax_mhz"); j("target_mhz") = target
    j("clock_source") = if (a.opt("clock-mhz").isDefined) p.clockSource else "board"
    val met = shown.fits && shown.fmaxMhz.exists(_ >= target)
    j("met") = met
    j("critical_path") = r("critical_path")
    // the LUT-level proxy of the same netlist beside the routed clock (what the ecp5 rule is fitted on)
    j("proxy") = ujson.Obj("lut_levels" -> r.value.getOrElse("proxy_lut_levels", ujson.Null),
      "fmax_mhz" -> r.value.getOrElse("proxy_fmax_mhz", ujson.Null), "rule" -> Timing.forFamily("ecp5").rule)
    for (k <- Seq("lut4", "ff", "mult18", "ebr", "carry", "lutram", "wrapper_ff", "fits", "first_overflow", "seed")) j(k) = r(k)
    j("seeds") = seeds; j("fmax_mhz_seeds") = ujson.Arr.from(runs.map(x => x.result("fmax_mhz")))
    j("fmax_reported") = if (seeds > 1) "median" else "the one seed"
    j("part") = board.part; j("device") = part.device; j("package") = part.pkg; j("speed_grade") = speed; j("router") = router
    j("placer") = placer
    for (k <- Seq("yosys_version", "nextpnr_version", "synth_s", "synth_cached", "pnr_s")) j(k) = r.value.getOrElse(k, ujson.Null)
    j("cached") = runs.forall(_.cached); j("cache") = shown.dir.toString
    j("wall_s") = (System.nanoTime() - t0) / 1e9; j("rtaccel") = Cli.version

    // the full nextpnr log and report of the run shown sit beside timing.json
    Files.createDirectories(out)
    for (f <- Seq(Route.pnrLog, Route.reportFile, "yosys.log") if Files.isRegularFile(shown.dir.resolve(f)))
      Files.copy(shown.dir.resolve(f), out.resolve(f), StandardCopyOption.REPLACE_EXISTING)
    Cli.writeText(out.resolve("timing.json"), ujson.write(j, indent = 2) + "\n")
    table(j, runs)
    println(ujson.write(j))
    if (!shown.fits) {
      val o = r("first_overflow")
      throw new CheckFailed(Seq(f"does not fit ${board.part}: ${o("resource").str} ${o("used").num}%.0f > ${o("available").num}%.0f"))
    }
    if (!met) throw new CheckFailed(Seq(f"fmax ${shown.fmaxMhz.get}%.1f MHz < target $target%.1f MHz (${j("clock_source").str})"))
  }

  private def table(j: ujson.Obj, runs: Seq[Routed]): Unit = {
    val e = Console.err
    e.println(s"[timing] ${j("unit").str} of '${j("config").str}' on ${j("board").str} (${j("part").str}, speed -${j("speed_grade").num.toInt}):")
    e.println(f"  LUT4 ${j("lut4").num}%.0f (carry cells ${j("carry").num}%.0f), FF ${j("ff").num}%.0f (wrapper ${j("wrapper_ff").num}%.0f), " +
      f"MULT18X18D ${j("mult18").num}%.0f, EBR ${j("ebr").num}%.0f")
    if (runs.length > 1) e.println(s"  fmax per seed: ${runs.map(r => r.fmaxMhz.fold("-")(f => f"$f%.1f")).mkString(", ")} MHz (median reported)")
    j("critical_path") match {
      case c: ujson.Obj =>
        e.println(f"  fmax ${j("fmax_mhz").num}%.1f MHz vs target ${j("target_mhz").num}%.1f MHz: ${if (j("met").bool) "met" else "NOT met"}")
        e.println(f"  critical path ${c("ns").num}%.2f ns (logic ${c("logic_ns").num}%.2f, routing ${c("routing_ns").num}%.2f), " +
          f"${c("logic_levels").num}%.0f logic elements: ${c("from").str} -> ${c("to").str}")
      case _ => e.println("  not routed (does not fit)")
    }
    j("proxy")("lut_levels") match {
      case ujson.Num(n) => e.println(f"  proxy: $n%.0f LUT levels, ~${j("proxy")("fmax_mhz").num}%.0f MHz by ${j("proxy")("rule").str}")
      case _ => ()
    }
  }
}
