package rtaccel.cli

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.area.Levels
import rtaccel.io.InputError

/** make timing-fit on a hand-made routing cache: the least-squares rule, which results it reads, its refusal. */
class TimingFitSpec extends AnyFunSuite {
  private def cache(routes: Seq[(String, Int, Double, Int)]) = {
    val d = Files.createTempDirectory("timing-cache")
    for (((top, lv, fmax, ver), i) <- routes.zipWithIndex) {
      val k = d.resolve(f"k$i%02d"); Files.createDirectories(k)
      Files.writeString(k.resolve("result.json"), ujson.write(ujson.Obj("top" -> top, "fmax_mhz" -> fmax, "fits" -> true,
        "proxy_lut_levels" -> lv, "proxy_levels_version" -> ver)))
    }
    d
  }

  test("the fit recovers a rule that the routes follow exactly, and reads only routes with the current proxy") {
    // period = 2.5 + 1.25 x levels
    val exact = Seq(4, 8, 12).map(lv => (s"U$lv", lv, 1000.0 / (2.5 + 1.25 * lv), Levels.version))
    val d = cache(exact :+ ("Old", 20, 10.0, Levels.version - 1))
    val ps = TimingFit.points(d)
    assert(ps.map(_.top) == Seq("U4", "U8", "U12"))
    val (o, l) = TimingFit.fit(ps)
    assert(math.abs(o - 2.5) < 1e-9 && math.abs(l - 1.25) < 1e-9)
  }

  test("--write 1 puts the fitted figures and their source into the ecp5 entry and leaves the file valid JSON") {
    val exact = Seq(4, 8, 12).map(lv => (s"U$lv", lv, 1000.0 / (2.5 + 1.25 * lv), Levels.version))
    val t = Files.createTempFile("timing", ".json")
    Files.copy(rtaccel.area.Timing.defaultPath, t, java.nio.file.StandardCopyOption.REPLACE_EXISTING)
    Console.withOut(new java.io.ByteArrayOutputStream) {
      TimingFit.main0(Args(Map("cache" -> cache(exact).toString, "write" -> "1", "timing" -> t.toString)))
    }
    val e = ujson.read(Files.readString(t))("families")("ecp5")
    assert(e("level_ns").num == 1.25 && e("overhead_ns").num == 2.5 && e("source").str.startsWith("fitted by make timing-fit to 3 routes"), e.toString)
    // the other families are untouched
    assert(ujson.read(Files.readString(t))("families")("xc5v") == ujson.read(Files.readString(rtaccel.area.Timing.defaultPath))("families")("xc5v"))
  }

  test("too few routes to fit: exit 2 naming the commands that make more") {
    val d = cache(Seq(("A", 4, 150.0, Levels.version), ("B", 4, 140.0, Levels.version), ("C", 4, 145.0, Levels.version)))
    val e = intercept[InputError](TimingFit.main0(Args(Map("cache" -> d.toString))))
    assert(e.getMessage.contains("1 distinct depth") && e.getMessage.contains("make timing"))
  }
}
