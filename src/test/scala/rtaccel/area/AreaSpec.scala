package rtaccel.area

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import scala.sys.process._
import rtaccel.cli.{Area, Cli, Flags}

/** make area on one unit (a cache path: block RAM, seconds of synthesis): the memory maps to block RAM, not
  * flip-flops, and the deepest path is named; a board too small is refused with both numbers; a bad BOARD lists
  * the catalog.
  */
class AreaSpec extends AnyFunSuite {
  private val hasYosys = (Seq("sh", "-c", "command -v yosys") ! ProcessLogger(_ => ())) == 0
  private val dir = Files.createTempDirectory("areaspec")
  private def area(extra: String*): (Int, String, String) = {
    val so = new java.io.ByteArrayOutputStream(); val se = new java.io.ByteArrayOutputStream()
    val argv = Array("--config", "small", "--tus", "1", "--unit", "CachePath", "--cache", "build/area-cache",
      "--out", dir.resolve(s"o${extra.hashCode}").toString) ++ extra
    val code = Console.withOut(so)(Console.withErr(se)(Cli.status(argv, Flags.area)(Area.main0)))
    (code, so.toString, se.toString)
  }
  private def last(s: String) = ujson.read(s.trim.linesIterator.toSeq.last)

  test("a node cache's data maps to block RAM as its bits need, and its flip-flops do not grow with its size") {
    assume(hasYosys, "yosys absent: make test installs it from apt")
    val runs = Seq(256, 1024).map { n =>
      val (code, out, err) = area("--node-cache", n.toString, "--board", "xc7k325t")
      assert(code == 0, err)
      n -> last(out)
    }.toMap
    for ((n, j) <- runs) {
      val dataBits = n.toLong * 4 * 257 // 4 beats of 256 bits + their error bit per 128 B node
      assert(j("bram36").num >= dataBits / 36864.0, s"$n entries: ${j("bram36").num} BRAM36 for $dataBits bits")
      assert(j("lut").num > 0 && j("ff").num > 0 && j("fits").bool && j("yosys_version").str.nonEmpty)
      // the timing proxy: a whole number of LUT levels, in a unit the table names, with a clock from it
      val (levels, unit) = (j("lut_levels").num, j("lut_levels_unit").str)
      assert(levels >= 1 && levels.isWhole && j("units")(unit)("lut_levels").num == levels, j.toString)
      assert(j("units").obj.values.forall(_("lut_levels").num <= levels) && j("fmax_mhz_proxy").num > 0)
    }
    val (ff256, ff1024) = (runs(256)("ff").num, runs(1024)("ff").num)
    assert(ff1024 - ff256 < 32, s"flip-flops grew from $ff256 to $ff1024 with 4x the cache: the memory went to registers")
  }

  test("RESP_ORDER=tagged: the data array's read port beside its write port still maps to block RAM, not LUT RAM") {
    assume(hasYosys, "yosys absent: make test installs it from apt")
    // firtool's memory module clocks its read and its write port on two inputs: kept apart, Yosys could not make the
    // read synchronous and mapped the whole array to LUT RAM (Yosys.inlineMemories)
    val (code, out, err) = area("--node-cache", "1024", "--resp-order", "tagged", "--board", "xc7k325t")
    assert(code == 0, err)
    val j = last(out)
    val dataBits = 1024L * 4 * 257
    assert(j("bram36").num >= dataBits / 36864.0 && j("lutram").num < 1024, s"${j("bram36").num} BRAM36, ${j("lutram").num} LUT RAM for $dataBits bits")
  }

  test("a board that is too small is refused with the resource and both numbers (exit 3)") {
    assume(hasYosys, "yosys absent: make test installs it from apt")
    // xc7k325t's clock and memory: the same parameters, so the same circuit (its Verilog kept in memory), whose
    // synthesis the test above cached
    val cat = dir.resolve("tiny.json")
    Files.writeString(cat, """{"boards": {"tiny": {"part": "a test part", "family": "xc7", "lut": 100, "ff": 100000,
      "dsp": 10, "bram36": 100, "dram_gbps": 12.8, "clock_mhz": 200}}}""")
    val (code, out, err) = area("--node-cache", "256", "--board", "tiny", "--catalog", cat.toString)
    assert(code == 3, err)
    val j = last(out)
    assert(!j("fits").bool && j("first_overflow")("resource").str == "lut" && j("first_overflow")("available").num == 100)
    assert(j("first_overflow")("used").num > 100 && err.contains("does not fit tiny"), err)
  }

  test("a BOARD not in the catalog is refused with the catalog's names (exit 2)") {
    val (code, out, err) = area("--board", "xc7z999")
    assert(code == 2 && out.isEmpty && err.contains("unknown BOARD 'xc7z999'") && err.contains("xc5vlx330t") && err.contains("u250"), err)
    val (c1, o1, e1) = area("--board", "ecp5-85")
    assert(c1 == 2 && o1.isEmpty && e1.contains("use make timing BOARD=ecp5-85"), e1) // ECP5: make timing's
    val (c2, _, e2) = area("--fidelity", "fast")
    assert(c2 == 2 && e2.contains("FIDELITY=fast is not one of yosys") && e2.contains("model"), e2)
  }
}
