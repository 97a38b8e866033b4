package rtaccel.cli

import java.nio.file.Paths
import rtaccel.area.{Board, Boards, Resources, Synthesis, Timing}
import rtaccel.io.InputError

/** make area: FPGA resources of a configuration from a Yosys synthesis for the board's family, per unit and in
  * total, and whether it fits the board (exit 3 when it does not). Results are cached per circuit (area.Synthesis:
  * hash of the emitted Verilog, the Yosys version, the family, the top and the script), since the whole platform
  * takes minutes. The deepest path in LUT levels is reported beside the resources (a timing proxy, docs/area.md).
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
    val syn = Synthesis.run(files, top, board.family, Paths.get(a.get("cache", "build/area-cache")), s"$top of '${p.name}'",
      line => System.err.println(s"[area] ${line.take(120)}"), Cli.version)
    val (total, per, instances, version, cache, cached) = (syn.total, syn.resources, syn.instances, syn.version, syn.cache, syn.cached)
    val (deepUnit, deepLevels) = syn.deepest
    val timing = Timing.forFamily(board.family)
    val verdict = fits(total, board)
    printTable(p.name, board, top, total, per, instances, syn.levels, verdict)
    System.err.println(f"  deepest path: $deepLevels LUT levels in $deepUnit, ~${timing.fmaxMhz(deepLevels)}%.0f MHz (a proxy: no placement or routing)")
    val json = ujson.Obj(
      "config" -> p.name, "board" -> board.name, "family" -> board.family, "fidelity" -> "yosys", "top" -> top,
      "lut" -> total.lut.toDouble, "lutram" -> total.lutram.toDouble, "ff" -> total.ff.toDouble, "dsp" -> total.dsp.toDouble,
      "bram36" -> total.bram36, "carry" -> total.carry.toDouble, "fits" -> verdict.isEmpty,
      "first_overflow" -> verdict.fold[ujson.Value](ujson.Null) { case (r, used, have) =>
        ujson.Obj("resource" -> r, "used" -> used, "available" -> have.toDouble) },
      "utilisation" -> ujson.Obj.from(total.used.zip(board.capacities).map { case ((r, u), (_, c)) => r -> ujson.Num(u / c) }),
      "units" -> ujson.Obj.from(instances.toSeq.sortBy(_._1).map { case (m, n) =>
        m -> { val o = per(m).json; o("instances") = n.toDouble; o("lut_levels") = syn.levels.getOrElse(m, 0).toDouble
          o("ltp_cells") = syn.ltpCells.getOrElse(m, 0).toDouble; o } }),
      // a proxy (no placement, routing or retiming; docs/area.md): the deepest unit and a rough clock from it
      "lut_levels" -> deepLevels.toDouble, "lut_levels_unit" -> deepUnit, "fmax_mhz_proxy" -> timing.fmaxMhz(deepLevels),
      "fmax_rule" -> timing.rule,
      "unclassified_cells" -> ujson.Arr.from(syn.unknown.toSeq.sorted.map(ujson.Str(_))),
      "yosys_version" -> version, "cached" -> cached, "cache" -> cache.toString,
      "tus" -> p.tus, "m" -> p.m, "mppl" -> p.mppl, "wall_s" -> (System.nanoTime() - t0) / 1e9, "rtaccel" -> Cli.version)
    Cli.writeText(out.resolve("area.json"), ujson.write(json, indent = 2) + "\n")
    println(ujson.write(json))
    verdict.foreach { case (r, used, have) => throw new CheckFailed(Seq(f"does not fit ${board.name}: $r $used%.0f > $have")) }
  }

  /** The first resource (lut, ff, dsp, bram36) the design needs more of than the board has. */
  def fits(r: Resources, b: Board): Option[(String, Double, Long)] =
    r.used.zip(b.capacities).collectFirst { case ((name, used), (_, have)) if used > have => (name, used, have) }

  private def printTable(cfg: String, b: Board, top: String, total: Resources, per: Map[String, Resources],
                         inst: Map[String, Long], levels: Map[String, Int], verdict: Option[(String, Double, Long)]): Unit = {
    val e = Console.err
    e.println(f"[area] $cfg ($top) on ${b.name} (${b.part}, ${b.family}):")
    e.println(f"  ${"unit"}%-28s ${"x"}%5s ${"LUT"}%9s ${"LUTRAM"}%7s ${"FF"}%9s ${"DSP"}%6s ${"BRAM36"}%7s ${"levels"}%6s")
    for ((m, n) <- inst.toSeq.sortBy { case (m, n) => -(per(m).lut * n) }) {
      val r = per(m)
      e.println(f"  $m%-28s $n%5d ${r.lut}%9d ${r.lutram}%7d ${r.ff}%9d ${r.dsp}%6d ${r.bram36}%7.1f ${levels.getOrElse(m, 0)}%6d")
    }
    e.println(f"  ${"board capacity"}%-28s ${""}%5s ${b.lut}%9d ${""}%7s ${b.ff}%9d ${b.dsp}%6d ${b.bram36}%7d")
    e.println(verdict.fold(f"  fits ${b.name}")(v => f"  does NOT fit ${b.name}: ${v._1} ${v._2}%.0f > ${v._3}"))
  }
}
