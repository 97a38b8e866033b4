package rtaccel.cli

import rtaccel.bvh.{MemoryImage, Mbvh}
import rtaccel.model.Traversal

/** make bench (model side): BVH build time and single-thread reference-model rays/s, medians of repeats; rays/s
  * both per wall second and per second of this thread's CPU time (the latter is what a loaded, shared machine
  * disturbs least; golden.bench reports Embree's the same way).
  */
object Bench {
  private def median(xs: Seq[Double]): Double = { val s = xs.sorted; s(s.length / 2) }

  def main(args: Array[String]): Unit = Cli.run(args, Flags.bench)(main0)

  def main0(a: Args): Unit = {
    val (scene, rays, _) = Cli.inputs(a)
    val req = Cli.request(a); val p = req.base // the tree depends on M, MPPL and the access sizes only
    val repeat = a.int("repeat", 5)
    val builds = (0 until repeat).map { _ =>
      val t0 = System.nanoTime(); val bvh = Mbvh.build(scene, p); ((System.nanoTime() - t0) / 1e9, bvh)
    }
    val b = Cli.build(scene, rays, req) // the configuration CONFIG names, fitted or checked
    val tr = new Traversal(MemoryImage.pack(b.bvh, b.scene, b.params))
    tr.traceAll(rays) // JIT warm-up, not timed
    val cpu = java.lang.management.ManagementFactory.getThreadMXBean
    val traces = (0 until repeat).map { _ =>
      val c0 = cpu.getCurrentThreadCpuTime; val t0 = System.nanoTime(); tr.traceAll(rays)
      ((System.nanoTime() - t0) / 1e9, (cpu.getCurrentThreadCpuTime - c0) / 1e9)
    }
    println(ujson.write(ujson.Obj.from(Seq[(String, ujson.Value)](
      "scene" -> a.get("scene-label", a.need("tris")), "rays" -> rays.count, "triangles" -> scene.triangles) ++
      rtaccel.config.Knobs.echo(b.params, "bench") ++ Seq[(String, ujson.Value)](
      "repeat" -> repeat, "threads" -> 1,
      "model_build_s_median" -> median(builds.map(_._1)),
      "model_rays_per_s_median" -> rays.count / median(traces.map(_._1)),
      "model_rays_per_cpu_s_median" -> rays.count / median(traces.map(_._2)), "rtaccel" -> Cli.version))))
  }
}
