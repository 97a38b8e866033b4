package rtaccel.area

import java.nio.file.Path
import scala.collection.mutable

/** The timing proxy: the deepest combinational path of each module, in LUT levels, from the synthesized
  * netlist (Yosys `write_json`). Only LUT cells count: a MUXF7/MUXF8 sits behind its LUTs in the same slice
  * and a CARRY4/CARRY8 link is a fraction of a LUT plus its net, so both pass a path on without a level
  * (which makes long adders look faster than they are; docs/area.md). A path starts and ends at module ports,
  * at the `Yosys.pathCuts` cell types (flip-flops, block and LUT RAM, DSP slices) and at submodule instances,
  * each of which is measured in its own module. Yosys' `ltp` counts every cell on its path instead; its
  * figure is kept beside ours (`ltp_cells`) as a cross-check.
  */
object Levels {
  private val lut = "LUT[1-6]".r
  private val cut = Yosys.pathCuts.map(p => java.util.regex.Pattern.quote(p.stripSuffix("*")) + ".*").mkString("(", "|", ")").r

  /** LUT levels of the deepest path of every (non-blackbox) module in a `write_json` netlist. */
  def ofNetlist(netlist: Path): Map[String, Int] = {
    // read as a stream of bytes: the whole platform's netlist is hundreds of MB
    val j = ujson.read(ujson.Readable.fromPath(netlist))
    val mods = j("modules").obj
    val own = mods.collect { case (n, m) if !isBox(m) => Yosys.clean(n) }.toSet
    mods.collect { case (n, m) if !isBox(m) => Yosys.clean(n) -> deepest(m, own) }.toMap
  }

  private def isBox(m: ujson.Value): Boolean =
    m.obj.get("attributes").exists(a => a.obj.contains("blackbox") || a.obj.contains("whitebox"))

  private def deepest(m: ujson.Value, submodules: Set[String]): Int = {
    // combinational cells: LUT weight and the nets they read; a net's driver is the cell that writes it
    val weight = mutable.ArrayBuffer[Int](); val reads = mutable.ArrayBuffer[Array[Long]]()
    val driver = mutable.HashMap[Long, Int]()
    for ((_, c) <- m.obj.get("cells").map(_.obj).getOrElse(Map.empty)) {
      val t = Yosys.clean(c("type").str)
      val dirs = c.obj.get("port_directions").map(_.obj).getOrElse(Map.empty[String, ujson.Value])
      // a cell type Yosys knows no directions of is treated like a submodule: a cut
      if (!submodules(t) && !cut.matches(t) && dirs.nonEmpty) {
        val idx = weight.length
        def bits(dir: String) = c("connections").obj.collect { case (p, b) if dirs.get(p).exists(_.str == dir) =>
          b.arr.collect { case ujson.Num(n) => n.toLong } }.flatten.toArray
        weight += (if (lut.matches(t)) 1 else 0)
        reads += bits("input")
        bits("output").foreach(driver(_) = idx)
      }
    }
    val deps = reads.map(_.flatMap(driver.get).distinct)
    longest(weight.toArray, deps.toArray)
  }

  /** Longest weighted path through a DAG of cells (deps = the cells each one reads), without recursion: a
    * module has tens of thousands of cells in a chain. A combinational loop (none in firtool output) is broken
    * where it is met.
    */
  private[area] def longest(weight: Array[Int], deps: Array[Array[Int]]): Int = {
    val memo = Array.fill(weight.length)(-1)
    val open = new Array[Boolean](weight.length)
    val stack = mutable.ArrayBuffer[Int]()
    for (root <- weight.indices if memo(root) < 0) {
      stack += root
      while (stack.nonEmpty) {
        val c = stack.last
        if (memo(c) >= 0) stack.remove(stack.length - 1)
        else if (!open(c)) { open(c) = true; deps(c).foreach(d => if (memo(d) < 0 && !open(d)) stack += d) }
        else {
          memo(c) = weight(c) + deps(c).iterator.map(d => memo(d) max 0).maxOption.getOrElse(0)
          open(c) = false; stack.remove(stack.length - 1)
        }
      }
    }
    memo.maxOption.getOrElse(0)
  }

  private val ltpHead = """Longest topological path in (\S+) \(length=(\d+)\):""".r.unanchored

  /** Cells on the longest path per module, from the text `ltp` prints ("Longest topological path in M (length=N):"). */
  def parseLtp(text: String): Map[String, Int] =
    text.linesIterator.collect { case ltpHead(m, n) => Yosys.clean(m) -> n.toInt }.toMap
}
