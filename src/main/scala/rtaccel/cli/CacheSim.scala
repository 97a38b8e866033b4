package rtaccel.cli

import rtaccel.bvh.MemoryImage
import rtaccel.cache.{CacheCounts, CacheModel, CacheSink, ClusterSinks, Replay}
import rtaccel.config.{CacheParams, CachePolicy}
import rtaccel.io.InputError
import rtaccel.model.{AccessRecorder, AccessSink, RayStats, Traversal}

/** make cachesim: the reference traversal on a rays file, its accesses replayed through a node cache and a
  * primitive cache model (one TU's order, or N TUs interleaved), DRAM traffic after the caches and a
  * bandwidth-bound throughput estimate. Last stdout line: one JSON object.
  * Optional --sweep-out <csv>: miss rate of the node cache for dm/bf/lrp0..6 (and lru 4-way) at 256..8192
  * entries on the same access stream, written as CSV.
  */
object CacheSim {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.cacheSim)(main0)

  def main0(a: Args): Unit = {
    val req = Cli.request(a) // refuses bad cache values before the scene is loaded
    val tLoad = System.nanoTime()
    val (scene, rays, _) = Cli.inputs(a)
    val loadS = (System.nanoTime() - tLoad) / 1e9 // ~0 when Serve kept the scene and rays
    val b = Cli.build(scene, rays, req)
    val p = b.params
    val tus = p.tus // the preset's TUs unless TUS= is given (paper2017: 32); TUS=1 replays one TU's order
    val (node, prim) = (p.nodeCache, p.primCache)
    CacheSink(p) // validate geometry before the traversal runs
    // Record once; the replay (1 or N TUs) is what is timed as the cache model. The access order depends on
    // the tree, the rays and the memory image, not on the caches or the TU count: Serve replays a kept trace.
    val traceKey = (new Memo.Id(b.bvh), new Memo.Id(rays), p.copy(tus = 1, ius = 1, nodeCache = CacheParams(), primCache = CacheParams(), nodeBanks = 0))
    val traceReused = Memo.has("trace", traceKey)
    val (rows, traceS) = Memo("trace", traceKey) {
      val img = MemoryImage.pack(b.bvh, b.scene, p)
      val rec = new AccessRecorder; val st = new RayStats
      val t0 = System.nanoTime()
      new Traversal(img).traceAll(rays, rec, st)
      (rec.toArray, (System.nanoTime() - t0) / 1e9)
    }
    // --repeat R: R replays on fresh caches (the first includes JIT warm-up); wall_s is their median
    val repeat = a.int("repeat", 1)
    if (repeat < 1) throw new InputError(s"--repeat must be at least 1 (got $repeat)")
    val runs = (1 to repeat).map { _ =>
      // IUS > 1: each IU cluster's TUs share that cluster's caches (Replay.clustered); the counts are the sums
      val sinks = new ClusterSinks(p)
      val t1 = System.nanoTime()
      Replay.clustered(rows, p, sinks)
      (sinks, (System.nanoTime() - t1) / 1e9)
    }
    val sink = runs.last._1.total
    val geometry = runs.last._1.sinks.head // the clusters' caches are alike: lines and side lines from the first
    val walls = runs.map(_._2).sorted
    val wall = walls(walls.length / 2)
    val n = math.max(1, rays.count).toDouble
    val accesses = sink.nodeAccesses + sink.leafAccesses
    def stats(c: Option[CacheCounts], g: Option[CacheModel], cp: CacheParams) = (c, g) match {
      case (Some(m), Some(g)) => ujson.Obj("entries" -> cp.entries, "lines" -> g.lines, "ways" -> cp.ways, "policy" -> cp.policy.name,
        "max_level" -> cp.maxLevel, "hits" -> m.hits.toDouble, "misses" -> m.misses.toDouble, "bypasses" -> m.bypasses.toDouble,
        "miss_rate" -> m.missRate, "side_lines" -> g.sideLines)
      case _ => ujson.Obj("entries" -> 0, "hits" -> 0, "misses" -> 0, "bypasses" -> 0, "miss_rate" -> 1.0)
    }
    val nodeBpr = sink.nodeDramBytes / n; val primBpr = sink.primDramBytes / n
    val nodeBprNoCache = sink.nodeAccesses * p.nodeAccessBytes / n; val primBprNoCache = sink.primBytesAll / n
    val sustained = p.memBytesPerSecondTotal
    def bound(bpr: Double): Double = if (bpr > 0) sustained / bpr else Double.PositiveInfinity
    a.opt("sweep-out").foreach(out => sweep(rows, java.nio.file.Paths.get(out), tus, CacheSink.code(p)))
    // the analytic rung's own cost (its inputs come from the replay): the fastest of 3 calls, the first loads classes
    val (pred, predictS) = (1 to 3).map { _ =>
      val t = System.nanoTime(); val r = rtaccel.cache.Throughput.predict(p, sink, rays.count, tus); (r, (System.nanoTime() - t) / 1e9)
    }.minBy(_._2)
    val j = ujson.Obj.from(Seq[(String, ujson.Value)](
      "scene" -> a.get("scene-label", a.need("tris")), "rtaccel" -> Cli.version) ++ rtaccel.config.Knobs.echo(p, "cachesim") ++ Seq[(String, ujson.Value)](
      "tus" -> tus, "rays" -> rays.count, "nodes" -> b.bvh.numNodes, "node_levels" -> (b.bvh.maxLevel + 1),
      "node_accesses" -> sink.nodeAccesses.toDouble, "leaf_accesses" -> sink.leafAccesses.toDouble,
      "node_cache" -> stats(sink.nodeCache, geometry.nodeCache, node), "prim_cache" -> stats(sink.primCache, geometry.primCache, prim),
      "node_bytes_per_ray" -> nodeBpr, "prim_bytes_per_ray" -> primBpr, "dram_bytes_per_ray" -> (nodeBpr + primBpr),
      "node_bytes_per_ray_nocache" -> nodeBprNoCache, "prim_bytes_per_ray_nocache" -> primBprNoCache,
      "node_bandwidth_reduction" -> (if (nodeBpr > 0) nodeBprNoCache / nodeBpr else Double.PositiveInfinity),
      "sustained_dram_bytes_per_s" -> sustained,
      "bandwidth_bound_rays_per_s" -> bound(nodeBpr + primBpr),
      "bandwidth_bound_rays_per_s_nocache" -> bound(nodeBprNoCache + primBprNoCache),
      "bandwidth_bound_note" -> "clock x sustained DRAM bytes/cycle / DRAM bytes per ray; ignores compute and latency limits",
      "predicted_rays_per_s" -> pred.raysPerCycle * p.cyclesPerSecond,
      "predicted_rays_per_s_no_hol" -> pred.raysPerCycleNoHol * p.cyclesPerSecond,
      "predicted_cycles_per_ray" -> ujson.Obj("latency_one_tu" -> pred.latencyCycles, "dram" -> pred.dramCycles, "beats" -> pred.beatCycles,
        "head_of_line" -> pred.holCyclesPerRay),
      "predicted_in_flight" -> pred.inFlightLimit,
      "predicted_note" -> ("MVA of min(TUS, IU/MC outstanding limit) rays in flight over DRAM and the MC response port, with the " +
        "in-order response stream's head-of-line blocking (rtaccel.cache.Throughput); _no_hol: the plain MVA of TUS rays"),
      "predict_s" -> predictS,
      "trace_s" -> (if (traceReused) 0.0 else traceS), "trace_reused" -> traceReused,
      "load_s" -> loadS, "bvh_build_s" -> b.buildSeconds, "wall_s" -> wall, "accesses_per_s" -> accesses / math.max(wall, 1e-9),
      "repeat" -> repeat, "wall_s_first" -> runs.head._2))
    println(ujson.write(j))
  }

  /** Node-cache miss rate grid on one access stream. */
  def sweep(rows: Array[Int], out: java.nio.file.Path, tus: Int, code: rtaccel.cache.policy.LevelPolicy.Code): Unit = {
    val sizes = Seq(256, 512, 1024, 2048, 4096, 8192)
    val cfgs: Seq[(String, Int => CacheParams)] =
      Seq[(String, Int => CacheParams)]("dm" -> (e => CacheParams(e, 1, CachePolicy.Dm)), "bf" -> (e => CacheParams(e, 1, CachePolicy.Bf))) ++
        (0 to 6).map(l => s"lrp$l" -> ((e: Int) => CacheParams(e, 1, CachePolicy.Lrp, l))) ++
        (0 to 6 by 3).map(l => s"lrp${l}_4way" -> ((e: Int) => CacheParams(e, 4, CachePolicy.Lrp, l))) ++
        Seq[(String, Int => CacheParams)]("lru_4way" -> (e => CacheParams(e, 4, CachePolicy.Lru)), "plru_4way" -> (e => CacheParams(e, 4, CachePolicy.Plru)),
          "hybrid_lrp6" -> (e => CacheParams(e, 1, CachePolicy.Hybrid, 6)))
    val sb = new StringBuilder("config," + sizes.mkString(",") + "\n")
    val t0 = System.nanoTime(); var total = 0L
    for ((name, mk) <- cfgs) {
      val rates = sizes.map { e =>
        val m = new CacheModel(mk(e), code)
        Replay.interleaved(rows, tus, new AccessSink {
          def node(ray: Int, id: Int, level: Int): Unit = m.access(id, level)
          def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = ()
        })
        total += m.accesses
        f"${m.missRate}%.5f"
      }
      sb ++= name + "," + rates.mkString(",") + "\n"
    }
    val secs = (System.nanoTime() - t0) / 1e9
    sb ++= f"# ${cfgs.size * sizes.size} replays, $total node accesses in $secs%.2f s = ${total / secs}%.3e accesses/s (model incl. replay)\n"
    Cli.writeText(out, sb.toString)
    Console.err.print(sb.toString)
  }
}
