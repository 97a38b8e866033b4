package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import rtaccel.config.PlatformParams
import rtaccel.io.InputError

/** CLOCK_MHZ=fmax: the clock of a configuration's circuit as measured earlier, never assumed. Every rays/s
  * names where its clock came from (PlatformParams.clockSource): `given` (CLOCK_MHZ=<MHz>), `board` (the
  * catalog's clock_mhz, or the paper's board's 150 MHz with no BOARD), `proxy` (make area's LUT-level rule) or
  * `routed` (make timing's nextpnr figure).
  */
object ClockSource {
  val sources: Seq[String] = Seq("given", "board", "proxy", "routed")

  /** (MHz, source) of the board top of `p` on `board`: the cached routed result of the same circuit (make timing,
    * the board's speed grade, seed 1) if there is one, else the cached make area proxy (fmax_mhz_proxy), else an
    * error naming the make command that makes one; `makeArgs` are the knobs that command needs ("CONFIG=small TUS=1").
    */
  def resolve(p: PlatformParams, board: Board, makeArgs: String, timingCache: Path = Paths.get("build/timing-cache"),
              areaCache: Path = Paths.get("build/area-cache")): (Double, String) = {
    Files.createDirectories(Paths.get("build"))
    val tmp = Files.createTempDirectory(Paths.get("build"), "clock-source")
    try {
      // the key of a cached result is the emitted Verilog, so it is emitted (seconds; no synthesis)
      val files = rtaccel.cli.EmitVerilog.emit(p, tmp).filter(_.toString.endsWith(".sv"))
      val routed = board.ecp5.flatMap { part =>
        try Route.lookup(Route.Job(files, "RtAccelTop", board, part, part.speedGrade, 1), timingCache).flatMap(_.fmaxMhz)
        catch { case _: InputError => None } // no yowasp tools: nothing can have been routed here
      }
      def proxy = if (board.ecp5.isDefined) None else try {
        val s = Synthesis.run(files, "RtAccelTop", board.family, areaCache, "", _ => (), rtaccel.cli.Cli.version, cachedOnly = true)
        Some(Timing.forFamily(board.family).fmaxMhz(s.deepest._2))
      } catch { case _: Synthesis.NotCached | _: InputError => None }
      routed.map(_ -> "routed").orElse(proxy.map(_ -> "proxy")).getOrElse {
        val make = if (board.ecp5.isDefined) "make timing" else "make area"
        throw new InputError(s"CLOCK_MHZ=fmax: no measured clock of this circuit (RtAccelTop of '${p.name}' on ${board.name}) is cached; " +
          s"make one with `$make $makeArgs BOARD=${board.name}`" +
          (if (board.ecp5.isDefined) "" else s" (a proxy; `make timing $makeArgs BOARD=ecp5-85` routes it on an ECP5 board)") +
          ", or give CLOCK_MHZ=<MHz>")
      }
    } finally Route.deleteTree(tmp)
  }
}
