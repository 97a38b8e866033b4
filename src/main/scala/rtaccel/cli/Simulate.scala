package rtaccel.cli

import java.nio.file.Files
import rtaccel.io.InputError
import rtaccel.sim.PlatformRun
import rtaccel.sim.PlatformRun.{Outcome, SimOptions}

/** make simulate: the platform RTL (Verilator) on a rays file, checked ray by ray against the reference
  * model; writes OUT/hits.npy and prints the metrics JSON as the last line.
  */
object Simulate {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.simulate)(main0)
  // the run itself (build key, simulation, comparison, the JSON) is sim.PlatformRun's; this reads flags and prints

  /** Writes the hits and the summary, prints the JSON last line, and then fails with status 3 when a check
    * failed: the outputs stay for inspection, the exit status tells scripts not to use them as results.
    */
  def main0(a: Args): Unit = {
    val out = a.path("out")
    val o = run(a)
    o.hits.save(out.resolve("hits.npy"))
    o.vcd.foreach { case (vcd, (from, to)) =>
      val r = rtaccel.sim.VcdWindow.cut(vcd, out.resolve("waves.vcd"), from, to, rtaccel.sim.VcdWindow.clockPeriod(vcd))
      o.json("waves") = ujson.Obj("file" -> out.resolve("waves.vcd").toString, "from_cycle" -> from, "to_cycle" -> to,
        "signals" -> r.signals, "changes" -> r.changes.toDouble)
      Files.delete(vcd) // the whole run's trace can be large; the window is what was asked for
      System.err.println(s"[simulate] waves: cycles $from..$to of ${r.signals} signals in ${out.resolve("waves.vcd")}")
    }
    Cli.writeText(out.resolve("summary.json"), ujson.write(o.json, indent = 2) + "\n")
    println(ujson.write(o.json))
    if (!o.ok) throw new CheckFailed(o.failures)
  }

  /** WAVES=1 [WAVES_FROM=0 WAVES_TO=FROM+20000]: the cycle window of OUT/waves.vcd (tracing is built in only then). */
  def wavesArg(a: Args): Option[(Long, Long)] =
    if (a.get("waves", "0") == "0") None
    else {
      if (a.get("waves", "0") != "1") throw new InputError(s"WAVES must be 0 or 1 (got '${a.get("waves", "")}')")
      def long(k: String, d: Long) = a.opt(k).map(v => v.toLongOption.filter(_ >= 0).getOrElse(
        throw new InputError(s"--$k must be a cycle number >= 0 (got '$v')"))).getOrElse(d)
      val from = long("waves-from", 0L); val to = long("waves-to", from + 20000L)
      if (to < from) throw new InputError(s"WAVES_TO ($to) is before WAVES_FROM ($from)")
      Some((from, to))
    }

  def run(a: Args): Outcome = {
    val (scene, rays, scaleExp) = Cli.inputs(a)
    val b = Cli.build(scene, rays, Cli.request(a))
    PlatformRun.run(b, rays, SimOptions(a.get("scene-label", a.need("tris")), a.int("mem-jitter", 0), a.int("host-stall", 0),
      a.int("seed", 1), a.get("work", "build/sim"), a.opt("max-cycles").map(_.toLong), scaleExp, a.double("mem-error-rate", 0.0), wavesArg(a),
      a.opt("sim-build").map(rtaccel.sim.VerilatorBuild.named), a.get("mem-error-mode", rtaccel.model.MemFaults.Transient)))
  }
}
