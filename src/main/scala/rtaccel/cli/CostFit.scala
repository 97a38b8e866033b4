package rtaccel.cli

import java.nio.file.{Files, Paths}
import rtaccel.area.{Boards, CostModel, Synthesis}
import rtaccel.area.CostFit.{fit, relErr}
import rtaccel.config.PlatformParams
import rtaccel.io.InputError

/** make cost-model: fits area.CostModel's coefficients from the real syntheses of a calibration plan
  * (boards/cost-calibration.json: `train` configurations and units, `validate` whole configurations it is
  * not fitted on, `scale` the same configuration on other families), then reports the model's error on the
  * validation set and writes boards/cost-model.json. Syntheses are cached per circuit (make area's cache),
  * so a refit after a change to the model alone takes seconds.
  */
object CostFit {
  // the command: the plan read, syntheses run or read from the cache, the fit (area.CostFit) written and checked
  def main(args: Array[String]): Unit = Cli.run(args, Flags.costFit)(main0)

  type Point = rtaccel.area.CostFit.Point
  private val Point = rtaccel.area.CostFit.Point

  private def points(plan: ujson.Value, key: String, family: String, path: java.nio.file.Path): Seq[Point] =
    plan.obj.get(key).map(_.arr.toSeq).getOrElse(Nil).map { e =>
      val name = e("name").str
      val argv = e("flags").arr.map(_.str).toArray
      val a = try Flags.parse(argv, Flags.area) catch { case x: InputError => throw new InputError(s"$path: $key '$name': ${x.getMessage}") }
      // the fit is of the fixed stages; the registers PIPELINE adds are counted at elaboration (CostModel.pipelineFf)
      val p = Cli.preset(a, s"$path: $key '$name'").copy(pipelining = rtaccel.config.Pipelining.Fixed)
      Point(name, p, a.get("unit", "RtAccelTop"), e.obj.get("family").map(_.str).getOrElse(family))
    }

  def main0(a: Args): Unit = {
    val t0 = System.nanoTime()
    val planPath = Paths.get(a.get("calibration", "boards/cost-calibration.json"))
    if (!Files.isRegularFile(planPath)) throw new InputError(s"calibration plan $planPath not found")
    val plan = try ujson.read(Files.readString(planPath)) catch { case e: ujson.ParseException => throw new InputError(s"$planPath is not JSON: ${e.getMessage}") }
    val family = plan("family").str
    if (!Boards.xilinxFamilies(family)) throw new InputError(s"$planPath: family '$family' is not one of ${Boards.xilinxFamilies.toSeq.sorted.mkString(", ")}")
    val cache = Paths.get(a.get("cache", "build/area-cache"))
    val rtl = Paths.get("build/cost-model/rtl")
    val train = points(plan, "train", family, planPath); val validate = points(plan, "validate", family, planPath)
    val scale = points(plan, "scale", family, planPath)
    val all = train ++ validate ++ scale
    var done = 0
    // --cached-only 1: refit from the syntheses already in the cache, leaving out the points that are not
    val cachedOnly = a.get("cached-only", "0") == "1"
    def synthOpt(pt: Point): Option[Synthesis] = {
      done += 1
      System.err.println(f"[cost-model] $done/${all.length} ${pt.name} (${pt.top}, ${pt.family})")
      try Some(Synthesis.of(pt.p, pt.family, pt.top, rtl, cache, line => System.err.println(s"[cost-model]   $line"), cachedOnly))
      catch { case e: Synthesis.NotCached => System.err.println(s"[cost-model]   not cached, left out: ${e.getMessage}"); None }
    }
    def synth(pt: Point): Synthesis = synthOpt(pt).get
    val trained = train.flatMap(pt => synthOpt(pt).map(pt -> _))
    if (trained.isEmpty) throw new InputError("no training synthesis available; run make cost-model without --cached-only")
    val coef = fit(trained)
    val base = CostModel.Fitted(coef, family, trained.head._2.version, Map(family -> CostModel.resources.map(_ -> 1.0).toMap), ujson.Obj())

    // validation: whole configurations the fit has not seen, and the model's instance counts against the hierarchy's
    val rows = validate.flatMap(pt => synthOpt(pt).map(pt -> _)).map { case (pt, s) =>
      val got = CostModel.resources.map(r => r -> CostModel.get(s.total, r)).toMap
      val predicted = base.predict(pt.p, family)
      val measured = CostModel.decompose(s)
      for ((u, _, n) <- predicted if measured.get(u).exists(_._2 != n))
        throw new CheckFailed(Seq(s"${pt.name}: the model counts $n x $u, the synthesis ${measured(u)._2}"))
      val want = base.total(pt.p, family)
      (pt, got, want)
    }
    val err = rows.map { case (pt, got, want) => pt -> CostModel.resources.map(r => r -> relErr(want(r), got(r))).toMap }
    // other families: the same configuration synthesized there, over its synthesis on the calibrated family
    val scales = scale.groupBy(_.family).map { case (fam, pts) =>
      val ratios = pts.flatMap(pt => synthOpt(pt).zip(synthOpt(pt.copy(family = family)))).map { case (s1, s0) =>
        val there = s1.total; val here = s0.total
        CostModel.resources.map(r => r -> (if (CostModel.get(here, r) == 0) 1.0 else CostModel.get(there, r) / CostModel.get(here, r))).toMap
      }
      fam -> ratios
    }.collect { case (fam, ratios) if ratios.nonEmpty => // a family none of whose syntheses is at hand stays uncalibrated
      fam -> CostModel.resources.map(r => r -> ratios.map(_(r)).sum / ratios.length).toMap
    }
    val summary = ujson.Obj.from(CostModel.resources.filter(_ != "carry").map { r =>
      val e = err.map(_._2(r)).filterNot(_.isNaN).map(math.abs).sorted
      r -> ujson.Obj("median_abs" -> (if (e.isEmpty) 0.0 else e(e.length / 2)), "max_abs" -> (if (e.isEmpty) 0.0 else e.last))
    })
    val json = ujson.Obj(
      "rtaccel" -> Cli.version, "yosys_version" -> base.yosysVersion, "family" -> family, "plan" -> planPath.toString,
      "units" -> ujson.Obj.from(coef.toSeq.sortBy(_._1).map { case (u, rs) => u -> ujson.Obj.from(rs.toSeq.sortBy(_._1).map { case (r, fs) =>
        r -> ujson.Obj.from(fs.toSeq.sortBy(_._1).map { case (k, v) => k -> ujson.Num(v) }) }) }),
      "family_scale" -> ujson.Obj.from((scales + (family -> CostModel.resources.map(_ -> 1.0).toMap)).toSeq.sortBy(_._1).map { case (f, rs) =>
        f -> ujson.Obj.from(rs.toSeq.sortBy(_._1).map { case (r, v) => r -> ujson.Num(v) }) }),
      "trained_on" -> ujson.Arr.from(train.map(pt => ujson.Str(s"${pt.name} (${pt.top})"))),
      "validation" -> ujson.Arr.from(rows.zip(err).map { case ((pt, got, want), (_, e)) =>
        ujson.Obj("name" -> pt.name, "tus" -> pt.p.tus, "m" -> pt.p.m,
          "yosys" -> ujson.Obj.from(got.toSeq.sortBy(_._1).map { case (k, v) => k -> ujson.Num(v) }),
          "model" -> ujson.Obj.from(want.toSeq.sortBy(_._1).map { case (k, v) => k -> ujson.Num(math.rint(v * 10) / 10) }),
          "rel_err" -> ujson.Obj.from(e.toSeq.sortBy(_._1).filterNot(_._2.isNaN).map { case (k, v) => k -> ujson.Num(math.rint(v * 1e4) / 1e4) })) }),
      "validation_summary" -> summary)
    printTable(rows, err)
    val out = Paths.get(a.get("out", CostModel.defaultPath.toString))
    Cli.writeText(out, ujson.write(json, indent = 2) + "\n")
    CostModel.fromJson(json) // what was written reads back
    println(ujson.write(ujson.Obj("cost_model" -> out.toString, "family" -> family, "trained" -> trained.length, "validated" -> rows.length,
      "validation_summary" -> summary, "wall_s" -> (System.nanoTime() - t0) / 1e9)))
  }

  private def printTable(rows: Seq[(Point, Map[String, Double], Map[String, Double])], err: Seq[(Point, Map[String, Double])]): Unit = {
    val e = Console.err
    e.println(f"[cost-model] validation (configurations not fitted on): yosys / model / error")
    e.println(f"  ${"config"}%-14s ${"TUs"}%4s ${"M"}%2s ${"LUT"}%24s ${"FF"}%22s ${"DSP"}%16s ${"BRAM36"}%20s")
    for (((pt, got, want), (_, er)) <- rows.zip(err)) {
      def cell(r: String) = f"${got(r)}%.0f/${want(r)}%.0f/${if (er(r).isNaN) 0.0 else er(r) * 100}%+.1f%%"
      e.println(f"  ${pt.name}%-14s ${pt.p.tus}%4d ${pt.p.m}%2d ${cell("lut")}%24s ${cell("ff")}%22s ${cell("dsp")}%16s ${cell("bram36")}%20s")
    }
  }
}
