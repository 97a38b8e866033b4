package rtaccel.area

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import scala.sys.process._
import rtaccel.cli.{AreaFp, Cli, Flags}

/** make area-fp on the multiplier alone (seconds): it takes LUTs and DSP slices and has a depth; bad names are refused. */
class AreaFpSpec extends AnyFunSuite {
  private val hasYosys = (Seq("sh", "-c", "command -v yosys") ! ProcessLogger(_ => ())) == 0
  private val dir = Files.createTempDirectory("areafpspec")
  private def areaFp(extra: String*): (Int, String, String) = {
    val so = new java.io.ByteArrayOutputStream(); val se = new java.io.ByteArrayOutputStream()
    val argv = Array("--cache", "build/area-cache", "--out", dir.resolve(s"o${extra.hashCode}").toString) ++ extra
    val code = Console.withOut(so)(Console.withErr(se)(Cli.status(argv, Flags.areaFp)(AreaFp.main0)))
    (code, so.toString, se.toString)
  }

  test("the fp32 multiplier alone maps to LUTs and DSP slices and has a positive LUT depth") {
    assume(hasYosys, "yosys absent: make test installs it from apt")
    val (code, out, err) = areaFp("--board", "xc7k325t", "--ops", "mul")
    assert(code == 0, err)
    val j = ujson.read(out.trim.linesIterator.toSeq.last)
    val mul = j("ops")("mul")
    assert(j("family").str == "xc7" && j("board").str == "xc7k325t" && j("yosys_version").str.nonEmpty && j("wall_s").num > 0)
    assert(mul("lut").num > 0 && mul("dsp").num > 0 && mul("ff").num >= 96, mul.toString) // 2 x 32 in, 32 out
    assert(mul("lut_levels").num >= 1 && mul("lut_levels").num.isWhole && mul("fmax_mhz_proxy").num > 0, mul.toString)
    assert(j("ops").obj.keySet == Set("mul"))
  }

  test("a BOARD not in the catalog or an unknown operation is refused (exit 2) before anything is written") {
    val (code, out, err) = areaFp("--board", "xc7z999", "--ops", "mul")
    assert(code == 2 && out.isEmpty && err.contains("unknown BOARD 'xc7z999'") && err.contains("xc5vlx330t") && err.contains("u250"), err)
    val (c2, o2, e2) = areaFp("--board", "xc7k325t", "--ops", "mul,sqrt")
    assert(c2 == 2 && o2.isEmpty && e2.contains("'sqrt'") && e2.contains("add, mul, div"), e2)
    assert(!Files.exists(dir.resolve(s"o${Seq("--board", "xc7z999", "--ops", "mul").hashCode}")))
  }
}
