package rtaccel.area

import java.nio.file.{Files, Path}
import scala.sys.process._
import rtaccel.io.InputError

/** Yosys synthesis of emitted Verilog for a Xilinx family, kept hierarchical so that every unit is counted
  * on its own; the design's totals are the roll-up of the same hierarchy (Resources per module x instance
  * counts), so units and totals agree by construction. Flattening would optimise across unit boundaries
  * (docs/area.md says by how much); the hierarchy is what a per-unit question needs.
  */
object Yosys {
  def version(): String = {
    val out = try Seq("yosys", "-V").!!.trim catch {
      case _: Exception => throw new InputError("yosys not found; install it (make area installs it from apt)")
    }
    out.split("\\s+").lift(1).getOrElse(out)
  }

  /** Names of the files a synthesis leaves in its folder. */
  val statFile = "stat.json"
  val ltpFile = "ltp.txt"
  val netlistFile = "netlist.json"
  val logFile = "yosys.log"

  /** Cell types where a combinational path starts and ends (flip-flops, latches, block RAM, DSP slices, LUT RAM
    * and shift registers, whose reads we take as registered); `Levels` cuts at the same types.
    */
  val pathCuts: Seq[String] = Seq("FD*", "LD*", "RAMB*", "DSP48*", "RAM16X*", "RAM32X*", "RAM64X*", "RAM128X*",
    "RAM256X*", "RAM512X*", "RAM32M*", "RAM64M*", "SRL*")

  /** Everything after read_verilog, run in the result folder; part of the cache key, so a changed recipe never
    * reuses an old result. ltp sees each module alone: an instance of a submodule is one cell of its parent and
    * cut like a flip-flop (its own depth is its module's entry).
    */
  def recipe(family: String, top: String, modules: Seq[String], memories: Seq[String] = Nil): String = {
    val cuts = (pathCuts ++ modules.sorted.distinct).map("t:" + _).mkString(" ")
    inlineMemories(top, memories) + s"synth_xilinx -family $family -top $top; tee -q -o $statFile stat -json; " +
      s"tee -q -o $ltpFile ltp -noff $cuts %% %n; write_json $netlistFile"
  }

  /** firtool emits each memory as a module with a clock input per port. Kept apart, its ports' clocks are different
    * wires to Yosys, so a read port's address register cannot join a write port of "another" clock (memory_dff:
    * "address FF clock is not compatible with write clock"): the read stays asynchronous and the memory can only be
    * LUT RAM. A 8192 x 257 cache data array (RESP_ORDER=tagged, NODE_BANKS: a read and a write port) then took
    * 15k LUTs and 11k LUT RAM instead of 58 RAMB36. These modules are inlined into their parents (every other module
    * keeps its hierarchy), where both ports' clocks are the platform's one clock, as in a flat synthesis.
    */
  private def inlineMemories(top: String, memories: Seq[String]): String =
    if (memories.isEmpty) "" else s"hierarchy -top $top; setattr -mod -set keep_hierarchy 1; " +
      s"setattr -mod -unset keep_hierarchy ${memories.sorted.distinct.mkString(" ")}; flatten; setattr -mod -unset keep_hierarchy; "

  // a port clock the module clocks registers on (an asynchronous read port's clock is unused)
  private val portClock = """posedge\s+((?:R|W|RW)\d+_clk)\b""".r
  /** The modules among `files` that firtool emitted for memories clocked by more than one port clock: a synchronous
    * read beside a write (see inlineMemories). */
  def multiClockMemories(files: Seq[Path]): Seq[String] = files.filter(_.toString.endsWith(".sv")).flatMap { f =>
    val clocks = portClock.findAllMatchIn(Files.readString(f)).map(_.group(1)).toSet
    if (clocks.size > 1) Some(f.getFileName.toString.stripSuffix(".sv")) else None
  }

  /** Runs `read_verilog` on `files` and then `recipe` in `dir` (stat, ltp and netlist files land there); Yosys'
    * log goes to yosys.log, and every pass it starts is reported to `progress` (the whole platform takes minutes).
    */
  def synthesize(files: Seq[Path], recipe: String, dir: Path, what: String, progress: String => Unit): Unit = {
    val script = s"read_verilog -sv ${files.map(_.toAbsolutePath.toString).mkString(" ")}; $recipe"
    val log = dir.toAbsolutePath.resolve(logFile)
    // warnings stay in the log; errors are shown as they come; every 30 s the pass Yosys is in
    // (-q keeps the terminal otherwise quiet)
    val code = Tools.run(Seq("yosys", "-q", "-l", log.toString, "-p", script), dir, progress, () => currentPass(log))
    if (code != 0 || !Files.isRegularFile(dir.resolve(statFile)) || !Files.isRegularFile(dir.resolve(netlistFile))) {
      val tail = if (Files.exists(log)) Files.readAllLines(log).toArray.takeRight(5).mkString(" | ") else ""
      throw new InputError(s"yosys failed (status $code) on $what: $tail (log: $log)")
    }
  }

  /** The last numbered pass line of a Yosys log ("25.41. Executing ABC pass ..."), for progress reports. */
  private[area] def currentPass(log: Path): String =
    Tools.lastLine(log, _.matches("""\d+(\.\d+)*\. .*"""), if (Files.exists(log)) "running" else "starting")

  /** Cell counts by type of every module in a `stat -json` file (module names without Yosys' escape). */
  def modules(statJson: Path): Map[String, Map[String, Long]] = {
    // Yosys 0.23 prints the hierarchy's "<module> <count>" lines into the JSON of `stat -json` when the design
    // has submodules; they are not JSON and carry nothing the modules section lacks
    val text = Files.readAllLines(statJson).toArray(Array[String]()).filterNot(_.trim.matches("""[^"{}\[\]:,]+\s+\d+""")).mkString("\n")
    val j = try ujson.read(text) catch {
      case e: ujson.ParseException => throw new InputError(s"$statJson: unreadable Yosys statistics (${e.getMessage}); delete it to synthesize again")
    }
    j("modules").obj.map { case (m, v) =>
      clean(m) -> v.obj.get("num_cells_by_type").map(_.obj.map { case (t, n) => clean(t) -> n.num.toLong }.toMap).getOrElse(Map.empty)
    }.toMap
  }

  private[area] def clean(name: String): String = name.stripPrefix("\\")

  /** Resources of `top` and of every module it instantiates, rolled up through the hierarchy. */
  def rollUp(mods: Map[String, Map[String, Long]], unknown: scala.collection.mutable.Set[String]): Map[String, Resources] = {
    val memo = scala.collection.mutable.Map[String, Resources]()
    def total(m: String): Resources = memo.getOrElseUpdate(m, {
      val cells = mods.getOrElse(m, Map.empty)
      val (subs, prims) = cells.partition { case (t, _) => mods.contains(t) }
      subs.foldLeft(Resources.of(prims, unknown)) { case (r, (s, n)) => r + total(s) * n }
    })
    mods.keys.foreach(total)
    memo.toMap
  }
}
