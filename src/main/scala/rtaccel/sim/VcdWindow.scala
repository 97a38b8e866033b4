package rtaccel.sim

import java.io.{BufferedReader, BufferedWriter}
import java.nio.file.{Files, Path}

/** Cuts a cycle window out of a VCD trace: the header, the value of every signal at the window's first
  * cycle (as a `$dumpvars` block), then every change inside the window. Simulators write the whole run;
  * the window keeps the file a user opens small. `timePerCycle` = VCD time units per clock cycle.
  */
object VcdWindow {
  final case class Result(signals: Int, changes: Long, firstTime: Long, lastTime: Long)

  /** VCD time units per cycle: the distance between two rising edges of the first signal named `clock`. */
  def clockPeriod(in: Path): Long = {
    val it = scala.io.Source.fromFile(in.toFile)
    try {
      var id: String = null; var time = 0L; var prevRise = -1L; var period = -1L
      val lines = it.getLines()
      while (period < 0 && lines.hasNext) {
        val l = lines.next().trim
        if (id == null && l.startsWith("$var") && l.split("\\s+").lift(4).contains("clock")) id = l.split("\\s+")(3)
        else if (l.startsWith("#")) time = l.substring(1).toLong
        else if (id != null && l == s"1$id") { if (prevRise >= 0) period = time - prevRise; prevRise = time }
      }
      if (period <= 0) throw new rtaccel.io.InputError(s"$in: no clock with two rising edges; cannot place a cycle window")
      period
    } finally it.close()
  }

  def cut(in: Path, out: Path, fromCycle: Long, toCycle: Long, timePerCycle: Long): Result = {
    require(fromCycle >= 0 && toCycle >= fromCycle, s"WAVES_FROM ($fromCycle) must be >= 0 and <= WAVES_TO ($toCycle)")
    val (t0, t1) = (fromCycle * timePerCycle, (toCycle + 1) * timePerCycle - 1)
    val r: BufferedReader = Files.newBufferedReader(in)
    val tmp = out.resolveSibling(s".${out.getFileName}.tmp")
    val w: BufferedWriter = Files.newBufferedWriter(tmp)
    val values = scala.collection.mutable.LinkedHashMap[String, String]() // id -> last value line
    var inHeader = true; var time = 0L; var started = false; var changes = 0L; var last = t0
    def idOf(line: String): String =
      if (line.startsWith("b") || line.startsWith("r")) line.substring(line.indexOf(' ') + 1) else line.substring(1)
    def begin(): Unit = {
      w.write(s"#$t0\n$$dumpvars\n"); values.values.foreach(v => w.write(v + "\n")); w.write("$end\n"); started = true
    }
    try {
      var line = r.readLine()
      while (line != null && time <= t1) {
        val l = line.trim
        if (inHeader) {
          w.write(line + "\n")
          if (l.startsWith("$var")) { val f = l.split("\\s+"); values(f(3)) = if (f(2) == "1") s"x${f(3)}" else s"bx ${f(3)}" }
          if (l.contains("$enddefinitions")) inHeader = false
        } else if (l.startsWith("#")) {
          val t = l.substring(1).toLong
          if (!started && t > t0) begin() // values now hold every change up to t0
          time = t
          if (started && time <= t1) { w.write(l + "\n"); last = time }
        } else if (l.nonEmpty && !l.startsWith("$")) {
          values(idOf(l)) = l
          if (started && time <= t1) { w.write(l + "\n"); changes += 1 }
        }
        line = r.readLine()
      }
      if (!started) begin()
    } finally { r.close(); w.close() }
    Files.move(tmp, out, java.nio.file.StandardCopyOption.REPLACE_EXISTING)
    Result(values.size, changes, t0, last)
  }
}
