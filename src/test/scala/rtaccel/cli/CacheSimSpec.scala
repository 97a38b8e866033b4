package rtaccel.cli

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes

class CacheSimSpec extends AnyFunSuite {
  private val dir = Files.createTempDirectory("cachesimspec")
  private val scene = TestScenes.soup(3, 500)
  private val rays = TestScenes.rays(4, 300)
  private val (tris, raysPath) = TestScenes.writeInputs(dir, scene, rays)
  private def sim(extra: String*): (Int, String, String) = {
    val out = new java.io.ByteArrayOutputStream(); val err = new java.io.ByteArrayOutputStream()
    val code = Console.withOut(out)(Console.withErr(err)(
      Cli.status(Array("--tris", tris.toString, "--rays", raysPath.toString) ++ extra, Flags.cacheSim)(a => CacheSim.main0(a))))
    (code, out.toString, err.toString)
  }

  test("JSON last line carries the pinned keys; caches cut DRAM bytes") {
    val (code, out, _) = sim("--node-cache", "256", "--node-policy", "lrp", "--max-level", "3", "--prim-cache", "512", "--prim-ways", "2", "--tus", "4")
    assert(code == 0)
    val j = ujson.read(out.trim.linesIterator.toSeq.last)
    for (k <- Seq("node_cache", "prim_cache", "wall_s", "accesses_per_s", "node_bytes_per_ray", "prim_bytes_per_ray",
      "bandwidth_bound_rays_per_s", "dram_bytes_per_ray")) assert(j.obj.contains(k), k)
    for (c <- Seq("node_cache", "prim_cache"); k <- Seq("hits", "misses", "miss_rate")) assert(j(c).obj.contains(k), s"$c.$k")
    // the configuration echoed from the registry, under the keys every command uses
    assert(j("caches")("node")("policy").str == "lrp" && j("caches")("node")("max_level").num == 3 && j("caches")("prim")("ways").num == 2)
    assert(j("tus").num == 4 && j("config").str == "fit" && j("numerics")("box_format").str == "fp32")
    assert(j("node_cache")("hits").num + j("node_cache")("misses").num == j("node_accesses").num)
    assert(j("node_bytes_per_ray").num < j("node_bytes_per_ray_nocache").num)
    assert(j("prim_bytes_per_ray").num <= j("prim_bytes_per_ray_nocache").num)
    val (c0, out0, _) = sim("--node-cache", "0")
    val j0 = ujson.read(out0.trim.linesIterator.toSeq.last)
    assert(c0 == 0 && j0("node_cache")("entries").num == 0 && j0("prim_cache")("entries").num == 0)
    assert(j0("node_bytes_per_ray").num == j0("node_bytes_per_ray_nocache").num && j0("node_bytes_per_ray").num > 0)
  }

  test("a preset is the whole platform: CONFIG=fit and paper2017 bring the paper's 2^13 DM node cache and 32 TUs") {
    for (cfg <- Seq("fit", "paper2017")) {
      val (code, out, err) = sim("--config", cfg)
      assert(code == 0, err)
      val j = ujson.read(out.trim.linesIterator.toSeq.last)
      assert(j("node_cache")("entries").num == 8192 && j("node_cache")("policy").str == "dm" && j("tus").num == 32, cfg)
      assert(j("node_cache")("hits").num > 0 && j("node_bytes_per_ray").num < j("node_bytes_per_ray_nocache").num, cfg)
    }
    val (_, out, _) = sim("--config", "paper2017-lrp", "--tus", "2")
    val j = ujson.read(out.trim.linesIterator.toSeq.last)
    assert(j("node_cache")("policy").str == "lrp" && j("node_cache")("entries").num == 8192 && j("tus").num == 2)
  }

  test("bad cache values: one error line, status 2") {
    for ((name, args) <- Seq(
      "entries not a power of two" -> Seq("--node-cache", "100"),
      "unknown policy" -> Seq("--node-cache", "64", "--node-policy", "fifo"),
      "MAX_LEVEL out of range" -> Seq("--node-cache", "64", "--max-level", "16"),
      "negative entries" -> Seq("--prim-cache", "-4"),
      "ways with dm" -> Seq("--node-cache", "64", "--node-ways", "4", "--node-policy", "dm"),
      "ways not dividing lines" -> Seq("--prim-cache", "8", "--prim-ways", "4"),
      "TUS zero" -> Seq("--tus", "0")
    )) {
      val (code, out, err) = sim(args: _*)
      assert(code == 2, name)
      assert(err.linesIterator.count(_.startsWith("error:")) == 1 && err.trim.linesIterator.size == 1, s"$name: $err")
      assert(out.isEmpty, name)
    }
  }

  test("BOARD= brings the board's memory bandwidth and clock; MEM_GBPS= overrides it") {
    def bound(extra: String*) = { val (c, o, e) = sim(extra: _*); assert(c == 0, e); ujson.read(o.trim.linesIterator.toSeq.last) }
    val paper = bound(); val kc705 = bound("--board", "xc7k325t"); val own = bound("--board", "xc7k325t", "--mem-gbps", "2.4")
    def r(j: ujson.Value) = j("bandwidth_bound_rays_per_s").num
    // same rays and caches: the bound scales with the bandwidth (12.8 GB/s of the catalog vs the paper's 1.2)
    assert(math.abs(r(kc705) / r(paper) - 12.8 / 1.2) < 1e-9 && math.abs(r(own) / r(paper) - 2.0) < 1e-9)
    val (code, _, err) = sim("--board", "nosuchboard")
    assert(code == 2 && err.contains("unknown BOARD 'nosuchboard'"), err)
  }
}
