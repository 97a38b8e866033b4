package rtaccel.cli

import java.nio.file.{Files, Path}
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.scene.Hits

class CliSpec extends AnyFunSuite {
  private val dir = Files.createTempDirectory("clispec")
  private def save(name: String, data: Array[Float], shape: Seq[Int]): Path = TestScenes.saveFloats(dir, name, data, shape)
  private val scene = TestScenes.soup(2, 300)
  private val rays = TestScenes.rays(3, 100)
  private val (tris, raysPath) = TestScenes.writeInputs(dir, scene, rays)
  /** A valid trace call with `extra` replacing or adding flags (a flag may be given only once). */
  private def argv(out: Path, extra: Seq[String]): Array[String] = {
    val base = Seq("--tris" -> tris.toString, "--rays" -> raysPath.toString, "--out" -> out.toString)
    val over = extra.grouped(2).collect { case Seq(k, v) => k -> v }.toSeq
    (base.filterNot(b => over.exists(_._1 == b._1)) ++ over).flatMap { case (k, v) => Seq(k, v) }.toArray ++
      (if (extra.length % 2 == 1) Array(extra.last) else Array.empty[String])
  }
  private def captured(args: Array[String], flags: Seq[Flags.Flag] = Flags.trace)(body: Args => Unit): (Int, String, String) = {
    val out = new java.io.ByteArrayOutputStream(); val err = new java.io.ByteArrayOutputStream()
    val code = Console.withOut(out)(Console.withErr(err)(Cli.status(args, flags)(body)))
    (code, out.toString, err.toString)
  }
  private def trace(out: Path, extra: String*) = captured(argv(out, extra))(a => Trace.main0(a))._1

  test("trace writes hits, access trace and summary") {
    val out = dir.resolve("ok")
    assert(trace(out) == 0)
    for (f <- Seq("hits.npy", "trace.npy", "summary.json")) assert(Files.size(out.resolve(f)) > 0, f)
    val s = ujson.read(Files.readString(out.resolve("summary.json")))
    assert(s("rays").num == 100 && s("triangles").num == 300 && s("stack_overflow_rays").num == 0)
    // the knobs as the trace resolved them (CONFIG=fit: the fitted stack), echoed from the registry
    val p = Cli.build(scene, rays, Cli.request(Args(Map.empty))).params
    for ((k, v) <- rtaccel.config.Knobs.echo(p, "trace")) assert(s(k) == v, k)
    assert(s("stack_depth").num == s("stack_bound").num && s("config").str == "fit")
  }

  test("bad input: one error, status 2, nothing written in OUT") {
    val bad = save("bad.npy", new Array[Float](14), Seq(2, 7))
    for ((name, args) <- Seq(
      "wrong rays shape" -> Seq("--rays", bad.toString),
      "missing scene" -> Seq("--tris", dir.resolve("nope.npy").toString),
      "MPPL over the count field" -> Seq("--mppl", "32"),
      "M not 2/4/8" -> Seq("--m", "5"),
      "unknown preset" -> Seq("--config", "nonexistent"),
      "odd argument list" -> Seq("--m"),
      "misspelled flag" -> Seq("--node-cahce", "64"),
      "flag of another command" -> Seq("--mem-jitter", "3"),
      "not an integer" -> Seq("--tus", "many"),
      "a triangle format narrower than fp32" -> Seq("--tri-format", "bf16"),
      "a wider triangle format with the watertight test" -> Seq("--tri-format", "fp64", "--tri-test", "watertight")
    )) {
      val out = dir.resolve(name.replace(' ', '_'))
      val (code, stdout, err) = captured(argv(out, args))(a => Trace.main0(a))
      assert(code == 2, name)
      assert(err.trim.linesIterator.toSeq.length == 1 && err.startsWith("error: "), s"$name: $err")
      assert(stdout.isEmpty && !Files.exists(out), s"$name left output")
    }
  }

  test("TRI_FORMAT: a narrower format is refused naming the knob, the format and what to use; fp64 traces") {
    val (code, _, err) = captured(argv(dir.resolve("tri16"), Seq("--tri-format", "fp16")))(a => Trace.main0(a))
    assert(code == 2 && err.contains("TRI_FORMAT=fp16: TRI_FORMAT takes fp32 or fp64, or e<8..11>m<23..52>") && err.contains("loses hits"), err)
    val out = dir.resolve("tri64")
    val (ok, stdout, _) = captured(argv(out, Seq("--tri-format", "fp64")))(a => Trace.main0(a))
    assert(ok == 0 && ujson.read(stdout.trim.linesIterator.toSeq.last)("numerics")("tri_format").str == "fp64", stdout)
  }

  test("TRI_II / BOX_II above a job's memory beats are refused with the value to use") {
    def cachesim(extra: String*) = captured(Array("--tris", tris.toString, "--rays", raysPath.toString) ++ extra, Flags.cacheSim)(CacheSim.main0)
    // packed leaves: the LeafAssembler spaces its records itself, so any TRI_II goes
    val (c1, o1, e1) = cachesim("--tri-ii", "3", "--prim-format", "packed")
    assert(c1 == 0 && ujson.read(o1.trim.linesIterator.toSeq.last)("tri_ii").num == 3, e1)
    val (c2, o2, e2) = cachesim("--tri-ii", "3")
    assert(c2 == 2 && o2.isEmpty && e2.contains("it takes 2 at a 256-bit bus") && e2.contains("use TRI_II=2 or PRIM_FORMAT=packed"), e2)
    val (c3, _, e3) = cachesim("--box-ii", "4", "--m", "2")
    assert(c3 == 2 && e3.contains("BOX_II=4") && e3.contains("use BOX_II=2 or less"), e3)
    val (c4, o4, e4) = cachesim("--box-ii", "4", "--tri-ii", "2", "--m", "4")
    assert(c4 == 0 && ujson.read(o4.trim.linesIterator.toSeq.last)("box_ii").num == 4, e4)
  }

  test("a misspelled flag names the nearest valid one; a repeated flag is refused") {
    val (c1, _, e1) = captured(Array("--tris", tris.toString, "--rays", raysPath.toString, "--node-cahce", "64"), Flags.cacheSim)(CacheSim.main0)
    assert(c1 == 2 && e1.contains("--node-cahce") && e1.contains("did you mean --node-cache?"), e1)
    val (c2, _, e2) = captured(argv(dir.resolve("twice"), Nil) ++ Array("--tus", "2", "--tus", "4"))(Trace.main0)
    assert(c2 == 2 && e2.contains("--tus") && e2.contains("more than once"), e2)
    assert(Flags.nearest("stak-depth", Flags.trace) == "stack-depth" && Flags.distance("kitten", "sitting") == 3)
  }

  test("a fixed preset refuses a scene that exceeds it; the fitted default accepts it") {
    assert(trace(dir.resolve("fits"), "--config", "paper2017", "--m", "8", "--mppl", "1") == 0, "paper2017 holds a small scene")
    val narrow = rtaccel.config.Presets.small.copy(refs = rtaccel.config.RefFormat(4, 4, 2, 0))
    val bvh = rtaccel.bvh.Mbvh.build(scene, narrow)
    val e = intercept[rtaccel.io.InputError](rtaccel.config.Fit.check(narrow, bvh, "soup"))
    assert(e.getMessage.contains("node id field needs") && e.getMessage.contains("4 bits"), e.getMessage)
  }

  test("STACK below the scene's bound is kept: overflowed rays get the overflow record, the others are unchanged") {
    val deep = dir.resolve("deep"); val shallow = dir.resolve("shallow")
    val (c0, _, _) = captured(argv(deep, Seq("--m", "8", "--mppl", "1")))(Trace.main0)
    val (c1, _, err) = captured(argv(shallow, Seq("--m", "8", "--mppl", "1", "--stack-depth", "2")))(Trace.main0)
    assert(c0 == 0 && c1 == 0 && err.contains("[warn] STACK=2"), err)
    val s = ujson.read(Files.readString(shallow.resolve("summary.json")))
    assert(s("stack_depth").num == 2 && s("overflowed").num > 0 && s("max_stack").num <= 2)
    val h0 = Hits.load(deep.resolve("hits.npy")); val h1 = Hits.load(shallow.resolve("hits.npy"))
    val flagged = (0 until h1.count).filter(i => h1.prim(i) == Hits.Overflow)
    assert(flagged.length == s("overflowed").num.toInt)
    for (i <- flagged) assert(h1.t(i).isPosInfinity && h1.u(i) == 0f && h1.v(i) == 0f)
    for (i <- 0 until h1.count if h1.prim(i) != Hits.Overflow)
      assert(h0.prim(i) == h1.prim(i) && java.lang.Float.floatToRawIntBits(h0.t(i)) == java.lang.Float.floatToRawIntBits(h1.t(i)), s"ray $i")
  }

  test("MAX_STEPS: the rays that need more fetches get the step-limit record (prim -4), the others are unchanged; a negative value is refused") {
    val free = dir.resolve("steps-default"); val tight = dir.resolve("steps-3")
    val (c0, _, _) = captured(argv(free, Seq("--m", "2", "--mppl", "1")))(Trace.main0)
    val (c1, _, _) = captured(argv(tight, Seq("--m", "2", "--mppl", "1", "--max-steps", "3")))(Trace.main0)
    assert(c0 == 0 && c1 == 0)
    val s0 = ujson.read(Files.readString(free.resolve("summary.json"))); val s = ujson.read(Files.readString(tight.resolve("summary.json")))
    assert(s0("step_limit_rays").num == 0 && s0("max_steps").num >= s0("nodes").num + s0("leaves").num, "the default bounds every ray")
    assert(s("max_steps").num == 3 && s("step_limit_rays").num > 0)
    val h0 = Hits.load(free.resolve("hits.npy")); val h1 = Hits.load(tight.resolve("hits.npy"))
    val flagged = (0 until h1.count).filter(i => h1.prim(i) == Hits.StepLimit)
    assert(flagged.length == s("step_limit_rays").num.toInt && flagged.forall(i => h1.t(i).isPosInfinity))
    for (i <- 0 until h1.count if !flagged.contains(i)) assert(h0.prim(i) == h1.prim(i), s"ray $i")
    val (c2, _, err) = captured(argv(dir.resolve("steps-bad"), Seq("--max-steps", "-1")))(Trace.main0)
    assert(c2 == 2 && err.startsWith("error: MAX_STEPS=-1: MAX_STEPS takes 0 or an integer 1..") && !Files.exists(dir.resolve("steps-bad")), err)
  }

  test("property: random bad flag lists are refused with one error line, status 2, nothing written") {
    val r = new scala.util.Random(7)
    val names = Flags.trace.map(_.name)
    def word() = r.alphanumeric.take(1 + r.nextInt(8)).mkString
    for (k <- 0 until 150) {
      val out = dir.resolve(s"prop$k")
      val base = Seq("--tris", tris.toString, "--rays", raysPath.toString, "--out", out.toString)
      val n = names(r.nextInt(names.length))
      val bad: Seq[String] = k % 6 match {
        case 0 => Seq(s"--${n.patch(r.nextInt(n.length), word(), 1)}", "1")                 // misspelled flag
        case 1 => Seq(s"--$n", "4", s"--$n", "4").filterNot(_ => Set("tris", "rays", "out")(n)) match {
          case Nil => Seq("--m", "4", "--m", "2"); case x => x }                          // repeated flag
        case 2 => Seq(Seq("--m", "--mppl", "--tus", "--stack-depth", "--node-cache", "--max-level")(r.nextInt(6)), word() + "x") // not an integer
        case 3 => Seq("--m", (r.nextInt(20) + 9).toString)                                  // M out of range
        case 4 => Seq(word())                                                             // stray word
        case _ => Seq("--node-policy", "q" + word())                                      // unknown policy
      }
      val (code, stdout, err) = captured((base ++ bad).toArray)(Trace.main0)
      assert(code == 2, s"case $k ${bad.mkString(" ")}: status $code")
      assert(err.trim.linesIterator.count(_.startsWith("error: ")) == 1 && !err.contains("Exception"), s"case $k: $err")
      assert(stdout.isEmpty && !Files.exists(out), s"case $k left output")
    }
  }

  test("analyze and bench honour CONFIG: a preset is checked against the scene, not fitted") {
    val out = dir.resolve("analyze")
    val args = Array("--tris", tris.toString, "--rays", raysPath.toString, "--out", out.toString, "--mppls", "1,4")
    val (c0, _, e0) = captured(args ++ Array("--config", "paper2017"), Flags.analyze)(Analyze.main0)
    assert(c0 == 0, e0)
    assert(Files.readString(out.resolve("levels.csv")).linesIterator.next().contains("config=paper2017 "))
    val (c1, _, _) = captured(args, Flags.analyze)(Analyze.main0)
    assert(c1 == 0 && Files.readString(out.resolve("levels.csv")).linesIterator.next().contains("config=fit "))
    val b = Array("--tris", tris.toString, "--rays", raysPath.toString, "--repeat", "1")
    val (c2, o2, e2) = captured(b ++ Array("--config", "small"), Flags.bench)(Bench.main0)
    assert(c2 == 0 && ujson.read(o2.trim.linesIterator.toSeq.last)("config").str == "small", e2)
  }
}
