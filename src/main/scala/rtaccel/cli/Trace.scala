package rtaccel.cli

import rtaccel.bvh.MemoryImage
import rtaccel.io.Npy
import rtaccel.model.{AccessRecorder, RayStats, Traversal}

/** make trace: the reference model on a rays file -> OUT/hits.npy, OUT/trace.npy, OUT/summary.json. */
object Trace {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.trace)(main0)

  def main0(a: Args): Unit = {
    val out = a.path("out")
    val (scene, rays, scaleExp) = Cli.inputs(a)
    val b = Cli.build(scene, rays, Cli.request(a))
    val img = MemoryImage.pack(b.bvh, b.scene, b.params)
    val rec = new AccessRecorder; val st = new RayStats
    val t0 = System.nanoTime()
    val hits = new Traversal(img).traceAll(rays, if (a.get("access-trace", "1") == "1") rec else rtaccel.model.AccessSink.none, st)
    val secs = (System.nanoTime() - t0) / 1e9
    val p = b.params
    val n = math.max(1, rays.count).toDouble
    val exhaustive = a.opt("exhaustive").map(_ => a.int("exhaustive", 0)).map { k =>
      if (k < 0) throw new rtaccel.io.InputError(s"--exhaustive must be >= 0 rays (got $k)")
      rtaccel.model.Exhaustive.check(p, b.scene, rays, hits, k)
    }
    val summary = ujson.Obj.from(Seq[(String, ujson.Value)](
      "scene" -> a.get("scene-label", a.need("tris")), "rtaccel" -> Cli.version) ++ rtaccel.config.Knobs.echo(p, "trace") ++ Seq[(String, ujson.Value)](
      "triangles" -> b.scene.triangles, "nodes" -> b.bvh.numNodes,
      "leaves" -> b.bvh.numLeaves, "node_levels" -> (b.bvh.maxLevel + 1), "stack_bound" -> b.bvh.stackBound,
      "ref_fields" -> ujson.Obj("node_id_bits" -> p.refs.nodeIdBits, "prim_index_bits" -> p.refs.primIndexBits,
        "count_bits" -> p.refs.countBits, "level_bits" -> p.refs.levelBits, "ref_bits" -> p.refs.refBits),
      "normalize_exponent" -> scaleExp, "rays" -> rays.count, "hits" -> hits.prim.count(_ >= 0),
      "node_fetches" -> st.nodeFetches.toDouble, "leaf_fetches" -> st.leafFetches.toDouble, "prim_tests" -> st.primTests.toDouble, "box_tests" -> st.boxTests.toDouble,
      "node_bytes_per_ray" -> st.nodeFetches * p.nodeAccessBytes / n,
      "prim_bytes_per_ray" -> st.primBytes / n,
      "max_stack" -> st.maxStack, "stack_overflow_rays" -> st.overflows, "overflowed" -> st.overflows,
      "step_limit_rays" -> st.stepLimits, "restarts" -> st.restarts.toDouble,
      "build_s" -> b.buildSeconds, "trace_s" -> secs, "rays_per_s" -> rays.count / math.max(secs, 1e-9)))
    exhaustive.foreach { e =>
      summary("exhaustive_rays") = e.rays; summary("lost_hits") = e.lost
      summary("lost_hit_rays") = ujson.Arr(e.firstLost.map(ujson.Num(_)): _*)
    }
    // Outputs are complete in memory before the first file is written.
    hits.save(out.resolve("hits.npy"))
    if (rec.rows > 0) Npy.writeInts(out.resolve("trace.npy"), rec.toArray, 5)
    Cli.writeText(out.resolve("summary.json"), ujson.write(summary, indent = 2) + "\n")
    println(ujson.write(summary))
  }
}
