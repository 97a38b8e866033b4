package rtaccel.cli

import java.nio.file.Paths
import rtaccel.area.{Boards, FpProbe, Synthesis, Timing}
import rtaccel.config.Pipelining
import rtaccel.fp.FpFormat

/** make area-fp: each fp32 operation of rtaccel.fp synthesized alone between flip-flops for the board's
  * family (resources and LUT levels), for the comparison with vendor floating-point cores in docs/area.md.
  * Cached like make area.
  */
object AreaFp {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.areaFp)(main0)

  def main0(a: Args): Unit = {
    val t0 = System.nanoTime()
    val board = Boards.requireXilinx(Boards.byName(a.get("board", "xc5vlx330t"), a.opt("catalog").map(Paths.get(_)).getOrElse(Boards.defaultPath)), "make area-fp")
    val ops = a.opt("ops").map(_.split(",").map(_.trim).filter(_.nonEmpty).toSeq.distinct.map(FpProbe.byName)).getOrElse(FpProbe.ops)
    if (ops.isEmpty) throw new rtaccel.io.InputError(s"OPS= names no operation; choose from ${FpProbe.ops.map(_.name).mkString(", ")}")
    val timing = Timing.forFamily(board.family)
    // each operation at its fixed depth and at the depth PIPELINE (default auto) gives for CLOCK_MHZ (default the board's)
    val mhz = a.opt("clock-mhz").map(_ => a.double("clock-mhz", 0)).getOrElse(board.clockMhz)
    if (!(mhz > 0)) throw new rtaccel.io.InputError(s"CLOCK_MHZ=$mhz must be positive")
    val pl = Pipelining.parse(a.get("pipeline", "auto"))
    val budgets = (Seq(None) ++ pl.budget(board.family, mhz).map(Some(_))).distinct
    val out = Paths.get(a.get("out", s"build/area-fp/${board.name}"))
    val cache = Paths.get(a.get("cache", "build/area-cache"))
    val runs = for (op <- ops; budget <- budgets) yield {
      var latency = 0
      val tag = op.name + budget.fold("")(b => s"-p$b")
      val files = EmitVerilog.emitModule({ val m = new FpProbe(op, FpFormat.fp32, budget, timing.dsp); latency = m.latency; m }, out.resolve(tag))
        .filter(_.toString.endsWith(".sv"))
      val top = files.map(_.getFileName.toString.stripSuffix(".sv")).find(_.startsWith(FpProbe.moduleName(op))).get
      val s0 = System.nanoTime()
      val syn = Synthesis.run(files, top, board.family, cache, s"fp32 $tag",
        line => System.err.println(s"[area-fp] ${line.take(120)}"), Cli.version)
      (op, budget, latency, syn, (System.nanoTime() - s0) / 1e9)
    }
    val e = Console.err
    e.println(s"[area-fp] fp32 operations of rtaccel.fp, registered in and out, on ${board.name} (${board.family}); " +
      s"PIPELINE=${pl.name} at $mhz MHz: ${budgets.flatten.headOption.fold("no budget")(b => s"$b LUT levels per stage")}:")
    e.println(f"  ${"op"}%-8s ${"budget"}%6s ${"cycles"}%6s ${"LUT"}%6s ${"LUTRAM"}%6s ${"FF"}%6s ${"DSP"}%4s ${"CARRY"}%6s ${"levels"}%6s ${"~MHz"}%5s ${"synth s"}%7s  what")
    for ((op, budget, lat, s, secs) <- runs) {
      val r = s.total; val lv = s.deepest._2
      e.println(f"  ${op.name}%-8s ${budget.fold("none")(_.toString)}%6s $lat%6d ${r.lut}%6d ${r.lutram}%6d ${r.ff}%6d ${r.dsp}%4d ${r.carry}%6d $lv%6d ${timing.fmaxMhz(lv)}%5.0f ${if (s.cached) "cached" else f"$secs%.1f"}%7s  ${op.about}")
    }
    def entry(budget: Option[Int], lat: Int, s: Synthesis, secs: Double, about: String) = {
      val o = s.total.json; val (unit, lv) = s.deepest
      o("lut_levels") = lv.toDouble; o("lut_levels_unit") = unit; o("fmax_mhz_proxy") = timing.fmaxMhz(lv)
      o("budget_levels") = budget.fold[ujson.Value](ujson.Null)(ujson.Num(_)); o("latency_cycles") = lat
      o("cached") = s.cached; o("synth_s") = secs; o("about") = about
      o
    }
    val json = ujson.Obj("board" -> board.name, "family" -> board.family, "format" -> "fp32",
      // the fixed depth under each name, as before; the pipelined one beside it
      "ops" -> ujson.Obj.from(runs.filter(_._2.isEmpty).map { case (op, b, lat, s, secs) => op.name -> entry(b, lat, s, secs, op.about) }),
      "pipelined" -> ujson.Obj.from(runs.filter(_._2.isDefined).map { case (op, b, lat, s, secs) => op.name -> entry(b, lat, s, secs, op.about) }),
      "pipeline" -> pl.name, "for_mhz" -> mhz,
      "fmax_rule" -> timing.rule, "yosys_version" -> runs.head._4.version,
      "wall_s" -> (System.nanoTime() - t0) / 1e9, "rtaccel" -> Cli.version)
    Cli.writeText(out.resolve("area-fp.json"), ujson.write(json, indent = 2) + "\n")
    println(ujson.write(json))
  }
}
