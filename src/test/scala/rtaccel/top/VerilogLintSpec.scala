package rtaccel.top

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import scala.sys.process._
import rtaccel.cli.{Cli, EmitVerilog, Flags}

/** `make verilog` + `make lint` in miniature: the board top of several configurations is emitted and must
  * pass `verilator --lint-only -Wall` with only the written-down waivers of tools/lint.vlt, and Yosys must
  * read and elaborate the same files.
  */
class VerilogLintSpec extends AnyFunSuite {
  private val hasYosys = (Seq("sh", "-c", "command -v yosys") ! ProcessLogger(_ => ())) == 0
  private val regress = rtaccel.Regress.full
  // the cached ones cover the DM, LRU, PLRU and hybrid (LRP) families, on both paths; one circuit carries every
  // precision and stack option at once (outward-rounded boxes, the watertight test, q8 nodes, packed leaves with a
  // leaf-row cache line, the short stack); make regress adds M=8, the breadth-first buffer and each option on its own.
  // Each case is an elaboration, firtool and a lint of a whole platform: make test's three carry every option between them.
  private val cases = Seq(("paper2017", 4, 32, "--node-cache 8192 --prim-cache 1024 --prim-ways 2"),
      // (with one lookup per cycle: write-first tag RAMs in both of the hybrid's arrays and the PLRU's)
      // (and two response streams in request order each)
      ("paper2017-lrp", 4, 2, "--node-cache 256 --node-policy hybrid --max-level 4 --prim-cache 256 --prim-ways 4 --prim-policy plru --tag-forward 1 --resp-order path"),
      // every precision and stack option (the packed leaves' LeafAssembler on the leaf stream) with tagged answers:
      // clean hits beside the tickets in both caches, the IU's job tables, and the ray stores of four clusters of one
      // TU each over 2 channels (the TC's writes routed by cluster); NODE_BANKS: one node cache in 4 banks for the 4
      // clusters (both crossbars wider than one), one lookup per cycle
      ("small", 4, 4, "--box-format bf16 --tri-test watertight --node-format q8 --prim-format packed --short-stack 4 " +
        "--resp-order tagged --ray-store 1 --ius 4 --mem-channels 2 --node-banks 4 --tag-forward 1 --node-cache 64 --node-ways 2 --prim-cache 64 --prim-ways 2")) ++
    (if (!regress) Nil else Seq(("paper2017", 4, 32, ""), ("paper2017", 4, 8, "--node-cache 8192 --prim-cache 1024 --prim-ways 2"),
      ("small", 4, 4, "--ius 4 --mem-channels 2 --node-cache 64 --prim-cache 64 --prim-ways 2"), // request order over the channels
      ("small", 4, 4, "--resp-order tagged --ray-store 1 --ius 2 --node-banks 4 --tag-forward 1 --node-cache 64 --node-ways 2 --prim-cache 64 --prim-ways 2"),
      ("small", 4, 2, "--box-format bf16 --tri-test watertight --node-format q8 --node-cache 64 --prim-format packed --prim-cache 64 --prim-ways 2 --short-stack 4 --resp-order path"),
      ("small", 2, 1, ""), ("paper2017-lrp", 8, 2, ""), ("small", 4, 1, "--node-cache 64 --node-policy bf"),
      ("paper2017-lrp", 2, 1, "--node-cache 64 --node-ways 4 --node-policy lrp --max-level 2"),
      ("small", 4, 2, "--box-format bf16 --short-stack 4"), ("small", 4, 2, "--tri-test watertight"),
      ("paper2017", 4, 2, "--prim-format packed --prim-cache 64 --prim-ways 2"),
      ("small", 4, 2, "--node-format q8 --node-cache 64"),
      ("paper2017", 4, 32, "--ius 2 --node-cache 1024"), ("paper2017", 4, 4, "--resp-order path"), ("paper2017", 4, 8, "--resp-order tagged --node-cache 0"),
      ("paper2017", 4, 32, "--ray-store 1"), // the request-order job FIFO without rays
      ("small", 4, 2, "--resp-order path --node-cache 64 --prim-format packed --prim-cache 64"),
      ("small", 4, 4, "--resp-order tagged --ray-store 1 --ius 2 --node-cache 64 --prim-cache 64 --prim-ways 2"),
      ("small", 4, 2, "--tri-format fp64"))) // the widened Möller–Trumbore pipe: a large circuit to lint
  for ((cfg, m, tus, caches) <- cases)
    test(s"$cfg with M=$m, TUs=$tus${if (caches.isEmpty) "" else s", caches $caches"} emits SystemVerilog that is lint clean") {
      val out = Files.createTempDirectory(s"lint-$cfg")
      val args = Array("--config", cfg, "--m", m.toString, "--tus", tus.toString, "--out", out.toString) ++
        caches.split(" ").filter(_.nonEmpty)
      assert(Cli.status(args, Flags.verilog)(a => EmitVerilog.main0(a)) == 0)
      val files = Files.list(out).toArray.map(_.toString).filter(_.endsWith(".sv")).toSeq
      assert(files.exists(_.endsWith("RtAccelTop.sv")))
      val log = new StringBuilder
      val code = (Seq("verilator", "--lint-only", "-Wall", "tools/lint.vlt", "--top-module", "RtAccelTop") ++ files) !
        ProcessLogger(l => log ++= l + "\n", l => log ++= l + "\n")
      assert(code == 0, log.toString)
      // the same files are what synthesis reads (issue: Yosys 0.23 refused `automatic` locals before the
      // firtool lowering options of EmitVerilog)
      assume(hasYosys, "yosys absent: make test installs it from apt")
      val ylog = new StringBuilder
      val ycode = Seq("yosys", "-q", "-p", s"read_verilog -sv ${files.mkString(" ")}; hierarchy -check -top RtAccelTop") !
        ProcessLogger(l => ylog ++= l + "\n", l => ylog ++= l + "\n")
      assert(ycode == 0, ylog.toString)
    }
}
