package rtaccel.cli

import java.nio.file.{Files, Path}
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes

class CliSpec extends AnyFunSuite {
  private val dir = Files.createTempDirectory("clispec")
  private def save(name: String, data: Array[Float], shape: Seq[Int]): Path = TestScenes.saveFloats(dir, name, data, shape)
  private val scene = TestScenes.soup(2, 300)
  private val rays = TestScenes.rays(3, 100)
  private val (tris, raysPath) = TestScenes.writeInputs(dir, scene, rays)
  private def trace(out: Path, extra: String*) =
    Cli.status(Array("--tris", tris.toString, "--rays", raysPath.toString, "--out", out.toString) ++ extra)(a => Trace.main0(a))

  test("trace writes hits, access trace and summary") {
    val out = dir.resolve("ok")
    assert(trace(out) == 0)
    for (f <- Seq("hits.npy", "trace.npy", "summary.json")) assert(Files.size(out.resolve(f)) > 0, f)
    val s = ujson.read(Files.readString(out.resolve("summary.json")))
    assert(s("rays").num == 100 && s("triangles").num == 300 && s("stack_overflow_rays").num == 0)
  }

  test("bad input: one error, status 2, nothing written in OUT") {
    val bad = save("bad.npy", new Array[Float](14), Seq(2, 7))
    for ((name, args) <- Seq(
      "wrong rays shape" -> Seq("--rays", bad.toString),
      "missing scene" -> Seq("--tris", dir.resolve("nope.npy").toString),
      "MPPL over the count field" -> Seq("--mppl", "32"),
      "M not 2/4/8" -> Seq("--m", "5"),
      "scene over a preset" -> Seq("--config", "paper2017", "--stack-depth", "2"),
      "unknown preset" -> Seq("--config", "nonexistent"),
      "odd argument list" -> Seq("--m")
    )) {
      val out = dir.resolve(name.replace(' ', '_'))
      // later keys win, so each case overrides one argument of a valid call
      val argv = Array("--tris", tris.toString, "--rays", raysPath.toString, "--out", out.toString) ++ args
      assert(Cli.status(argv)(a => Trace.main0(a)) == 2, name)
      assert(!Files.exists(out), s"$name left files in OUT")
    }
  }

  test("a fixed preset refuses a scene that exceeds it; the fitted default accepts it") {
    val out = dir.resolve("refused")
    assert(trace(dir.resolve("fits"), "--config", "paper2017", "--m", "8", "--mppl", "1") == 0, "paper2017 holds a small scene")
    val err = new java.io.ByteArrayOutputStream()
    val code = Console.withErr(err)(trace(out, "--config", "paper2017", "--stack-depth", "2"))
    assert(code == 2 && !Files.exists(out))
    assert(err.toString.contains("traversal stack needs") && err.toString.contains("has 2 entries"), err.toString)
    assert(trace(dir.resolve("fit"), "--stack-depth", "2") == 0, "CONFIG=fit sizes the stack to the scene")
  }
}
