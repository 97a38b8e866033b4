package rtaccel.area

import java.nio.file.{Files, Path}
import java.security.MessageDigest
import rtaccel.config.PlatformParams
import rtaccel.io.InputError

/** One Yosys synthesis of a configuration's Verilog (or of one module of it), cached per circuit: the hash of
  * the emitted Verilog, the Yosys version, the family and the top names a folder of `cacheRoot` holding
  * Yosys' statistics, so a rerun of the same circuit answers at once.
  */
final case class Synthesized(top: String, mods: Map[String, Map[String, Long]], per: Map[String, Resources],
                             instances: Map[String, Long], unknown: Set[String], cached: Boolean, cacheDir: Path, yosysVersion: String) {
  def total: Resources = per(top)
}

object Synthesis {
  /** Thrown instead of synthesizing when only cached results are wanted. */
  final class NotCached(what: String) extends Exception(what)

  def run(p: PlatformParams, family: String, top: String, rtlDir: Path, cacheRoot: Path, log: String => Unit,
          cachedOnly: Boolean = false): Synthesized = {
    val files = rtaccel.cli.EmitVerilog.emit(p, rtlDir).filter(_.toString.endsWith(".sv"))
    val modulesInRtl = files.map(_.getFileName.toString.stripSuffix(".sv")).toSet
    if (!modulesInRtl(top))
      throw new InputError(s"UNIT=$top is not a module of config '${p.name}'; choose one of ${modulesInRtl.toSeq.sorted.mkString(", ")}")
    val version = Yosys.version()
    val cache = cacheRoot.resolve(hash(files, s"$version $family $top"))
    val stat = cache.resolve("stat.json")
    val cached = Files.isRegularFile(stat)
    if (!cached && cachedOnly) throw new NotCached(s"$top of '${p.name}' for $family")
    if (!cached) {
      Files.createDirectories(cache)
      log(s"synthesizing $top of '${p.name}' for $family with Yosys $version (minutes for the whole platform)")
      val tmp = cache.resolve("stat.json.tmp")
      Yosys.synthesize(files, top, family, cache.resolve("yosys.log"), tmp, line => log(line.take(120)))
      Files.move(tmp, stat)
    } else log(s"cached synthesis $cache")
    val unknown = scala.collection.mutable.Set[String]()
    val mods = Yosys.modules(stat)
    val per = Yosys.rollUp(mods, unknown)
    if (!per.contains(top)) throw new InputError(s"Yosys reported no module $top (see ${cache.resolve("yosys.log")})")
    Synthesized(top, mods, per, countInstances(mods, top), unknown.toSet, cached, cache, version)
  }

  /** How many times each module is instantiated in the design under `top` (top itself once). */
  def countInstances(mods: Map[String, Map[String, Long]], top: String): Map[String, Long] = {
    val n = scala.collection.mutable.Map[String, Long]().withDefaultValue(0L)
    def walk(m: String, k: Long): Unit = { n(m) += k; mods.getOrElse(m, Map.empty).foreach { case (t, c) => if (mods.contains(t)) walk(t, k * c) } }
    walk(top, 1)
    n.toMap
  }

  private def hash(files: Seq[Path], extra: String): String = {
    val md = MessageDigest.getInstance("SHA-256")
    for (f <- files.sortBy(_.getFileName.toString)) { md.update(f.getFileName.toString.getBytes); md.update(Files.readAllBytes(f)) }
    md.update(extra.getBytes)
    md.digest().take(12).map("%02x".format(_)).mkString
  }
}
