package rtaccel.config

import rtaccel.io.InputError

/** The platform knobs, one entry each: the make variable, the flag it becomes, what it does, the values it takes,
  * whether it shapes the circuit, which commands read it and where the cost model is calibrated for it.
  *
  * Everything else reads this table: the entry points' flags (cli.Flags), the first check of a value (`check`, before
  * PlatformParams' requirements, which judge combinations and the scene-fitted widths), the cost model's refusal of
  * an uncalibrated value (area.CostModel), and through the export (`make knobs` writes knobs.json, which a test keeps
  * equal to this table) the Makefile's flags and dse/'s space checks. A value's legality is written here once, as
  * data (a `Domain`), so the Python side interprets the same rule rather than restating it.
  */
object Knobs {
  /** Values a knob takes, case-insensitive for names. Data, not code: the export carries it to dse/. */
  sealed trait Domain {
    def accepts(v: String): Boolean
    /** What the error message says is allowed. */
    def rule: String
    def json: ujson.Value
  }
  /** lo..hi; `pow2`: powers of two only; `zero`: 0 as well (off). */
  final case class Ints(lo: Int, hi: Int, pow2: Boolean = false, zero: Boolean = false) extends Domain {
    def accepts(v: String): Boolean = v.toIntOption.exists(n => (zero && n == 0) ||
      (n >= lo && n <= hi && (!pow2 || Integer.bitCount(n) == 1)))
    def rule: String = (if (zero) "0 or " else "") + (if (pow2) s"a power of two $lo..$hi" else s"an integer $lo..$hi")
    def json: ujson.Value = ujson.Obj("kind" -> "ints", "lo" -> lo, "hi" -> hi, "pow2" -> pow2, "zero" -> zero)
  }
  final case class Names(names: Seq[String]) extends Domain {
    def accepts(v: String): Boolean = names.contains(v.toLowerCase)
    def rule: String = if (names.size == 1) names.head else names.init.mkString(", ") + " or " + names.last
    def json: ujson.Value = ujson.Obj("kind" -> "names", "names" -> names)
  }
  /** A number > 0. */
  case object Positive extends Domain {
    def accepts(v: String): Boolean = v.toDoubleOption.exists(d => d > 0 && !d.isInfinite)
    def rule: String = "a number > 0"
    def json: ujson.Value = ujson.Obj("kind" -> "positive")
  }
  /** Letters each followed by an integer in its range, e.g. e<3..8>m<2..23>. */
  final case class Template(parts: Seq[(String, Int, Int)]) extends Domain {
    private val re = parts.map { case (l, _, _) => s"$l(\\d+)" }.mkString.r
    def accepts(v: String): Boolean = v.toLowerCase match {
      case re(ns @ _*) => ns.zip(parts).forall { case (n, (_, lo, hi)) => n.length <= 4 && n.toInt >= lo && n.toInt <= hi }
      case _ => false
    }
    def rule: String = parts.map { case (l, lo, hi) => s"$l<$lo..$hi>" }.mkString
    def json: ujson.Value = ujson.Obj("kind" -> "template", "parts" -> parts.map { case (l, lo, hi) => ujson.Obj("letter" -> l, "lo" -> lo, "hi" -> hi) })
  }
  final case class AnyOf(ds: Domain*) extends Domain {
    def accepts(v: String): Boolean = ds.exists(_.accepts(v))
    def rule: String = ds.map(_.rule).mkString(", or ")
    def json: ujson.Value = ujson.Obj("kind" -> "any_of", "of" -> ds.map(_.json))
  }
  /** A name of the board catalog (the file is an input, so the names are read where a value is judged). */
  case object Board extends Domain {
    def accepts(v: String): Boolean = true // rtaccel.area.Boards.byName refuses an unknown board with the catalog's names
    def rule: String = "a board of the catalog (boards/catalog.json)"
    def json: ujson.Value = ujson.Obj("kind" -> "board")
  }
  /** A file path (no rule beyond existing where it is read). */
  case object File extends Domain {
    def accepts(v: String): Boolean = v.nonEmpty
    def rule: String = "a file"
    def json: ujson.Value = ujson.Obj("kind" -> "file")
  }

  /** The make targets that read each group of knobs (a knob given to any other target is refused by the Makefile,
    * which reads these lists from the export: a user who passes NODE_CACHE= to make trace must hear that it had no
    * effect). soak and bench-caches run make simulate / cachesim with the knobs given, but their own CONFIG (and
    * bench-caches its own TUS and NODE_CACHE).
    */
  object Use {
    /** The tree and the arithmetic: every command that builds a tree. */
    val tree: Set[String] = Set("trace", "cachesim", "check", "analyze", "bench", "simulate", "roofline", "soak", "verilog", "lint",
      "area", "timing", "max-tus", "precision", "bench-caches")
    /** The platform: TUs, IUs, memory, response order, caches (the cache models, the RTL, its cost, the throughput). */
    val platform: Set[String] = tree -- Set("trace", "check", "analyze")
    /** The datapath's registers and the clock: the circuit's commands and the fp operators alone (area-fp). */
    val clocked: Set[String] = platform + "area-fp"
    /** The RTL's own knobs, which no model reads (the memory controller's re-reads: below the caches, they change no
      * count, no hit and no throughput model's figure): the commands that build or simulate the circuit. */
    val circuit: Set[String] = Set("simulate", "roofline", "soak", "verilog", "lint", "area", "timing", "max-tus")
    /** make precision runs every arithmetic option itself (PRECISION_OPTIONS) */
    val arithmetic: Set[String] = tree - "precision"
  }

  /** Where the cost model is calibrated: the values (as the knob spells them) it was fitted on, and how a platform's
    * value reads (`effective`: what the circuit has, e.g. TAG_FORWARD has no effect without a cache).
    */
  final case class Calibration(values: Seq[String], effective: PlatformParams => String)

  /** A register field through which the host reads the value a circuit was built with (REGISTER.FIELD of top.RegMap,
    * docs/registers.md) and what the circuit of `p` holds there: RtAccelTop.configWords encodes the read-only
    * configuration words from these; in a RW register it is the reset value (RegFileSpec). */
  final case class Field(name: String, value: PlatformParams => Long)

  /** `why`: a reason the refusal of a value outside the domain adds (the rule alone does not say it).
    * `echo`: the keys under which the JSON last line of every command that reads the knob reports the value it ran
    * with (resolved: a fitted format, the board's clock), from the resolved platform; several knobs may share one
    * key (the formats' `numerics`, the caches' `caches`). Empty only for a knob that is not a value of the platform
    * (CATALOG: a file to read boards from). */
  final case class Knob(make: String, flag: String, help: String, domain: Domain, shapes: Boolean, commands: Set[String],
                        calibrated: Option[Calibration] = None, why: String = "",
                        echo: PlatformParams => Seq[(String, ujson.Value)] = _ => Nil, fields: Seq[Field] = Nil,
                        setAside: Option[PlatformParams => PlatformParams] = None) {
    def json: ujson.Obj = ujson.Obj("make" -> make, "flag" -> s"--$flag", "help" -> help, "domain" -> domain.json,
      "rule" -> domain.rule, "shapes_circuit" -> shapes, "commands" -> commands.toSeq.sorted,
      "cost_calibrated" -> calibrated.fold[ujson.Value]("all")(c => ujson.Arr.from(c.values)),
      "json_keys" -> echo(Presets.paper2017).map(_._1), "register_fields" -> registers)
    def echoes(f: PlatformParams => Seq[(String, ujson.Value)]): Knob = copy(echo = f)
    /** The register fields through which the host reads the value (RegisterFieldsSpec checks each one exists and
      * moves with the knob). */
    def reads(fields: Field*): Knob = copy(fields = fields)
    def registers: Seq[String] = fields.map(_.name)
    /** One key, one value. */
    def echoes(key: String)(f: PlatformParams => ujson.Value): Knob = copy(echo = p => Seq(key -> f(p)))
    /** A knob that shapes no circuit: the platform with what it sets put back to a fixed value, so that the circuit's
      * build keys (`circuitView`) do not tell two values of it apart. */
    def setsAside(f: PlatformParams => PlatformParams): Knob = copy(setAside = Some(f))
  }

  private val policies = Names(CachePolicy.all.map(_.name))
  private def cal(values: String*)(effective: PlatformParams => String) = Some(Calibration(values, effective))
  private def bit(b: Boolean) = if (b) "1" else "0"
  private def flag(b: Boolean): Long = if (b) 1L else 0L
  private def log2(n: Int): Long = chisel3.util.log2Ceil(n).toLong
  private def at(name: String)(value: PlatformParams => Long) = Field(name, value)
  private def cacheKnobs(prefix: String, what: String): Seq[Knob] = {
    val P = prefix.toUpperCase
    val c: PlatformParams => CacheParams = if (prefix == "node") _.nodeCache else _.primCache
    Seq(
      Knob(s"${P}_CACHE", s"$prefix-cache", s"$what cache entries (0 = none)", Ints(1, 1 << 24, pow2 = true, zero = true), shapes = true,
        if (prefix == "node") Use.platform - "bench-caches" else Use.platform),
      Knob(s"${P}_WAYS", s"$prefix-ways", s"$what cache ways", Ints(1, 64, pow2 = true), shapes = true, Use.platform),
      Knob(s"${P}_POLICY", s"$prefix-policy", s"$what cache replacement policy", policies, shapes = true, Use.platform))
      .zip(Seq[Seq[(String, CacheParams => Long)]](
        Seq("LOG2_ENTRIES" -> (c => if (c.entries > 0) log2(c.entries) else 0L), "PRESENT" -> (c => flag(c.entries > 0))),
        Seq("WAYS" -> (_.ways.toLong)), Seq("POLICY" -> (c => CachePolicy.code(c.policy).toLong))))
      .map { case (k, fs) => k.echoes(caches).reads(fs.map { case (f, v) => at(s"${P}_CACHE.$f")(p => v(c(p))) }: _*) }
  }

  /** The caches as built: entries, ways, policy and MAX_LEVEL per path (`node_cache` and `prim_cache` are the
    * commands' counts of a run, so the configuration has a key of its own). */
  private val caches: PlatformParams => Seq[(String, ujson.Value)] = { p =>
    def one(c: CacheParams) = ujson.Obj("entries" -> c.entries, "ways" -> c.ways, "policy" -> c.policy.name, "max_level" -> c.maxLevel)
    Seq("caches" -> ujson.Obj("node" -> one(p.nodeCache), "prim" -> one(p.primCache)))
  }
  private val numerics: PlatformParams => Seq[(String, ujson.Value)] = p => Seq("numerics" -> Numerics.json(p))

  val all: Seq[Knob] = Seq(
    Knob("CONFIG", "config", "preset name or fit (the widths fitted to the scene)", Names(("fit" +: Presets.all.keys.toSeq.sorted)), shapes = true, Use.tree -- Set("soak", "bench-caches")).echoes("config")(_.name),
    Knob("M", "m", "MBVH width (2, 4, 8)", Names(Seq("2", "4", "8")), shapes = true, Use.tree ++ Set("paper-nocache", "paper-caches")).echoes("m")(_.m).reads(at("CONFIG0.M")(_.m)),
    Knob("MPPL", "mppl", "max primitives per leaf", Ints(1, 16), shapes = true, Use.tree ++ Set("paper-nocache", "paper-caches")).echoes("mppl")(_.mppl),
    Knob("TUS", "tus", "traversal units", Ints(1, 1024), shapes = true, Use.platform - "bench-caches").echoes("tus")(_.tus).reads(at("CONFIG0.TUS")(_.tus)),
    Knob("IUS", "ius", "intersection units, each with its own MC and caches serving TUS / IUS TUs (TUS a multiple of IUS)", Ints(1, 64), shapes = true, Use.platform).echoes("ius")(_.ius).reads(at("FORMATS2.IUS")(_.ius)),
    Knob("MEM_CHANNELS", "mem-channels", "address-interleaved DRAM channels, each an AXI4 master with MEM_GBPS of its own",
      Ints(1, 16, pow2 = true), shapes = true, Use.platform, cal("1")(p => p.memChannels.toString)).echoes("mem_channels")(_.memChannels),
    Knob("STACK", "stack-depth", "TU stack entries", Ints(1, 4096), shapes = true, Use.tree).echoes("stack_depth")(_.stackDepth).reads(at("CONFIG1.STACK_DEPTH")(_.stackDepth)),
    Knob("RESP_ORDER", "resp-order", "MC response order: request (one stream in request order, the paper's) | path (node and primitive streams, " +
      "each in its own order, so a hit never waits behind the other path's miss) | tagged (the two streams, each in any order, tagged by TU: " +
      "hits under misses)", Names(Seq(RespOrder.Request, RespOrder.Path, RespOrder.Tagged)), shapes = true, Use.platform,
      cal(RespOrder.Request)(_.respOrder)).echoes("resp_order")(_.respOrder).reads(at("FORMATS2.RESP_ORDER")(p => flag(p.respByPath)), at("FORMATS2.RESP_TAGGED")(p => flag(p.respTagged))),
    Knob("RAY_STORE", "ray-store", "1: each IU keeps its TUs' rays in a ray store written by the TC, requests carry the TU's index and not the ray; 0: the paper's",
      Names(Seq("0", "1")), shapes = true, Use.platform, cal("0")(p => bit(p.rayStore))).echoes("ray_store")(_.rayStore).reads(at("FORMATS2.RAY_STORE")(p => flag(p.rayStore))),
    Knob("TAG_FORWARD", "tag-forward", "1: every cache path's tags take one lookup per cycle (the set just written is forwarded to the next lookup); 0: one per two cycles",
      Names(Seq("0", "1")), shapes = true, Use.platform, cal("0")(p => bit(p.tagForward && (p.nodeCache.entries > 0 || p.primCache.entries > 0)))).echoes("tag_forward")(_.tagForward).reads(at("FORMATS2.TAG_FORWARD")(p => flag(p.tagForward))),
    Knob("NODE_BANKS", "node-banks", "k >= 1: one node cache of NODE_CACHE entries shared by every IU, in k banks by the node id's low bits (needs RESP_ORDER=tagged); 0: a node cache per IU",
      Ints(1, 64, pow2 = true, zero = true), shapes = true, Use.platform, cal("0")(_.nodeBanks.toString)).echoes("node_banks")(_.nodeBanks).reads(at("NODE_CACHE.SHARED")(p => flag(p.nodeShared)), at("NODE_CACHE.BANKS_LOG2")(_.nodeBankBits)),
    Knob("MEM_RETRIES", "mem-retries", "re-reads of a burst the memory answered with SLVERR before its rays are flagged read error (0: flag at once)",
      Ints(0, PlatformParams.MaxMemRetries), shapes = true, Use.circuit).echoes("mem_retry_limit")(_.memRetries).reads(at("FORMATS2.MEM_RETRIES")(_.memRetries)),
    Knob("SHORT_STACK", "short-stack", "ring of that many entries with restart instead of the full stack (0: the full stack)", Ints(0, 64), shapes = true, Use.tree).echoes("short_stack")(_.shortStack),
    Knob("MAX_STEPS", "max-steps", "fetches (node or leaf) a ray may issue; a ray that needs more is flagged prim -4 (0: no limit; " +
      "default: a bound no ray of an uncorrupted image reaches, PlatformParams.stepBound)",
      Ints(1, math.min(HwLimits().stepMax, Int.MaxValue.toLong).toInt, zero = true), shapes = true, Use.tree).echoes("max_steps")(_.stepLimit.toDouble).reads(at("MAX_STEPS.VALUE")(_.stepLimit)),
    Knob("BOX_FORMAT", "box-format", "arithmetic of the ray-box test (narrower ones round outward; m<M> fits the exponent to the scene)",
      AnyOf(Names(Seq("fp32", "fp24", "bf16", "fp16")), Template(Seq(("e", 3, 8), ("m", 2, 23))), Template(Seq(("m", 2, 23)))), shapes = true, Use.arithmetic,
      cal("fp32")(_.boxFormat.name)).echoes(p => ("box_format" -> ujson.Str(p.boxFormat.name)) +: numerics(p))
      .reads(at("FORMATS.BOX_FP")(p => flag(p.boxFormat != rtaccel.fp.FpFormat.fp32)), at("FORMATS.BOX_EXP_BITS")(_.boxFormat.expBits),
        at("FORMATS.BOX_MAN_BITS")(_.boxFormat.manBits)),
    Knob("TRI_TEST", "tri-test", "ray-triangle test: mt (Moller-Trumbore, the paper's) | watertight (Woop et al. 2013)",
      Names(TriTest.all.map(_.name)), shapes = true, Use.arithmetic, cal(TriTest.Mt.name)(_.triTest.name)).echoes(numerics).reads(at("FORMATS.TRI_TEST")(p => TriTest.all.indexOf(p.triTest))),
    Knob("TRI_FORMAT", "tri-format", "arithmetic of Moller-Trumbore (wider ones round t, u, v to fp32 at the end)",
      AnyOf(Names(Seq("fp32", "fp64")), Template(Seq(("e", 8, 11), ("m", 23, 52)))), shapes = true, Use.arithmetic, cal("fp32")(_.triFormat.name),
      why = "triangle arithmetic narrower than fp32 is not conservative (it loses hits)").echoes(numerics)
      .reads(at("FORMATS.TRI_FP")(p => flag(p.triFormat != rtaccel.fp.FpFormat.fp32)), at("FORMATS2.TRI_EXP_BITS")(_.triFormat.expBits),
        at("FORMATS2.TRI_MAN_BITS")(_.triFormat.manBits)),
    Knob("TRI_II", "tri-ii", "cycles between two primitives at least (the triangle pipe's initiation interval): k > 1 shares each of " +
      "Moller-Trumbore's operators among k operations of a primitive, about 1/k of its multipliers and adders, the same results",
      Ints(1, PlatformParams.MaxTriInterval), shapes = true, Use.platform, cal("1")(_.triInterval.toString))
      .echoes("tri_ii")(_.triInterval).reads(at("INTERVALS.TRI_II")(_.triInterval)),
    Knob("BOX_II", "box-ii", "cycles between two nodes at least (the box pipe's initiation interval): k > 1 shares each of the slab test's " +
      "subtractors and multipliers among k planes of a node, about 1/k of them, the same results",
      Ints(1, PlatformParams.MaxBoxInterval), shapes = true, Use.platform, cal("1")(_.boxInterval.toString))
      .echoes("box_ii")(_.boxInterval).reads(at("INTERVALS.BOX_II")(_.boxInterval)),
    Knob("NODE_FORMAT", "node-format", "node layout: full (6 fp32 planes per child), q<bits> (quantized planes, docs/numerics.md) or fit (the narrowest the scene needs)",
      AnyOf(Names(Seq("full", "fit")), Template(Seq(("q", 2, 16)))), shapes = true, Use.tree, cal("full")(p => Numerics.nodeFormatName(p.nodeQuantBits))).echoes(numerics)
      .reads(at("FORMATS2.NODE_QUANT_BITS")(_.nodeQuantBits), at("FORMATS.NODE_BYTES_LOG2")(p => log2(p.nodeSlotBytes))),
    Knob("PRIM_FORMAT", "prim-format", "primitive layout: slot64 (9 fp32 + id in 64 B) or packed (40 B records back to back, a beat-aligned row per leaf)",
      Names(Numerics.primFormats), shapes = true, Use.tree, cal("slot64")(p => if (p.primPacked) "packed" else "slot64")).echoes(numerics).reads(at("FORMATS.PRIM_PACKED")(p => flag(p.primPacked))),
    Knob("NODE_BYTES", "node-bytes", "bytes per node fetch", Ints(1, 4096), shapes = true, Use.tree).echoes("node_access_bytes")(_.nodeAccessBytes),
    Knob("PRIM_BYTES", "prim-bytes", "bytes per primitive fetch", Ints(1, 4096), shapes = true, Use.tree).echoes("prim_access_bytes")(_.primAccessBytes),
    Knob("BOARD", "board", "board of the catalog: its memory bandwidth and clock unless MEM_GBPS / CLOCK_MHZ are given", Board, shapes = true, Use.clocked).echoes("family")(_.family),
    Knob("MEM_GBPS", "mem-gbps", "peak memory bandwidth in GB/s", Positive, shapes = false, Use.platform).echoes("mem_gbps")(_.memory.bytesPerSecond / 1e9)
      // the DRAM's figures (this bandwidth, or the board's with its efficiency and latency) are the throughput
      // models' and the simulator's DRAM model's (whose own build key names them): no RTL reads them
      .setsAside(_.copy(memory = MemoryParams())),
    Knob("CLOCK_MHZ", "clock-mhz", "platform clock in MHz, or fmax (the clock measured for the configuration's circuit)",
      AnyOf(Positive, Names(Seq("fmax"))), shapes = true, Use.clocked)
      .echoes(p => Seq("clock_mhz" -> ujson.Num(p.clockMhz), "clock_source" -> ujson.Str(p.clockSource))),
    Knob("PIPELINE", "pipeline", "register placement of the datapaths: auto (the LUT-level budget of the target clock on the board's family) | " +
      "none (the fixed stages) | <levels>", AnyOf(Names(Seq("auto", "none")), Ints(Pipelining.MinLevels, Pipelining.MaxLevels)), shapes = true, Use.clocked).echoes("pipeline")(Pipelining.json).reads(at("PIPELINE.BUDGET")(_.stageBudget.getOrElse(0).toLong)),
    Knob("CATALOG", "catalog", "board catalog file (default boards/catalog.json)", File, shapes = true, Use.clocked),
  ) ++ cacheKnobs("node", "node") ++ cacheKnobs("prim", "primitive") :+
    Knob("MAX_LEVEL", "max-level", "MAX_LEVEL of the level replacement policy", Ints(0, HwLimits().maxLevelCode), shapes = true, Use.platform).echoes(caches)
      .reads(at("MAX_LEVEL.VALUE")(_.nodeCache.maxLevel))

  // a knob that shapes no circuit says how to set it aside, else the build keys would tell its values apart
  require(all.forall(k => k.shapes == k.setAside.isEmpty), all.filter(k => k.shapes != k.setAside.isEmpty).map(_.make).mkString(", "))

  /** The platform as its circuit sees it: every knob that shapes no circuit set aside (PlatformRun.paramsDigest,
    * EmitVerilog's key). */
  def circuitView(p: PlatformParams): PlatformParams = all.flatMap(_.setAside).foldLeft(p)((q, f) => f(q))

  def byFlag(flag: String): Option[Knob] = all.find(_.flag == flag)
  def byMake(make: String): Option[Knob] = all.find(_.make == make)

  /** The first check of a knob's value: one message naming the make variable and what it takes. */
  def check(k: Knob, v: String): String =
    if (k.domain.accepts(v)) v
    else throw new InputError(s"${k.make}=$v: ${k.make} takes ${k.domain.rule}" + (if (k.why.isEmpty) "" else s"; ${k.why}"))

  /** The knobs whose value in `p` the cost model was not fitted on, each with that value. */
  def uncalibrated(p: PlatformParams): Seq[(Knob, String)] =
    all.flatMap(k => k.calibrated.flatMap { c => val v = c.effective(p); if (c.values.contains(v)) None else Some(k -> v) })

  /** The knobs `command` reads, as that command's JSON reports them: the values `p` (resolved) ran with. A command
    * merges it under its own keys, so every JSON last line echoes the same knobs the same way. */
  def echo(p: PlatformParams, command: String): Seq[(String, ujson.Value)] = {
    val seen = scala.collection.mutable.LinkedHashMap.empty[String, ujson.Value]
    for (k <- all if k.commands(command); (key, v) <- k.echo(p) if !seen.contains(key)) seen(key) = v
    seen.toSeq
  }

  /** The export (make knobs): every knob with its domain as data, for the Makefile and dse/. */
  def json: ujson.Obj = ujson.Obj("knobs" -> ujson.Arr.from(all.map(_.json)),
    // the policies whose node references carry the tree level (paper Section 7.2): dse/ tells the level policy apart
    "level_aware_policies" -> CachePolicy.all.filter(_.levelAware).map(_.name))
}
