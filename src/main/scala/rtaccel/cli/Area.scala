package rtaccel.cli

import java.nio.file.Paths
import rtaccel.area.{Board, Boards, CostModel, Resources, Synthesis, Timing}
import rtaccel.io.InputError

/** make area: FPGA resources of a configuration from a Yosys synthesis for the board's family, per unit and in
  * total, and whether it fits the board (exit 3 when it does not). Results are cached per circuit (hash of the
  * emitted Verilog, the Yosys version, the family and the top), since the whole platform takes minutes.
  * UNIT=<module> synthesizes one module of the design (e.g. BoxPipe) instead of the board top.
  * The deepest path in LUT levels is reported beside the resources (a timing proxy, docs/area.md).
  * FIDELITY=model answers from the fitted cost model (area.CostModel, boards/cost-model.json) without a synthesis.
  */
object Area {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.area)(main0)

  def main0(a: Args): Unit = {
    val t0 = System.nanoTime()
    val fidelity = a.get("fidelity", "yosys")
    if (fidelity != "yosys" && fidelity != "model")
      throw new InputError(s"FIDELITY=$fidelity is not one of yosys (a real synthesis) or model (the fitted cost model, boards/cost-model.json)")
    val board = Boards.requireXilinx(Boards.byName(a.get("board", "xc5vlx330t"), a.opt("catalog").map(Paths.get(_)).getOrElse(Boards.defaultPath)), "make area")
    // (the board's memory and clock reach the configuration through Cli.request as for every command)
    val p = Cli.preset(a, "make area")
    val out = Paths.get(a.get("out", s"build/area/${p.name}-${board.name}"))
    val json = if (fidelity == "model") modelJson(a, p, board) else yosysJson(a, p, board, out)
    val verdict = fits(json, board)
    json("fits") = verdict.isEmpty
    json("first_overflow") = verdict.fold[ujson.Value](ujson.Null) { case (r, used, have) =>
      ujson.Obj("resource" -> r, "used" -> used, "available" -> have.toDouble) }
    json("utilisation") = ujson.Obj.from(used(json).zip(board.capacities).map { case ((r, u), (_, c)) => r -> ujson.Num(u / c) })
    json("tus") = p.tus; json("m") = p.m; json("mppl") = p.mppl
    json("wall_s") = (System.nanoTime() - t0) / 1e9; json("rtaccel") = Cli.version
    Console.err.println(verdict.fold(f"  fits ${board.name}")(v => f"  does NOT fit ${board.name}: ${v._1} ${v._2}%.0f > ${v._3}"))
    Cli.writeText(out.resolve(if (fidelity == "model") "area-model.json" else "area.json"), ujson.write(json, indent = 2) + "\n")
    println(ujson.write(json))
    verdict.foreach { case (r, used, have) => throw new CheckFailed(Seq(f"does not fit ${board.name}: $r $used%.0f > $have")) }
  }

  private def header(p: rtaccel.config.PlatformParams, b: Board, fidelity: String, top: String) = ujson.Obj.from(rtaccel.config.Knobs.echo(p, "area") ++
    Seq[(String, ujson.Value)]("board" -> b.name, "family" -> b.family, "fidelity" -> fidelity, "top" -> top))

  /** A real synthesis (cached per circuit), every module of the hierarchy in `units`. */
  private def yosysJson(a: Args, p: rtaccel.config.PlatformParams, board: Board, out: java.nio.file.Path): ujson.Obj = {
    val s = Synthesis.of(p, board.family, a.get("unit", "RtAccelTop"), out.resolve("rtl"), Paths.get(a.get("cache", "build/area-cache")),
      line => System.err.println(s"[area] ${line.take(120)}"))
    val total = s.total
    val (deepUnit, deepLevels) = s.deepest
    val timing = Timing.forFamily(board.family)
    printTable(p.name, board, s.top, s.resources, s.instances, s.levels)
    System.err.println(f"  deepest path: $deepLevels LUT levels in $deepUnit, ~${timing.fmaxMhz(deepLevels)}%.0f MHz (a proxy: no placement or routing)")
    val deepPath = s.paths.getOrElse(deepUnit, Nil)
    if (deepPath.nonEmpty) System.err.println(s"  through: ${deepPath.mkString(" -> ")}")
    val j = header(p, board, "yosys", s.top)
    j("lut") = total.lut.toDouble; j("lutram") = total.lutram.toDouble; j("ff") = total.ff.toDouble; j("dsp") = total.dsp.toDouble
    j("bram36") = total.bram36; j("carry") = total.carry.toDouble
    j("units") = ujson.Obj.from(s.instances.toSeq.sortBy(_._1).map { case (m, n) =>
      m -> { val o = s.resources(m).json; o("instances") = n.toDouble; o("lut_levels") = s.levels.getOrElse(m, 0).toDouble
        o("ltp_cells") = s.ltpCells.getOrElse(m, 0).toDouble
        o("lut_levels_path") = ujson.Arr.from(s.paths.getOrElse(m, Nil).map(ujson.Str(_))); o } })
    // a proxy (no placement, routing or retiming; docs/area.md): the deepest unit and a rough clock from it
    j("lut_levels") = deepLevels.toDouble; j("lut_levels_unit") = deepUnit; j("fmax_mhz_proxy") = timing.fmaxMhz(deepLevels)
    j("fmax_rule") = timing.rule
    j("unclassified_cells") = ujson.Arr.from(s.unknown.toSeq.sorted.map(ujson.Str(_)))
    j("yosys_version") = s.version; j("cached") = s.cached; j("cache") = s.cache.toString
    j
  }

  /** The fitted cost model (no synthesis): the platform's units as CostModel defines them. */
  private def modelJson(a: Args, p: rtaccel.config.PlatformParams, board: Board): ujson.Obj = {
    if (a.opt("unit").isDefined) throw new InputError("UNIT= needs FIDELITY=yosys: the cost model prices the whole platform")
    val m = CostModel.load(a.opt("cost-model").map(Paths.get(_)).getOrElse(CostModel.defaultPath))
    val units = m.predict(p, board.family)
    val total = CostModel.resources.map(r => r -> units.map(_._2(r)).sum).toMap
    val e = Console.err
    e.println(f"[area] ${p.name} on ${board.name} (${board.family}), cost model fitted on ${m.family} with Yosys ${m.yosysVersion}:")
    e.println(f"  ${"unit"}%-22s ${"x"}%5s ${"LUT"}%9s ${"LUTRAM"}%7s ${"FF"}%9s ${"DSP"}%6s ${"BRAM36"}%7s")
    for ((u, r, n) <- units.sortBy(-_._2("lut")) if r.values.exists(_ > 0))
      e.println(f"  $u%-22s $n%5d ${r("lut")}%9.0f ${r("lutram")}%7.0f ${r("ff")}%9.0f ${r("dsp")}%6.0f ${r("bram36")}%7.1f")
    val j = header(p, board, "model", "RtAccelTop")
    for (r <- CostModel.resources) j(r) = if (r == "bram36") math.rint(total(r) * 10) / 10 else math.round(total(r)).toDouble
    j("units") = ujson.Obj.from(units.map { case (u, r, n) =>
      u -> ujson.Obj.from(CostModel.resources.map(k => k -> ujson.Num(math.rint(r(k) * 10) / 10)) :+ ("instances" -> ujson.Num(n.toDouble))) })
    j("lut_levels") = ujson.Null // a synthesis property: FIDELITY=yosys reports it
    // The model's clock: with PIPELINE the Stagers cut every datapath segment at the budget, so the budget is the
    // model's deepest path (paper2017 on xc5v at auto: 6 levels predicted, 6 synthesized, docs/timing.md); the fixed
    // stages' depth (PIPELINE=none) is the synthesis's to tell. A proxy's proxy: make timing routes the circuit.
    val timing = Timing.forFamily(board.family)
    j("lut_levels_model") = p.stageBudget.fold[ujson.Value](ujson.Null)(b => ujson.Num(b))
    j("fmax_mhz_model") = p.stageBudget.fold[ujson.Value](ujson.Null)(b => ujson.Num(timing.fmaxMhz(b)))
    j("yosys_version") = m.yosysVersion; j("model_family") = m.family
    j("model_error") = m.json.obj.get("validation_summary").getOrElse(ujson.Null)
    j
  }

  /** What the board's capacities are checked against (logic LUTs and LUT RAM both occupy LUT6 sites). */
  private def used(j: ujson.Obj): Seq[(String, Double)] =
    Seq("lut" -> (j("lut").num + j("lutram").num), "ff" -> j("ff").num, "dsp" -> j("dsp").num, "bram36" -> j("bram36").num)

  def fits(j: ujson.Obj, b: Board): Option[(String, Double, Long)] =
    used(j).zip(b.capacities).collectFirst { case ((name, u), (_, have)) if u > have => (name, u, have) }

  private def printTable(cfg: String, b: Board, top: String, per: Map[String, Resources], inst: Map[String, Long],
                         levels: Map[String, Int]): Unit = {
    val e = Console.err
    e.println(f"[area] $cfg ($top) on ${b.name} (${b.part}, ${b.family}):")
    e.println(f"  ${"unit"}%-28s ${"x"}%5s ${"LUT"}%9s ${"LUTRAM"}%7s ${"FF"}%9s ${"DSP"}%6s ${"BRAM36"}%7s ${"levels"}%6s")
    for ((m, n) <- inst.toSeq.sortBy { case (m, n) => -(per(m).lut * n) }) {
      val r = per(m)
      e.println(f"  $m%-28s $n%5d ${r.lut}%9d ${r.lutram}%7d ${r.ff}%9d ${r.dsp}%6d ${r.bram36}%7.1f ${levels.getOrElse(m, 0)}%6d")
    }
    e.println(f"  ${"board capacity"}%-28s ${""}%5s ${b.lut}%9d ${""}%7s ${b.ff}%9d ${b.dsp}%6d ${b.bram36}%7d")
  }
}
