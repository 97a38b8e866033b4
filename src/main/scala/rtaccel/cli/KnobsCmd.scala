package rtaccel.cli

import java.nio.file.Paths

/** `make knobs`: the knob registry (config.Knobs) exported as JSON, to config/knobs.json by default. The Makefile
  * (through tools/knobs-mk) and dse/ read that file; KnobsSpec keeps it equal to the registry.
  */
object KnobsCmd {
  val defaultPath = "config/knobs.json"
  def text: String = ujson.write(rtaccel.config.Knobs.json, indent = 1) + "\n"

  def main(args: Array[String]): Unit = Cli.run(args, Seq(Flags.Flag("out", s"export file (default $defaultPath)"))) { a =>
    val out = Paths.get(a.get("out", defaultPath))
    Cli.writeText(out, text)
    println(ujson.write(ujson.Obj("knobs" -> rtaccel.config.Knobs.all.size, "out" -> out.toString)))
  }
}
