package rtaccel.area

import java.nio.file.{Files, Path, StandardCopyOption}
import scala.collection.mutable

/** One cached Yosys synthesis of a circuit: resources rolled up per module, instance counts under the top and
  * the timing proxy per module. `levels` and `ltpCells` are per instance of a module (its own logic between
  * its cuts, see [[Levels]]).
  */
final case class Synthesis(top: String, family: String, version: String, cache: Path, cached: Boolean,
                           resources: Map[String, Resources], instances: Map[String, Long],
                           levels: Map[String, Int], ltpCells: Map[String, Int], unknown: Set[String],
                           mods: Map[String, Map[String, Long]], paths: Map[String, Seq[String]] = Map.empty) {
  def total: Resources = resources(top)
  /** The module under the top with the deepest path (ties: the name first in order) and its LUT levels. */
  def deepest: (String, Int) = instances.keys.toSeq.sorted.map(m => m -> levels.getOrElse(m, 0)).maxBy(_._2)
}

object Synthesis {
  /** Synthesizes `files` with `top` for `family` unless `cacheRoot` holds the result already. The key hashes the
    * Verilog, the Yosys version, the family, the top and the recipe, so a changed script never reuses old results.
    */
  /** Thrown instead of synthesizing when only cached results are wanted (make cost-model CACHED_ONLY=1). */
  final class NotCached(what: String) extends Exception(what)

  /** The board top of `p` (or its module `top`), emitted into `rtlDir` and synthesized (or found in the cache). */
  def of(p: rtaccel.config.PlatformParams, family: String, top: String, rtlDir: Path, cacheRoot: Path, say: String => Unit,
         cachedOnly: Boolean = false): Synthesis = {
    val files = rtaccel.cli.EmitVerilog.emit(p, rtlDir).filter(_.toString.endsWith(".sv"))
    val modulesInRtl = files.map(_.getFileName.toString.stripSuffix(".sv")).toSet
    if (!modulesInRtl(top))
      throw new rtaccel.io.InputError(s"UNIT=$top is not a module of config '${p.name}'; choose one of ${modulesInRtl.toSeq.sorted.mkString(", ")}")
    run(files, top, family, cacheRoot, s"$top of '${p.name}'", say, rtaccel.cli.Cli.version, cachedOnly)
  }

  /** The files of `top` and of every module under it: firtool writes one file per module, named after it, and a
    * module's file names each module it instantiates. Yosys keeps only the top's hierarchy, so reading the
    * other modules (a whole platform's, when the top is one unit of it) only costs time: a 141-LUT unit of 'small'
    * took 10 s in YoWASP's Yosys reading every module. Cache keys still hash every emitted file.
    */
  def hierarchy(files: Seq[Path], top: String): Seq[Path] = {
    val byName = files.map(f => f.getFileName.toString.stripSuffix(".sv") -> f).toMap
    val word = "[A-Za-z_][A-Za-z0-9_$]*".r
    def below(m: String): Set[String] =
      word.findAllIn(Files.readString(byName(m))).filter(w => w != m && byName.contains(w)).toSet
    @annotation.tailrec def close(todo: List[String], seen: Set[String]): Set[String] = todo match {
      case Nil => seen
      case m :: rest => val n = below(m) -- seen; close(n.toList ++ rest, seen ++ n)
    }
    val keep = close(List(top), Set(top))
    // files that are not modules (firtool's include files, if any) stay
    files.filter(f => keep(f.getFileName.toString.stripSuffix(".sv")) || !f.toString.endsWith(".sv"))
  }

  def run(files: Seq[Path], top: String, family: String, cacheRoot: Path, what: String, say: String => Unit,
          rtaccelVersion: String, cachedOnly: Boolean = false): Synthesis = {
    val version = Yosys.version()
    val recipe = recipeOf(files, top, family)
    val dir = cacheDirOf(files, top, family, recipe, cacheRoot)
    val stat = dir.resolve(Yosys.statFile)
    val cached = Files.isRegularFile(stat)
    if (!cached && cachedOnly) throw new NotCached(s"$what for $family")
    if (!cached) {
      val work = dir.resolve("work")
      Files.createDirectories(work)
      say(s"synthesizing $what for $family with Yosys $version (minutes for the whole platform)")
      Yosys.synthesize(hierarchy(files, top), recipe, work, what, say)
      val levels = Levels.ofNetlist(work.resolve(Yosys.netlistFile), Timing.forFamily(family).dspLevels)
      Files.writeString(work.resolve(levelsFile), ujson.write(ujson.Obj("about" -> ("LUT levels of the deepest combinational " +
        "path per module (rtaccel.area.Levels)"), "top" -> top, "family" -> family, "yosys_version" -> version,
        "rtaccel" -> rtaccelVersion, "modules" -> ujson.Obj.from(levels.levels.toSeq.sorted.map { case (m, n) => m -> ujson.Num(n) }),
        "paths" -> ujson.Obj.from(levels.paths.toSeq.sortBy(_._1).map { case (m, ns) => m -> ujson.Arr.from(ns.map(ujson.Str(_))) })), indent = 2))
      // the netlist is large and everything it was kept for is in levels.json
      Files.delete(work.resolve(Yosys.netlistFile))
      // stat.json last: its presence is what marks a complete result
      for (f <- Seq(Yosys.ltpFile, levelsFile, Yosys.logFile, Yosys.statFile))
        Files.move(work.resolve(f), dir.resolve(f), StandardCopyOption.REPLACE_EXISTING)
      Files.delete(work)
    } else say(s"cached synthesis $dir")
    val unknown = mutable.Set[String]()
    val mods = Yosys.modules(stat)
    val per = Yosys.rollUp(mods, unknown)
    if (!per.contains(top)) throw new rtaccel.io.InputError(s"Yosys reported no module $top (see ${dir.resolve(Yosys.logFile)})")
    val lj = ujson.read(Files.readString(dir.resolve(levelsFile)))
    val levels = lj("modules").obj.map { case (m, n) => m -> n.num.toInt }.toMap
    val paths = lj.obj.get("paths").fold(Map.empty[String, Seq[String]])(_.obj.map { case (m, a) => m -> a.arr.map(_.str).toSeq }.toMap)
    val ltp = Levels.parseLtp(Files.readString(dir.resolve(Yosys.ltpFile)))
    Synthesis(top, family, version, dir, cached, per, countInstances(mods, top), levels, ltp, unknown.toSet, mods, paths)
  }

  val levelsFile = "levels.json"

  private def modules(files: Seq[Path]): Seq[String] = files.map(_.getFileName.toString.replaceAll("""\.s?v$""", ""))

  /** The folder of the synthesis of `files` with `top` for `family` (the key: see `run`). */
  def cacheDir(files: Seq[Path], top: String, family: String, cacheRoot: Path): Path =
    cacheDirOf(files, top, family, recipeOf(files, top, family), cacheRoot)
  /** The Yosys script for `top` (it reads every memory module of the hierarchy once, to find those it inlines). */
  private def recipeOf(files: Seq[Path], top: String, family: String): String =
    Yosys.recipe(family, top, modules(files), Yosys.multiClockMemories(hierarchy(files, top)))
  private def cacheDirOf(files: Seq[Path], top: String, family: String, recipe: String, cacheRoot: Path): Path =
    // the proxy's rules are part of the key: levels.json is all that is kept of the netlist
    cacheRoot.resolve(hash(files, s"${Yosys.version()} $family $top levels v${Levels.version} dsp ${Timing.forFamily(family).dspLevels}\n" + recipe))

  /** How many times each module is instantiated in the design under `top` (top itself once). */
  def countInstances(mods: Map[String, Map[String, Long]], top: String): Map[String, Long] = {
    val n = mutable.Map[String, Long]().withDefaultValue(0L)
    def walk(m: String, k: Long): Unit = { n(m) += k; mods.getOrElse(m, Map.empty).foreach { case (t, c) => if (mods.contains(t)) walk(t, k * c) } }
    walk(top, 1)
    n.toMap
  }

  /** The cache key of a circuit: its Verilog files (names and bytes) and `extra` (tools, target, recipe). */
  private[area] def hash(files: Seq[Path], extra: String): String = {
    val named = files.sortBy(_.getFileName.toString).iterator.flatMap(f => Iterator(f.getFileName.toString.getBytes("UTF-8"), Files.readAllBytes(f)))
    rtaccel.io.Digest.hexOfAll(12, named ++ Iterator(extra.getBytes("UTF-8")))
  }
}
