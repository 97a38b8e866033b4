package rtaccel.cli

import rtaccel.model.Analysis

/** make analyze: bandwidth vs MPPL (Fig 4) and accesses by level (Figs 5-6) as CSV in OUT. */
object Analyze {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.analyze)(main0)

  def main0(a: Args): Unit = {
    val out = a.path("out")
    val (scene, rays, _) = Cli.inputs(a)
    val req = Cli.request(a); val base = req.base
    if (base.primPacked) throw new rtaccel.io.InputError("PRIM_FORMAT=packed: make analyze counts primitive slots per access " +
      "(the paper's Fig 4); its packed bytes come from make trace or make cachesim")
    val mppls = a.get("mppls", "1,2,4,8,16").split(",").map(_.trim.toInt).toSeq
    val label = a.get("scene-label", a.need("tris"))
    val levelMppl = base.mppl
    val results = mppls.map { k =>
      System.err.println(s"[analyze] MPPL=$k: building and tracing ${rays.count} rays")
      val b = Cli.build(scene, rays, req.map(_.copy(mppl = k))) // CONFIG=<preset> is checked against the scene, CONFIG=fit fitted
      val c = Analysis.run(b.scene, b.bvh, b.params, rays)
      (k, b, c, Analysis.mpplRow(b.params, rays, b.bvh, c))
    }
    val (_, lb, lc, _) = results.find(_._1 == levelMppl).getOrElse {
      val b = Cli.build(scene, rays, req); (levelMppl, b, Analysis.run(b.scene, b.bvh, b.params, rays), null)
    }
    val lbvh = lb.bvh
    // what CONFIG made of the scene (the preset, or fit), as the builds above named it: no extra BVH build
    val cfgName = lb.params.name
    val prov = s"# scene=$label triangles=${scene.triangles} config=$cfgName M=${base.m} rays=${rays.count} " +
      s"node_access_bytes=${base.nodeAccessBytes} prim_access_bytes=${base.primAccessBytes} rtaccel=${Cli.version}\n"
    val bw = new StringBuilder(prov)
    bw ++= "mppl,rays,nodes,leaves,depth,node_accesses,leaf_accesses,prim_accesses,node_bytes_per_ray,prim_bytes_per_ray,total_bytes_per_ray\n"
    for ((_, _, _, r) <- results)
      bw ++= f"${r.mppl},${r.rays},${r.nodes},${r.leaves},${r.depth},${r.nodeAccesses},${r.leafAccesses},${r.primAccesses},${r.nodeBytesPerRay}%.3f,${r.primBytesPerRay}%.3f,${r.totalBytesPerRay}%.3f\n"
    val lv = new StringBuilder(prov.stripSuffix("\n") + s" levels_for_mppl=$levelMppl\n")
    lv ++= "level,nodes,accesses,accesses_per_node,cum_node_share,cum_access_share\n"
    val levelRows = Analysis.levels(lbvh, lc)
    for (r <- levelRows)
      lv ++= f"${r.level},${r.nodes},${r.accesses},${r.accessesPerNode}%.4f,${r.cumNodeShare}%.6f,${r.cumAccessShare}%.6f\n"
    Cli.writeText(out.resolve("bandwidth_vs_mppl.csv"), bw.toString)
    Cli.writeText(out.resolve("levels.csv"), lv.toString)
    val top4 = levelRows.take(4)
    // the knobs as the level run (MPPL=levels_for_mppl) resolved them; the other MPPLs are bytes_per_ray's keys
    val summary = ujson.Obj.from(Seq[(String, ujson.Value)]("scene" -> label, "rays" -> rays.count) ++
      rtaccel.config.Knobs.echo(lb.params, "analyze") ++ Seq[(String, ujson.Value)](
      "bytes_per_ray" -> ujson.Obj.from(results.map { case (k, _, _, r) =>
        k.toString -> ujson.Obj("node" -> r.nodeBytesPerRay, "prim" -> r.primBytesPerRay, "total" -> r.totalBytesPerRay) }),
      "levels_for_mppl" -> levelMppl,
      "top4_levels_nodes" -> top4.map(_.nodes).sum, "top4_levels_node_share" -> top4.last.cumNodeShare,
      "top4_levels_access_share" -> top4.last.cumAccessShare))
    println(ujson.write(summary))
  }
}
