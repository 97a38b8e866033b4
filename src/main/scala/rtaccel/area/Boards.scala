package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import rtaccel.io.InputError

/** An FPGA board of the catalog (boards/catalog.json): capacities, the Yosys family, memory and clock. */
final case class Board(name: String, part: String, family: String, lut: Long, ff: Long, dsp: Long, bram36: Long,
                       dramGbps: Double, clockMhz: Double, source: String) {
  /** Resources in the order a verdict checks them. */
  def capacities: Seq[(String, Long)] = Seq("lut" -> lut, "ff" -> ff, "dsp" -> dsp, "bram36" -> bram36)
}

object Boards {
  val defaultPath: Path = Paths.get("boards/catalog.json")
  val families: Set[String] = Set("xc5v", "xc6s", "xc7", "xcu", "xcup")

  def load(path: Path = defaultPath): Map[String, Board] = {
    if (!Files.isRegularFile(path)) throw new InputError(s"board catalog $path not found; run from the project root")
    val j = try ujson.read(Files.readString(path)) catch {
      case e: ujson.ParseException => throw new InputError(s"board catalog $path is not JSON: ${e.getMessage}")
    }
    j("boards").obj.map { case (n, b) =>
      def num(k: String) = b.obj.get(k).map(_.num).getOrElse(throw new InputError(s"board '$n' in $path has no '$k'"))
      val fam = b("family").str
      if (!families(fam)) throw new InputError(s"board '$n' in $path: family '$fam' is not one of ${families.toSeq.sorted.mkString(", ")}")
      n -> Board(n, b("part").str, fam, num("lut").toLong, num("ff").toLong, num("dsp").toLong, num("bram36").toLong,
        num("dram_gbps"), num("clock_mhz"), b.obj.get("source").map(_.str).getOrElse(""))
    }.toMap
  }

  def byName(name: String, path: Path = defaultPath): Board = {
    val all = load(path)
    all.getOrElse(name, throw new InputError(s"unknown BOARD '$name'; the catalog ($path) has ${all.keys.toSeq.sorted.mkString(", ")}"))
  }
}
