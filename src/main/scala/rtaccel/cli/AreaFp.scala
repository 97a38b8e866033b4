package rtaccel.cli

import java.nio.file.Paths
import rtaccel.area.{Boards, FpProbe, Synthesis, Timing}
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
    val out = Paths.get(a.get("out", s"build/area-fp/${board.name}"))
    val cache = Paths.get(a.get("cache", "build/area-cache"))
    val runs = ops.map { op =>
      val files = EmitVerilog.emitModule(new FpProbe(op, FpFormat.fp32), out.resolve(op.name)).filter(_.toString.endsWith(".sv"))
      val s0 = System.nanoTime()
      val syn = Synthesis.run(files, FpProbe.moduleName(op), board.family, cache, s"fp32 ${op.name}",
        line => System.err.println(s"[area-fp] ${line.take(120)}"), Cli.version)
      (op, syn, (System.nanoTime() - s0) / 1e9)
    }
    val e = Console.err
    e.println(s"[area-fp] fp32 operations of rtaccel.fp, registered in and out, on ${board.name} (${board.family}):")
    e.println(f"  ${"op"}%-8s ${"LUT"}%6s ${"LUTRAM"}%6s ${"FF"}%6s ${"DSP"}%4s ${"CARRY"}%6s ${"levels"}%6s ${"~MHz"}%5s ${"synth s"}%7s  what")
    for ((op, s, secs) <- runs) {
      val r = s.total; val lv = s.deepest._2
      e.println(f"  ${op.name}%-8s ${r.lut}%6d ${r.lutram}%6d ${r.ff}%6d ${r.dsp}%4d ${r.carry}%6d $lv%6d ${timing.fmaxMhz(lv)}%5.0f ${if (s.cached) "cached" else f"$secs%.1f"}%7s  ${op.about}")
    }
    val json = ujson.Obj("board" -> board.name, "family" -> board.family, "format" -> "fp32",
      "ops" -> ujson.Obj.from(runs.map { case (op, s, secs) =>
        val o = s.total.json; val (unit, lv) = s.deepest
        o("lut_levels") = lv.toDouble; o("lut_levels_unit") = unit; o("fmax_mhz_proxy") = timing.fmaxMhz(lv)
        o("cached") = s.cached; o("synth_s") = secs; o("about") = op.about
        op.name -> o }),
      "fmax_rule" -> timing.rule, "yosys_version" -> runs.head._2.version,
      "wall_s" -> (System.nanoTime() - t0) / 1e9, "rtaccel" -> Cli.version)
    Cli.writeText(out.resolve("area-fp.json"), ujson.write(json, indent = 2) + "\n")
    println(ujson.write(json))
  }
}
