package rtaccel.cli

import java.nio.file.{Files, Paths}
import rtaccel.top.RtAccelTop

/** make verilog: SystemVerilog of the board top for a preset (optionally with TUS/M/MPPL overrides), one
  * file per module under OUT, through firtool.
  */
object EmitVerilog {
  val LoweringOptions = "--lowering-options=disallowLocalVariables,disallowPackedArrays"

  def main(args: Array[String]): Unit = Cli.run(args, Flags.verilog)(main0)

  /** SystemVerilog of the board top of `p`, one file per module in `out` (old .sv files removed); the files.
    * The last few circuits' text is kept in memory: CLOCK_MHZ=fmax, make timing and make area each emit the
    * circuit they look up, often the same one again in one process (seconds of elaboration each time).
    */
  def emit(p: rtaccel.config.PlatformParams, out: java.nio.file.Path): Seq[java.nio.file.Path] = {
    val key = rtaccel.sim.PlatformRun.paramsDigest(p) // what shapes the circuit: not the preset's name, not a clock within the budget
    val kept = recent.get(key)
    kept match {
      case Some(texts) =>
        clearSv(out)
        texts.map { case (name, bytes) => Files.write(out.resolve(name), bytes) }.sortBy(_.toString)
      case None =>
        val files = emitModule(new RtAccelTop(p), out)
        val texts = files.map(f => f.getFileName.toString -> Files.readAllBytes(f))
        recent.put(key, texts)
        files
    }
  }
  // a few MB of text per circuit (the 32-TU paper2017 about 10): six keep the circuits of the two commands a test
  // JVM or a server may run side by side
  private val recent = new rtaccel.io.Lru[String, Seq[(String, Array[Byte])]](6)
  private def clearSv(out: java.nio.file.Path): Unit = {
    Files.createDirectories(out)
    // a previous configuration's modules must not linger next to this one's
    Files.list(out).toArray.map(_.asInstanceOf[java.nio.file.Path]).filter(f => f.toString.endsWith(".sv")).foreach(Files.delete)
  }

  /** SystemVerilog of any module (make area-fp's probes as well as the board top), as `emit` writes it. */
  def emitModule(gen: => chisel3.RawModule, out: java.nio.file.Path): Seq[java.nio.file.Path] = {
    clearSv(out)
    // randomization off and debug info stripped: the output is for synthesis and lint, not for simulation
    new _root_.circt.stage.ChiselStage().execute(
      Array("--target-dir", out.toString, "--target", "systemverilog", "--split-verilog") ++
        (if (sys.env.contains("RTACCEL_DEBUG")) Array("--full-stacktrace") else Array[String]()),
      Seq(chisel3.stage.ChiselGeneratorAnnotation(() => gen),
        _root_.circt.stage.FirtoolOption("-disable-all-randomization"), _root_.circt.stage.FirtoolOption("-strip-debug-info"),
        // the SystemVerilog subset that Yosys 0.23 reads (no `automatic` locals in always blocks, no packed
        // arrays) and Verilator lints clean: one output for synthesis, lint and vendor tools
        _root_.circt.stage.FirtoolOption(EmitVerilog.LoweringOptions)))
    Files.list(out).toArray.map(_.asInstanceOf[java.nio.file.Path]).filter(f => f.toString.endsWith(".sv") || f.toString.endsWith(".v")).sortBy(_.toString).toSeq
  }

  def main0(a: Args): Unit = {
    val p = Cli.preset(a, "make verilog")
    val out = Paths.get(a.get("out", s"build/${p.name}"))
    val files = emit(p, out)
    // the host's view of this build: register map, counters and the configuration words it reads back
    Cli.writeText(out.resolve("rtaccel_regs.h"), rtaccel.top.RegHeaders.c(p, Cli.version))
    Cli.writeText(out.resolve("rtaccel_regs.py"), rtaccel.top.RegHeaders.python(p, Cli.version))
    System.err.println(s"[verilog] ${files.length} files in $out (config ${p.name}: ${p.tus} TUs, M=${p.m}, MPPL=${p.mppl}, stack ${p.stackDepth})")
    println(ujson.write(ujson.Obj.from(rtaccel.config.Knobs.echo(p, "verilog") ++ Seq[(String, ujson.Value)](
      "out" -> out.toString, "files" -> files.length, "top" -> "RtAccelTop",
      "regs_h" -> out.resolve("rtaccel_regs.h").toString, "regs_py" -> out.resolve("rtaccel_regs.py").toString))))
  }
}
