package rtaccel.cli

import rtaccel.io.InputError

/** Paper Figs 12-13: rays/s and memory utilisation vs the number of TUs, one RTL simulation per TU count,
  * every run checked against the reference model. Writes OUT/tus_sweep.csv (plotted by dse.plots.tus).
  */
object SweepTus {
  def desc(c: rtaccel.config.CacheParams): String =
    if (c.entries == 0) "none" else s"${c.entries}x${c.ways}-${c.policy}" + (if (c.policy.levelAware) s"-ml${c.maxLevel}" else "")

  /** A cache's miss rate from the simulate JSON (empty when the cache is absent); `model_interleaved` = the
    * trace model's prediction for the same TU count.
    */
  private def rate(j: ujson.Value, cache: String, key: String): String = {
    val o = j(cache).obj
    if (!o.contains("miss_rate")) "" else if (key == "miss_rate") f"${o("miss_rate").num}%.5f" else f"${o(key)("miss_rate").num}%.5f"
  }

  def main(args: Array[String]): Unit = Cli.run(args, Flags.sweepTus) { a =>
    val out = a.path("out")
    val (scene, rays, e) = Cli.inputs(a)
    val tusList = a.get("tus-list", "1,2,4,8,16,32").split(",").map(s => s.trim.toIntOption.getOrElse(
      throw new InputError(s"--tus-list must be integers (got '$s')"))).toSeq
    val req = Cli.request(a)
    val label = a.get("scene-label", a.need("tris"))
    val rows = tusList.map { t =>
      val b = Cli.build(scene, rays, req.map(_.copy(tus = t)))
      System.err.println(s"[sweep] $label: TUs=$t")
      val o = rtaccel.sim.PlatformRun.run(b, rays, rtaccel.sim.PlatformRun.SimOptions(label, scaleExp = e))
      // a failed point stops the sweep before any CSV exists, so nothing downstream plots it
      if (!o.ok) { println(ujson.write(o.json)); throw new CheckFailed(o.failures.map(f => s"TUS=$t $f")) }
      o.json
    }
    val p = req.base
    val sb = new StringBuilder(s"# scene=$label triangles=${scene.triangles} rays=${rays.count} config=${p.name} M=${p.m} " +
      s"MPPL=${p.mppl} clock_mhz=${p.clockMhz} mem_bytes_per_s=${p.memory.bytesPerSecond} sustained=${p.memory.sustainedEfficiency} " +
      s"node_cache=${desc(p.nodeCache)} prim_cache=${desc(p.primCache)} rtaccel=${Cli.version}\n")
    sb ++= "tus,rays,cycles,rays_per_s,mem_utilisation,node_bytes_per_ray,prim_bytes_per_ray,stall_memory_data,tu_busy_cycles,sim_cycles_per_wall_s," +
      "dram_bytes_per_ray,node_cache_miss_rate,prim_cache_miss_rate,model_node_miss_rate,model_prim_miss_rate\n"
    for (j <- rows) {
      def n(k: String) = j(k).num
      def c(k: String) = j("counters")(k).num
      sb ++= f"${n("tus")}%.0f,${n("rays")}%.0f,${n("cycles")}%.0f,${n("rays_per_s_at_clock")}%.1f,${n("mem_utilisation")}%.4f," +
        f"${n("node_bytes_per_ray")}%.1f,${n("prim_bytes_per_ray")}%.1f,${c("stall_memory_data")}%.0f,${c("tu_busy_cycles")}%.0f,${n("sim_cycles_per_wall_s")}%.0f," +
        f"${n("dram_bytes_per_ray")}%.1f,${rate(j, "node_cache", "miss_rate")},${rate(j, "prim_cache", "miss_rate")}," +
        f"${rate(j, "node_cache", "model_interleaved")},${rate(j, "prim_cache", "model_interleaved")}\n"
    }
    Cli.writeText(out.resolve("tus_sweep.csv"), sb.toString)
    println(ujson.write(ujson.Obj("scene" -> label, "csv" -> out.resolve("tus_sweep.csv").toString,
      "rays_per_s" -> ujson.Arr.from(rows.map(_("rays_per_s_at_clock"))), "mem_utilisation" -> ujson.Arr.from(rows.map(_("mem_utilisation"))))))
  }
}
