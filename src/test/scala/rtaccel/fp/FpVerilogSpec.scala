package rtaccel.fp

import java.nio.file.{Files, Paths}
import scala.sys.process._
import org.scalatest.flatspec.AnyFlatSpec
import org.scalatest.matchers.should.Matchers

/** The generators elaborate to SystemVerilog that Verilator lints cleanly (-Wall), for fp32 and other formats. */
class FpVerilogSpec extends AnyFlatSpec with Matchers {
  private def lint(name: String, sv: String, extra: Seq[String]): (Int, String) = {
    val dir = Paths.get("build", "fp-verilog")
    Files.createDirectories(dir)
    val file = dir.resolve(s"$name.sv")
    Files.write(file, sv.getBytes("UTF-8"))
    val out = new StringBuilder
    val rc = (Seq("verilator", "--lint-only", "-Wall", "-Wno-DECLFILENAME") ++ extra :+ file.toString)
      .!(ProcessLogger(l => out ++= l + "\n", l => out ++= l + "\n"))
    (rc, out.toString)
  }

  "Fp and FpDivPipe" should "emit SystemVerilog that passes verilator --lint-only -Wall" in {
    assume(Seq("sh", "-c", "command -v verilator").! == 0, "verilator not installed")
    // The divider's pipeline registers carry the full-width quotient word from the first step on; its upper bits
    // are still zero in early stages and Verilator reports them unused (synthesis prunes constant registers).
    val designs: Seq[(String, () => chisel3.RawModule, Seq[String])] = Seq(
      ("FpOps_fp32", () => new FpOpsComb(Seq((FpFormat.fp32, 1))), Nil),
      ("FpOps_half_8_15_3_2", () => new FpOpsComb(Seq((FpFormat(5, 10), 1), (FpFormat(8, 15), 1), (FpFormat(3, 2), 1))), Nil),
      ("FpDivPipe_fp32", () => new DivPipeHarness(Seq(FpFormat.fp32), Seq(0, 1, 5, 13, 30)), Seq("-Wno-UNUSEDSIGNAL"))
    )
    for ((name, gen, extra) <- designs) {
      val sv = _root_.circt.stage.ChiselStage.emitSystemVerilog(gen(),
        firtoolOpts = Array("-disable-all-randomization", "-strip-debug-info"))
      val (rc, msgs) = lint(name, sv, extra)
      withClue(s"$name:\n$msgs") { rc shouldBe 0; msgs should not include "%Warning" }
      info(s"$name: ${sv.linesIterator.size} lines of SystemVerilog, lint clean")
    }
  }
}
