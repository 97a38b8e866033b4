package rtaccel.top

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import scala.sys.process._
import rtaccel.cli.{Cli, EmitVerilog}

/** `make verilog` + `make lint` in miniature: the board top of several configurations is emitted and must
  * pass `verilator --lint-only -Wall` with only the written-down waivers of tools/lint.vlt.
  */
class VerilogLintSpec extends AnyFunSuite {
  for ((cfg, m, tus) <- Seq(("paper2017", 4, 32), ("small", 2, 1), ("paper2017-lrp", 8, 2)))
    test(s"$cfg with M=$m, TUs=$tus emits SystemVerilog that is lint clean") {
      val out = Files.createTempDirectory(s"lint-$cfg")
      val args = Array("--config", cfg, "--m", m.toString, "--tus", tus.toString, "--out", out.toString)
      assert(Cli.status(args)(a => EmitVerilog.main0(a)) == 0)
      val files = Files.list(out).toArray.map(_.toString).filter(_.endsWith(".sv")).toSeq
      assert(files.exists(_.endsWith("RtAccelTop.sv")))
      val log = new StringBuilder
      val code = (Seq("verilator", "--lint-only", "-Wall", "tools/lint.vlt", "--top-module", "RtAccelTop") ++ files) !
        ProcessLogger(l => log ++= l + "\n", l => log ++= l + "\n")
      assert(code == 0, log.toString)
    }
}
