package rtaccel.area

import java.nio.file.Path
import scala.collection.mutable

/** The timing proxy: the deepest combinational path of each module, in LUT levels, from the synthesized netlist
  * (Yosys `write_json`, Xilinx or ECP5 cells).
  *
  * What counts: a LUT is a level; a carry or wide-mux cell passes a path on without one (Xilinx CARRY4/CARRY8
  * and MUXF7/MUXF8 sit behind their LUTs in the same slice; an ECP5 CCU2C is one level for the LUTs inside it and
  * none along its carry chain), which makes long adders look faster than they are (docs/area.md). Flip-flops,
  * block RAM and registered DSP ports start and end paths. Three kinds of path that routed timing showed the
  * first proxy missed (docs/timing.md) are counted:
  *  - a DSP block's multiplier is `dspLevels` levels of its family's rule (boards/timing.json `dsp_levels`) and its
  *    post-adder one more, which a cascade from the block before it passes through; the block's own registers
  *    (A/B, M, P; ECP5's input, pipeline and output registers) cut the path where they are, and Yosys' inferred
  *    blocks mostly have none;
  *  - an asynchronous LUT-RAM read (the address in, the data out, as a LUT) is a level, and so is a shift register
  *    LUT's address-to-output path; their writes end a path;
  *  - paths through submodule ports: each module is summarised per port (the deepest path from its registers to
  *    an output, from an input to its registers, and from an input through to an output) and its parent's paths
  *    go through those summaries, so a path that crosses module boundaries is counted in the module where it
  *    turns (the deepest common ancestor of its ends) with the parts that lie inside the submodules.
  * Yosys' `ltp` counts every cell on its path in one module alone; its figure is kept beside ours (`ltp_cells`).
  */
object Levels {
  /** Bump when the rules above change: it is part of make area's cache key (the netlist is not kept).
    * 3: the deepest path's named nets are kept (`Result.paths`).
    */
  val version = 3

  /** Per module: the deepest path's LUT levels, and the named nets it passes, start to end ("inst.port" where it
    * crosses a submodule; Yosys' own `$`-names left out), so that a deep module says where to cut.
    */
  final case class Result(levels: Map[String, Int], paths: Map[String, Seq[String]])

  private val NegInf = Int.MinValue / 4

  /** LUT levels of the deepest path of every (non-blackbox) module in a `write_json` netlist; `dspLevels` is
    * the family's unregistered DSP multiplier in levels (FamilyTiming.dspLevels).
    */
  def ofNetlist(netlist: Path, dspLevels: Int): Result = {
    // read as a stream of bytes: the whole platform's netlist is hundreds of MB
    val j = ujson.read(ujson.Readable.fromPath(netlist))
    ofModules(j("modules").obj.iterator.map { case (n, m) => Yosys.clean(n) -> m }.toMap, dspLevels)
  }

  private[area] def ofModules(mods: Map[String, ujson.Value], dspLevels: Int): Result = {
    val own = mods.collect { case (n, m) if !isBox(m) => n -> m }
    val summaries = mutable.Map[String, Summary]()
    val deepest = mutable.Map[String, Int]()
    val paths = mutable.Map[String, Seq[String]]()
    // children first (the hierarchy is a DAG; firtool emits no recursion)
    def visit(n: String, path: Set[String]): Unit = if (!summaries.contains(n) && !path(n)) {
      val m = own(n)
      for (c <- cells(m); t = Yosys.clean(c("type").str) if own.contains(t)) visit(t, path + n)
      val g = Graph.of(m, own.keySet, summaries, dspLevels)
      val (d, trail) = g.deepestPath
      deepest(n) = d; paths(n) = trail
      summaries(n) = g.summary
    }
    own.keys.foreach(visit(_, Set.empty))
    Result(deepest.toMap, paths.toMap)
  }

  private def isBox(m: ujson.Value): Boolean =
    m.obj.get("attributes").exists(a => a.obj.contains("blackbox") || a.obj.contains("whitebox"))
  private def cells(m: ujson.Value): Iterable[ujson.Value] = m.obj.get("cells").map(_.obj.values).getOrElse(Nil)

  /** A module seen from its parent, per port: the deepest path from its own registers to output `p` (`src`),
    * from input `q` to its registers (`sink`), and from input `q` through to output `p` (`thru`).
    */
  final case class Summary(src: Map[String, Int], sink: Map[String, Int], thru: Map[(String, String), Int])

  /** What a cell is on a path, by family library. */
  private sealed trait Role
  private case class Comb(weight: Int) extends Role // every input to every output
  private case object Cut extends Role // a register (or a cell we know nothing of): starts and ends paths
  /** Outputs computed from `reads` ports only (weight `weight`); other inputs end a path (`sinkWeight`). */
  private case class Reads(reads: String => Boolean, weight: Int, sinkWeight: Int) extends Role
  /** A DSP block: a multiplier stage (registered or not) then a post-adder that a cascade input joins. */
  private case class Dsp(inReg: Boolean, midReg: Boolean, outReg: Boolean, cascade: String => Boolean, levels: Int) extends Role
  /** An ECP5 CCU2C: its LUTs (one level) then the carry chain, which CIN joins. */
  private case object Ccu extends Role

  private def param(c: ujson.Value, k: String): Option[String] = c.obj.get("parameters").flatMap(_.obj.get(k)).map(_.str)
  private def regOn(c: ujson.Value, k: String): Boolean = param(c, k).exists(v => v.exists(_ != '0') && v != "NONE")
  private val lut = "LUT[1-6]".r
  private val xilinxCut = Seq("FD", "LD", "RAMB", "FIFO", "DCM", "BUFG", "IBUF", "OBUF", "MMCM", "PLL")
  private val lutRam = "RAM(16|32|64|128|256|512)(X|M).*".r
  private val readAddr: String => Boolean = p => p.startsWith("ADDR") || p.startsWith("DPRA") || p.matches("A[0-9]*") || p == "RAD" || p.startsWith("RAD")
  private def role(t: String, c: ujson.Value, dspLevels: Int): Role = t match {
    case lut(_*) | "LUT4" | "LUT5" | "LUT6_2" => Comb(1)
    case "CARRY4" | "CARRY8" | "MUXF7" | "MUXF8" | "MUXF9" | "PFUMX" | "L6MUX21" | "INV" | "VCC" | "GND" => Comb(0)
    case "CCU2C" => Ccu
    case lutRam(_*) => Reads(readAddr, 1, 0)
    case "TRELLIS_DPR16X4" => Reads(readAddr, 1, 0)
    case s if s.startsWith("SRL") => Reads(p => p.startsWith("A"), 1, 0)
    case s if s.startsWith("DSP48") =>
      Dsp(regOn(c, "AREG") && regOn(c, "BREG"), regOn(c, "MREG"), regOn(c, "PREG"), p => p.endsWith("CIN") && p != "CARRYIN", dspLevels)
    case "MULT18X18D" =>
      Dsp(regOn(c, "REG_INPUTA_CLK") && regOn(c, "REG_INPUTB_CLK"), regOn(c, "REG_PIPELINE_CLK"), regOn(c, "REG_OUTPUT_CLK"), _ => false, dspLevels)
    case "ALU54B" | "ALU24B" => Reads(_ => true, 1, 0)
    case _ => Cut // flip-flops, block RAM, I/O, and any type we know nothing of
  }

  /** The combinational graph of one module: nodes with a weight and a base (the value of a path that starts in
    * them), each reading nodes with an extra weight per edge; bits name the nets.
    */
  private final class Graph {
    val weight = mutable.ArrayBuffer[Int](); val base = mutable.ArrayBuffer[Int]()
    val readsBits = mutable.ArrayBuffer[mutable.ArrayBuffer[(Long, Int)]]() // (net bit, extra)
    val readsNodes = mutable.ArrayBuffer[mutable.ArrayBuffer[(Int, Int)]]() // (node, extra)
    val driver = mutable.HashMap[Long, Int]()
    val label = mutable.ArrayBuffer[String]() // a named net the node drives ("" if none), for the path report
    var bitName: Long => String = _ => ""
    var inPorts: Seq[(String, Array[Long])] = Nil
    var outPorts: Seq[(String, Array[Long])] = Nil

    /** A node of weight `w`; `b` is the value of a path that starts in it (a submodule's output, a DSP block's
      * registered inputs), none for a cell whose paths start at the nets it reads.
      */
    def node(w: Int, b: Int = NegInf): Int = {
      weight += w; base += b; readsBits += mutable.ArrayBuffer(); readsNodes += mutable.ArrayBuffer(); label += ""; weight.length - 1
    }

    private lazy val deps: Array[Array[(Int, Int)]] = weight.indices.map { c =>
      (readsBits(c).flatMap { case (b, x) => driver.get(b).map(_ -> x) } ++ readsNodes(c)).distinct.toArray
    }.toArray
    /** Input-port bits each node reads directly (not through another node), with the edge's extra weight. */
    private lazy val portReads: Array[Array[(Long, Int)]] = readsBits.map(_.filter { case (b, _) => !driver.contains(b) }.toArray).toArray
    private lazy val order: Array[Int] = topo()

    /** Nodes in an order where each comes after the nodes it reads (iterative: chains are tens of thousands long;
      * a combinational loop, never in firtool output, is broken where it is met).
      */
    private def topo(): Array[Int] = {
      val state = new Array[Byte](weight.length) // 0 new, 1 open, 2 done
      val out = mutable.ArrayBuffer[Int](); val stack = mutable.ArrayBuffer[Int]()
      for (r <- weight.indices if state(r) == 0) {
        stack += r
        while (stack.nonEmpty) {
          val c = stack.last
          if (state(c) == 2) stack.remove(stack.length - 1)
          else if (state(c) == 0) { state(c) = 1; deps(c).foreach { case (d, _) => if (state(d) == 0) stack += d } }
          else { state(c) = 2; out += c; stack.remove(stack.length - 1) }
        }
      }
      out.toArray
    }

    /** Path values: v(c) = weight(c) + max(base, input bits' starts, max over reads (v(d) + extra)). `from`, when
      * given, records what each value came from: a node (>= 0), an input bit (-2 - bit) or the node's base (-1).
      */
    private def eval(useBase: Boolean, start: Long => Int, from: Array[Long] = null): Array[Int] = {
      val v = Array.fill(weight.length)(NegInf)
      for (c <- order) {
        var best = if (useBase) base(c) else NegInf
        var arg = -1L
        for ((b, x) <- portReads(c)) { val s = start(b); if (s > NegInf && s + x > best) { best = s + x; arg = -2 - b } }
        for ((d, x) <- deps(c)) if (v(d) > NegInf && v(d) + x > best) { best = v(d) + x; arg = d }
        v(c) = if (best > NegInf) best + weight(c) else NegInf
        if (from != null) from(c) = arg
      }
      v
    }

    /** The deepest path in this module (from its registers, its input ports and its submodules' outputs) and the
      * named nets along it, start first.
      */
    def deepestPath: (Int, Seq[String]) = {
      val from = new Array[Long](weight.length)
      val v = eval(useBase = true, _ => 0, from)
      if (v.isEmpty || v.max <= 0) (0, Nil)
      else {
        var c = v.indices.maxBy(v(_))
        val names = mutable.ArrayBuffer[String](label(c))
        while (from(c) >= 0) { c = from(c).toInt; names += label(c) }
        if (from(c) <= -2) names += bitName(-2 - from(c))
        (v.max, names.reverseIterator.filter(_.nonEmpty).foldLeft(Vector.empty[String])((a, n) => if (a.lastOption.contains(n)) a else a :+ n))
      }
    }

    def summary: Summary = {
      val inBits = inPorts.flatMap(_._2).toSet
      def atOut(v: Array[Int], bits: Array[Long], start: Long => Int) =
        bits.iterator.map(b => driver.get(b).map(v(_)).getOrElse(start(b))).maxOption.getOrElse(NegInf)
      val fromRegs: Long => Int = b => if (inBits(b)) NegInf else 0
      val vr = eval(useBase = true, fromRegs)
      val src = outPorts.map { case (p, bits) => p -> (atOut(vr, bits, fromRegs) max 0) }.toMap
      val sink = mutable.Map[String, Int](); val thru = mutable.Map[(String, String), Int]()
      for ((q, qBits) <- inPorts) {
        val mine = qBits.toSet
        val from: Long => Int = b => if (mine(b)) 0 else NegInf
        val vq = eval(useBase = false, from)
        sink(q) = (vq :+ 0).max
        for ((p, bits) <- outPorts) { val t = atOut(vq, bits, from); if (t > NegInf) thru((q, p)) = t }
      }
      Summary(src, sink.toMap, thru.toMap)
    }
  }

  private object Graph {
    def of(m: ujson.Value, own: Set[String], summaries: collection.Map[String, Summary], dspLevels: Int): Graph = {
      val g = new Graph
      def bitsOf(v: ujson.Value): Array[Long] = v.arr.collect { case ujson.Num(n) => n.toLong }.toArray
      val ports = m.obj.get("ports").map(_.obj.toSeq).getOrElse(Nil)
      g.inPorts = ports.collect { case (p, d) if d("direction").str == "input" => p -> bitsOf(d("bits")) }
      g.outPorts = ports.collect { case (p, d) if d("direction").str == "output" => p -> bitsOf(d("bits")) }
      // a bit's name: a net the source named (Yosys' own names start with `$`), with the bit's index in it
      val names = mutable.HashMap[Long, String]()
      for ((n, d) <- m.obj.get("netnames").map(_.obj.toSeq).getOrElse(Nil) if !n.startsWith("$") && !d.obj.get("hide_name").exists(_.num != 0)) {
        val bits = bitsOf(d("bits"))
        for ((b, i) <- bits.zipWithIndex if !names.contains(b)) names(b) = Yosys.clean(n) + (if (bits.length > 1) s"[$i]" else "")
      }
      g.bitName = b => names.getOrElse(b, "")
      for ((cellName, c) <- m.obj.get("cells").map(_.obj.toSeq).getOrElse(Nil)) {
        val t = Yosys.clean(c("type").str)
        val conns = c("connections").obj.toSeq.map { case (p, b) => p -> bitsOf(b) }
        val dirs = c.obj.get("port_directions").map(_.obj).getOrElse(Map.empty[String, ujson.Value])
        def dirOf(p: String) = dirs.get(p).map(_.str).getOrElse("")
        val ins = conns.filter(x => dirOf(x._1) == "input"); val outs = conns.filter(x => dirOf(x._1) == "output")
        def drive(n: Int, ports: Seq[(String, Array[Long])]): Unit = {
          ports.foreach(_._2.foreach(g.driver(_) = n))
          if (g.label(n).isEmpty) g.label(n) = ports.iterator.flatMap(_._2).map(g.bitName).find(_.nonEmpty).getOrElse("")
        }
        def read(n: Int, ports: Seq[(String, Array[Long])], extra: Int = 0): Unit = ports.foreach(_._2.foreach(b => g.readsBits(n) += (b -> extra)))
        if (own(t)) summaries.get(t) match {
          case Some(s) =>
            // the submodule: its inputs end paths `sink` deep; each output starts `src` deep and continues its inputs' paths
            for ((q, bits) <- ins) { val n = g.node(0); read(n, Seq(q -> bits), s.sink.getOrElse(q, 0)); g.label(n) = s"${Yosys.clean(cellName)}.$q" }
            for ((p, bits) <- outs) {
              val n = g.node(0, s.src.getOrElse(p, 0))
              for ((q, qb) <- ins; x <- s.thru.get((q, p))) read(n, Seq(q -> qb), x)
              g.label(n) = s"${Yosys.clean(cellName)}.$p"
              drive(n, Seq(p -> bits))
            }
          case None => () // a submodule on a recursion path (none in firtool output): a cut
        } else if (dirs.isEmpty) () // a cell Yosys knows no directions of: a cut
        else role(t, c, dspLevels) match {
          case Comb(w) => val n = g.node(w); read(n, ins); drive(n, outs)
          case Cut => ()
          case Reads(r, w, sw) =>
            val n = g.node(w); read(n, ins.filter(x => r(x._1))); drive(n, outs)
            val s = g.node(sw); read(s, ins.filterNot(x => r(x._1)))
          case Ccu =>
            val l = g.node(1); read(l, ins.filterNot(_._1 == "CIN"))
            val ch = g.node(0); read(ch, ins.filter(_._1 == "CIN")); g.readsNodes(ch) += (l -> 0); drive(ch, outs)
          case Dsp(inReg, midReg, outReg, cascade, lv) =>
            // the multiplier: from registered inputs it starts `lv` deep, else it continues its inputs' paths; a
            // register behind it (M) ends it there, and the post-adder (joined by a cascade) starts from that register
            val mul = if (inReg) g.node(0, lv) else { val n = g.node(lv); read(n, ins.filterNot(x => cascade(x._1))); n }
            val post = g.node(1, if (midReg) 1 else NegInf)
            if (!midReg) g.readsNodes(post) += (mul -> 0)
            read(post, ins.filter(x => cascade(x._1)))
            if (!outReg) drive(post, outs) // else the post-adder ends at the P register
        }
      }
      g
    }
  }

  /** Longest weighted path through a DAG of cells (deps = the cells each one reads): the same walk as a module's
    * graph, for a test that gives weights alone.
    */
  private[area] def longest(weight: Array[Int], deps: Array[Array[Int]]): Int = {
    val g = new Graph
    weight.foreach(w => g.node(w, 0))
    for ((ds, c) <- deps.zipWithIndex; d <- ds) g.readsNodes(c) += (d -> 0)
    g.deepestPath._1
  }

  private val ltpHead = """Longest topological path in (\S+) \(length=(\d+)\):""".r.unanchored

  /** Cells on the longest path per module, from the text `ltp` prints ("Longest topological path in M (length=N):"). */
  def parseLtp(text: String): Map[String, Int] =
    text.linesIterator.collect { case ltpHead(m, n) => Yosys.clean(m) -> n.toInt }.toMap
}
