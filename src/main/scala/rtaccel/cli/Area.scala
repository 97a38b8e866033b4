package rtaccel.cli

import java.nio.file.{Files, Path, Paths}
import java.security.MessageDigest
import rtaccel.area.{Board, Boards, Resources, Yosys}
import rtaccel.io.InputError

/** make area: FPGA resources of a configuration from a Yosys synthesis for the board's family, per unit and in
  * total, and whether it fits the board (exit 3 when it does not). Results are cached per circuit (hash of the
  * emitted Verilog, the Yosys version, the family and the top), since the whole platform takes minutes.
  * UNIT=<module> synthesizes one module of the design (e.g. BoxPipe) instead of the board top.
  */
object Area {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.area)(main0)

  def main0(a: Args): Unit = {
    val t0 = System.nanoTime()
    a.opt("fidelity").filter(_ != "yosys").foreach(f => throw new InputError(
      s"FIDELITY=$f is not available: only FIDELITY=yosys (a real synthesis) is built so far"))
    val board = Boards.byName(a.get("board", "xc5vlx330t"), a.opt("catalog").map(Paths.get(_)).getOrElse(Boards.defaultPath))
    // (the board's memory and clock reach the configuration through Cli.params as for every command)
    val p = EmitVerilog.preset(a, "make area")
    val out = Paths.get(a.get("out", s"build/area/${p.name}-${board.name}"))
    val rtl = out.resolve("rtl")
    val files = EmitVerilog.emit(p, rtl).filter(_.toString.endsWith(".sv"))
    val top = a.get("unit", "RtAccelTop")
    val modulesInRtl = files.map(_.getFileName.toString.stripSuffix(".sv")).toSet
    if (!modulesInRtl(top))
      throw new InputError(s"UNIT=$top is not a module of config '${p.name}'; choose one of ${modulesInRtl.toSeq.sorted.mkString(", ")}")
    val version = Yosys.version()
    val key = hash(files, s"$version ${board.family} $top")
    val cache = Paths.get(a.get("cache", "build/area-cache")).resolve(key)
    val stat = cache.resolve("stat.json")
    val cached = Files.isRegularFile(stat)
    if (!cached) {
      Files.createDirectories(cache)
      System.err.println(s"[area] synthesizing $top of '${p.name}' for ${board.family} with Yosys $version (minutes for the whole platform)")
      val tmp = cache.resolve("stat.json.tmp")
      Yosys.synthesize(files, top, board.family, cache.resolve("yosys.log"), tmp, line => System.err.println(s"[area] ${line.take(120)}"))
      Files.move(tmp, stat)
    } else System.err.println(s"[area] cached synthesis $cache")
    val unknown = scala.collection.mutable.Set[String]()
    val mods = Yosys.modules(stat)
    val per = Yosys.rollUp(mods, unknown)
    val total = per.getOrElse(top, throw new InputError(s"Yosys reported no module $top (see ${cache.resolve("yosys.log")})"))
    val instances = countInstances(mods, top)
    val verdict = fits(total, board)
    printTable(p.name, board, top, total, per, instances, verdict)
    val json = ujson.Obj(
      "config" -> p.name, "board" -> board.name, "family" -> board.family, "fidelity" -> "yosys", "top" -> top,
      "lut" -> total.lut.toDouble, "lutram" -> total.lutram.toDouble, "ff" -> total.ff.toDouble, "dsp" -> total.dsp.toDouble,
      "bram36" -> total.bram36, "carry" -> total.carry.toDouble, "fits" -> verdict.isEmpty,
      "first_overflow" -> verdict.fold[ujson.Value](ujson.Null) { case (r, used, have) =>
        ujson.Obj("resource" -> r, "used" -> used, "available" -> have.toDouble) },
      "utilisation" -> ujson.Obj.from(total.used.zip(board.capacities).map { case ((r, u), (_, c)) => r -> ujson.Num(u / c) }),
      "units" -> ujson.Obj.from(instances.toSeq.sortBy(_._1).map { case (m, n) =>
        m -> { val o = per(m).json; o("instances") = n.toDouble; o } }),
      "lut_levels" -> ujson.Null, // the timing proxy is not built yet: left empty, never invented
      "unclassified_cells" -> ujson.Arr.from(unknown.toSeq.sorted.map(ujson.Str(_))),
      "yosys_version" -> version, "cached" -> cached, "cache" -> cache.toString,
      "tus" -> p.tus, "m" -> p.m, "mppl" -> p.mppl, "wall_s" -> (System.nanoTime() - t0) / 1e9, "rtaccel" -> Cli.version)
    Cli.writeText(out.resolve("area.json"), ujson.write(json, indent = 2) + "\n")
    println(ujson.write(json))
    verdict.foreach { case (r, used, have) => throw new CheckFailed(Seq(f"does not fit ${board.name}: $r $used%.0f > $have")) }
  }

  /** The first resource (lut, ff, dsp, bram36) the design needs more of than the board has. */
  def fits(r: Resources, b: Board): Option[(String, Double, Long)] =
    r.used.zip(b.capacities).collectFirst { case ((name, used), (_, have)) if used > have => (name, used, have) }

  /** How many times each module is instantiated in the design under `top` (top itself once). */
  def countInstances(mods: Map[String, Map[String, Long]], top: String): Map[String, Long] = {
    val n = scala.collection.mutable.Map[String, Long]().withDefaultValue(0L)
    def walk(m: String, k: Long): Unit = { n(m) += k; mods.getOrElse(m, Map.empty).foreach { case (t, c) => if (mods.contains(t)) walk(t, k * c) } }
    walk(top, 1)
    n.toMap
  }

  private def hash(files: Seq[Path], extra: String): String = {
    val md = MessageDigest.getInstance("SHA-256")
    for (f <- files.sortBy(_.getFileName.toString)) { md.update(f.getFileName.toString.getBytes); md.update(Files.readAllBytes(f)) }
    md.update(extra.getBytes)
    md.digest().take(12).map("%02x".format(_)).mkString
  }

  private def printTable(cfg: String, b: Board, top: String, total: Resources, per: Map[String, Resources],
                         inst: Map[String, Long], verdict: Option[(String, Double, Long)]): Unit = {
    val e = Console.err
    e.println(f"[area] $cfg ($top) on ${b.name} (${b.part}, ${b.family}):")
    e.println(f"  ${"unit"}%-28s ${"x"}%5s ${"LUT"}%9s ${"LUTRAM"}%7s ${"FF"}%9s ${"DSP"}%6s ${"BRAM36"}%7s")
    for ((m, n) <- inst.toSeq.sortBy { case (m, n) => -(per(m).lut * n) }) {
      val r = per(m)
      e.println(f"  $m%-28s $n%5d ${r.lut}%9d ${r.lutram}%7d ${r.ff}%9d ${r.dsp}%6d ${r.bram36}%7.1f")
    }
    e.println(f"  ${"board capacity"}%-28s ${""}%5s ${b.lut}%9d ${""}%7s ${b.ff}%9d ${b.dsp}%6d ${b.bram36}%7d")
    e.println(verdict.fold(f"  fits ${b.name}")(v => f"  does NOT fit ${b.name}: ${v._1} ${v._2}%.0f > ${v._3}"))
  }
}
