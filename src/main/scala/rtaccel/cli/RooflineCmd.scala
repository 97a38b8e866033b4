package rtaccel.cli

import rtaccel.io.InputError
import rtaccel.perf.Roofline

/** make roofline: RTL runs (Simulate, each checked against the model) of one configuration or of a TUS list,
  * each set against its memory and compute bounds (rtaccel.perf.Roofline, docs/roofline.md). Writes
  * OUT/roofline.csv (plotted by dse.plots.roofline) and prints, last, one JSON line: the roofline of the last
  * configuration (rays_per_s, memory_bound, compute_bound, roofline_fraction, binding, ...), the clock it assumes with
  * clock_source (given, board, proxy or routed: area.ClockSource) and "points", all of them.
  */
object RooflineCmd {
  val columns: Seq[String] = Seq("tus", "rays", "cycles", "rays_per_s", "memory_bound", "compute_bound", "compute_bound_box",
    "compute_bound_tri", "roofline_fraction", "binding", "nearest_roof", "dram_bytes_per_ray", "box_jobs_per_ray", "tri_jobs_per_ray",
    "util_memory", "util_iu", "util_tu", "stall_iu_arbitration", "stall_memory_data", "stall_memory_request",
    "node_cache_miss_rate", "prim_cache_miss_rate", "ius", "mem_channels", "sim_build", "wall_build_s", "sim_cycles_per_wall_s",
    "sim_cycles_per_cpu_s", "sim_wall_s")

  /** "8 16 32" or "8,16,32": the TU counts of a sweep (empty: the configuration's own TUS). */
  def tusList(s: String, what: String = "ROOFLINE_TUS", unit: String = "TU"): Seq[Int] = s.split("[ ,]+").filter(_.nonEmpty).map(t => t.toIntOption.filter(_ >= 1).getOrElse(
    throw new InputError(s"$what must be $unit counts >= 1 separated by spaces or commas (got '$t')"))).toSeq

  /** The grid of a sweep: every TU count with every IU count (each must split its TUs evenly, checked up front). */
  def grid(tus: Seq[Int], ius: Seq[Int]): Seq[(Int, Int)] = {
    val g = for (t <- tus; i <- ius) yield (t, i)
    g.find { case (t, i) => t % i != 0 }.foreach { case (t, i) =>
      throw new InputError(s"TUS=$t does not split evenly over IUS=$i; give ROOFLINE_TUS that are multiples of every ROOFLINE_IUS") }
    g
  }

  /** One CSV row / JSON point of a simulate result. */
  def point(j: ujson.Value): ujson.Obj = {
    val r = j("roofline").obj
    def miss(c: String): ujson.Value = j(c).obj.get("miss_rate").getOrElse(ujson.Null)
    ujson.Obj.from(Seq("tus" -> j("tus"), "rays" -> j("rays"), "cycles" -> j("cycles")) ++ r.toSeq ++
      Seq("node_cache_miss_rate" -> miss("node_cache"), "prim_cache_miss_rate" -> miss("prim_cache"),
        "sim_build" -> j("sim_build"), "wall_build_s" -> j("wall_build_s"), "sim_cycles_per_wall_s" -> j("sim_cycles_per_wall_s"),
        "sim_cycles_per_cpu_s" -> j("sim_cycles_per_cpu_s"), "sim_wall_s" -> j("sim_wall_s")))
  }

  def cell(v: ujson.Value): String = v match {
    case ujson.Null => ""
    case ujson.Str(s) => s
    case ujson.Num(d) if d == math.rint(d) && math.abs(d) < 1e15 => f"$d%.0f"
    case ujson.Num(d) if d.isNaN || d.isInfinite => throw new IllegalArgumentException(s"a roofline figure is not finite: $d")
    case ujson.Num(d) => BigDecimal(d).round(new java.math.MathContext(6)).bigDecimal.stripTrailingZeros.toPlainString // 6 digits
    case other => ujson.write(other)
  }

  def main(args: Array[String]): Unit = Cli.run(args, Flags.roofline) { a =>
    val out = a.path("out")
    val (scene, rays, e) = Cli.inputs(a)
    val req = Cli.request(a); val base = req.base
    val label = a.get("scene-label", a.need("tris"))
    val list = grid(tusList(a.get("tus-list", "")) match { case Seq() => Seq(base.tus); case l => l },
      tusList(a.get("ius-list", ""), "ROOFLINE_IUS", "IU") match { case Seq() => Seq(base.ius); case l => l })
    val build = a.opt("sim-build").map(rtaccel.sim.VerilatorBuild.named)
    val points = list.zipWithIndex.map { case ((t, k), i) =>
      val b = Cli.build(scene, rays, req.map(_.copy(tus = t, ius = k)))
      System.err.println(s"[roofline] $label: TUS=$t IUS=$k (${i + 1} of ${list.length}), ${rays.count} rays")
      val o = rtaccel.sim.PlatformRun.run(b, rays, rtaccel.sim.PlatformRun.SimOptions(label, scaleExp = e, build = build))
      // a failed point stops the sweep before any CSV exists, so nothing downstream plots it
      if (!o.ok) { println(ujson.write(o.json)); throw new CheckFailed(o.failures.map(f => s"TUS=$t IUS=$k $f")) }
      val pt = point(o.json)
      System.err.println(f"[roofline] TUS=$t IUS=$k: ${pt("rays_per_s").num}%.4g rays/s, memory bound ${cell(pt("memory_bound"))}, " +
        s"compute bound ${cell(pt("compute_bound"))}, ${cell(pt("roofline_fraction"))} of the nearer roof: ${pt("binding").str}")
      pt
    }
    val p = base
    val res = Roofline.resources(p)
    val sb = new StringBuilder(s"# scene=$label triangles=${scene.triangles} rays=${rays.count} config=${p.name} M=${p.m} " +
      s"MPPL=${p.mppl} clock_mhz=${p.clockMhz} clock_source=${p.clockSource} mem_bytes_per_s=${p.memory.bytesPerSecond} sustained=${p.memory.sustainedEfficiency} " +
      s"ius=${list.map(_._2).distinct.mkString(",")} mem_channels=${res.memChannels} resp_order=${p.respOrder} ray_store=${if (p.rayStore) 1 else 0} tag_forward=${if (p.tagForward) 1 else 0} node_banks=${p.nodeBanks} node_cache=${SweepTus.desc(p.nodeCache)} prim_cache=${SweepTus.desc(p.primCache)} " +
      s"binds_at=${Roofline.bindsAt} rtaccel=${Cli.version}\n")
    sb ++= columns.mkString(",") + "\n"
    for (pt <- points) sb ++= columns.map(c => cell(pt.value.getOrElse(c, ujson.Null))).mkString(",") + "\n"
    val csv = out.resolve("roofline.csv")
    Cli.writeText(csv, sb.toString)
    val last = points.last
    val j = ujson.Obj.from(last.value.toSeq ++ Seq("scene" -> ujson.Str(label), "config" -> ujson.Str(p.name),
      "clock_mhz" -> ujson.Num(p.clockMhz), "clock_source" -> ujson.Str(p.clockSource), "csv" -> ujson.Str(csv.toString), "png" -> ujson.Str(out.resolve("roofline.png").toString),
      "points" -> ujson.Arr.from(points), "rtaccel" -> ujson.Str(Cli.version)))
    println(ujson.write(j))
  }
}
