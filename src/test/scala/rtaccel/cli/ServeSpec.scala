package rtaccel.cli

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes

class ServeSpec extends AnyFunSuite {
  private val dir = Files.createTempDirectory("servespec")
  private val (tris, raysPath) = TestScenes.writeInputs(dir, TestScenes.soup(5, 400), TestScenes.rays(6, 200))
  private val base = Seq("--tris", tris.toString, "--rays", raysPath.toString, "--scene-label", "soup")
  private def request(cmd: String, args: Seq[String]): String =
    ujson.write(ujson.Obj("cmd" -> cmd, "args" -> ujson.Arr.from(args.map(ujson.Str(_)))))
  /** The command's own JSON last line, run as its entry point does (no memo). */
  private def oneShot(args: Seq[String]): ujson.Value = {
    val out = new java.io.ByteArrayOutputStream()
    assert(Console.withOut(out)(Console.withErr(new java.io.ByteArrayOutputStream())(
      Cli.status((base ++ args).toArray, Flags.cacheSim)(CacheSim.main0))) == 0)
    ujson.read(out.toString.trim.linesIterator.toSeq.last)
  }
  // timings and the reuse flag differ between a fresh and a served run; every count must not
  private def counts(j: ujson.Value) = j.obj.filterNot { case (k, _) => k.endsWith("_s") || k.endsWith("_per_s") || k.endsWith("_first") || k == "trace_reused" }

  private def served[T](body: => T): T = {
    Memo.clear(); Memo.enabled = true
    try body finally { Memo.enabled = false; Memo.clear() }
  }

  test("served cachesim equals the entry point's result; a cache-only change replays the kept trace") {
    val cfgs = Seq(Seq("--node-cache", "256", "--tus", "2"), Seq("--node-cache", "1024", "--node-policy", "lrp", "--max-level", "3"),
      Seq("--node-cache", "0", "--prim-cache", "512"))
    val fresh = cfgs.map(oneShot)
    served {
      val answers = cfgs.map(c => Serve.answer(request("cachesim", base ++ c)))
      for ((a, f) <- answers.zip(fresh)) {
        assert(a("status").num == 0 && a("error").isNull, a)
        assert(counts(a("result")) == counts(f))
      }
      // LRP stores the level in the node refs (another memory image, so another trace); the primitive-cache-only
      // point has the first point's image and replays its trace
      assert(answers.map(_("result")("trace_reused").bool) == Seq(false, false, true))
      assert(Memo.misses("scene") == 1 && Memo.hits("scene") == 2 && Memo.misses("bvh") == 1)
    }
  }

  test("a tree-shaping change rebuilds the tree and retraces") {
    served {
      assert(Serve.answer(request("cachesim", base ++ Seq("--mppl", "2")))("status").num == 0)
      assert(Serve.answer(request("cachesim", base ++ Seq("--mppl", "4")))("status").num == 0)
      assert(Memo.misses("bvh") == 2 && Memo.misses("trace") == 2)
    }
  }

  test("bad requests and refused input answer status 2 with the error; the server keeps going") {
    served {
      for ((line, words) <- Seq(
        "not json" -> "not JSON", """{"cmd": "nope", "args": []}""" -> "unknown cmd", """{"cmd": "cachesim"}""" -> "a request is",
        request("cachesim", base ++ Seq("--node-cahce", "64")) -> "did you mean --node-cache?",
        request("cachesim", base ++ Seq("--m", "5")) -> "M",
        request("cachesim", Seq("--tris", dir.resolve("absent.npy").toString, "--rays", raysPath.toString)) -> "absent.npy")) {
        val a = Serve.answer(line)
        assert(a("status").num == 2 && a("result").isNull, line)
        assert(a("error").str.contains(words), s"$line: ${a("error")}")
      }
      assert(Serve.answer(request("cachesim", base))("status").num == 0)
    }
  }

  test("analyze is served too, and its tree builds are kept") {
    served {
      val out = dir.resolve("analyze")
      val a = Serve.answer(request("analyze", base ++ Seq("--out", out.toString, "--mppls", "2,4")))
      assert(a("status").num == 0, a)
      assert(a("result")("bytes_per_ray").obj.keySet == Set("2", "4"))
      assert(Files.isRegularFile(out.resolve("levels.csv")))
    }
  }

  test("a command that throws answers status 1 with the exception; the next request is served") {
    served {
      val a = Serve.answer(request("analyze", base ++ Seq("--out", "/proc/no-such-dir/x", "--mppls", "4")))
      assert(a("status").num == 1 && a("result").isNull, a)
      assert(a("error").str.contains("analyze crashed") && a("error").str.contains("/proc/no-such-dir"), a)
      assert(Serve.answer(request("cachesim", base))("status").num == 0)
    }
  }
}
