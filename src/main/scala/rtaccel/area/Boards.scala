package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import rtaccel.io.InputError

/** An FPGA board of the catalog (boards/catalog.json): capacities, the Yosys family, memory and clock.
  * `lut`/`ff`/`dsp`/`bram36` are a Xilinx part's (make area's units); an ECP5 part's own resources are in `ecp5`
  * (and its `lut`/`dsp`/`bram36` are 0: LUT4, MULT18X18D and 18 Kb EBR are not LUT6, DSP48 and RAMB36).
  */
final case class Board(name: String, part: String, family: String, lut: Long, ff: Long, dsp: Long, bram36: Long,
                       dramGbps: Double, clockMhz: Double, source: String, ecp5: Option[Ecp5Part] = None) {
  /** Resources in the order a verdict checks them. */
  def capacities: Seq[(String, Long)] = ecp5.fold(Seq("lut" -> lut, "ff" -> ff, "dsp" -> dsp, "bram36" -> bram36))(_.capacities)
}

/** A Lattice ECP5 part as nextpnr-ecp5 names it: `device` is its flag without dashes (um5g-85k), `speedGrade` the
  * part's own (the 5G parts are all -8; nextpnr defaults to -6, the slowest, unless told).
  */
final case class Ecp5Part(device: String, pkg: String, speedGrade: Int, lut4: Long, ff: Long, mult18: Long, ebr: Long) {
  def capacities: Seq[(String, Long)] = Seq("lut4" -> lut4, "ff" -> ff, "mult18" -> mult18, "ebr" -> ebr)
}

object Boards {
  val defaultPath: Path = Paths.get("boards/catalog.json")
  val xilinxFamilies: Set[String] = Set("xc5v", "xc6s", "xc7", "xcu", "xcup")
  val families: Set[String] = xilinxFamilies + "ecp5"

  def load(path: Path = defaultPath): Map[String, Board] = {
    if (!Files.isRegularFile(path)) throw new InputError(s"board catalog $path not found; run from the project root")
    val j = try ujson.read(Files.readString(path)) catch {
      case e: ujson.ParseException => throw new InputError(s"board catalog $path is not JSON: ${e.getMessage}")
    }
    j("boards").obj.map { case (n, b) =>
      def num(k: String) = b.obj.get(k).map(_.num).getOrElse(throw new InputError(s"board '$n' in $path has no '$k'"))
      def str(k: String) = b.obj.get(k).map(_.str).getOrElse(throw new InputError(s"board '$n' in $path has no '$k'"))
      val fam = b("family").str
      if (!families(fam)) throw new InputError(s"board '$n' in $path: family '$fam' is not one of ${families.toSeq.sorted.mkString(", ")}")
      val source = b.obj.get("source").map(_.str).getOrElse("")
      n -> (if (fam == "ecp5") {
        val e = Ecp5Part(str("device"), str("package"), num("speed_grade").toInt, num("lut4").toLong, num("ff").toLong,
          num("mult18").toLong, num("ebr").toLong)
        Board(n, str("part"), fam, 0, e.ff, 0, 0, num("dram_gbps"), num("clock_mhz"), source, Some(e))
      } else Board(n, str("part"), fam, num("lut").toLong, num("ff").toLong, num("dsp").toLong, num("bram36").toLong,
        num("dram_gbps"), num("clock_mhz"), source))
    }.toMap
  }

  def byName(name: String, path: Path = defaultPath): Board = {
    val all = load(path)
    all.getOrElse(name, throw new InputError(s"unknown BOARD '$name'; the catalog ($path) has ${all.keys.toSeq.sorted.mkString(", ")}"))
  }

  /** The ECP5 boards of the catalog, for the messages that refuse another family. */
  def ecp5Names(path: Path = defaultPath): Seq[String] = load(path).collect { case (n, b) if b.ecp5.isDefined => n }.toSeq.sorted

  /** `board` if it is a Xilinx one: `what` (make area, area-fp, max-tus) synthesizes with synth_xilinx and counts
    * Xilinx cells; an ECP5 board is routed by make timing instead, which reports its LUT4 / FF / MULT18 / EBR.
    */
  def requireXilinx(board: Board, what: String): Board = {
    if (board.ecp5.isDefined) throw new InputError(s"$what synthesizes for Xilinx families (synth_xilinx); BOARD=${board.name} " +
      s"is an ECP5 part: use make timing BOARD=${board.name} (synth_ecp5 + nextpnr: LUT4, FF, MULT18X18D, EBR and the routed clock)")
    board
  }
}
