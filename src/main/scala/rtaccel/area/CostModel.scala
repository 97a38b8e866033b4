package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import rtaccel.cache.hw.{CacheGeometry, CachePath}
import rtaccel.config.{Knobs, PlatformParams}
import rtaccel.io.InputError

/** The fast rung of the cost side (docs/area.md, "cost model"): FPGA resources of a configuration as a sum over
  * the platform's units, each a linear function of the parameters that shape it, with coefficients fitted by
  * CostFit from real Yosys syntheses. Answers in milliseconds where a synthesis takes minutes.
  *
  * A unit is a module of the hierarchy (with everything it instantiates that is not itself a unit); its
  * features are the parameters its logic grows with, e.g. a TU's stack bits or the request arbiter's TU count.
  */
object CostModel {
  /** A unit: the module names it covers, its features, and whether its cost is per instance (TUs, dividers). */
  final case class CostUnit(name: String, modules: scala.util.matching.Regex, perInstance: Boolean,
                        features: PlatformParams => Seq[(String, Double)], instances: PlatformParams => Long)

  val resources: Seq[String] = Seq("lut", "lutram", "ff", "dsp", "bram36", "carry")

  private def one(p: PlatformParams) = Seq("one" -> 1.0)
  private def once(p: PlatformParams) = 1L
  /** IUS clusters each build an IU (its pipes) and an MC (its caches): those units' features are one cluster's times
    * IUS, so that the fit (made on one cluster) scales exactly and is unchanged at IUS=1. */
  private def perIu(p: PlatformParams, f: Seq[(String, Double)]) = f.map { case (k, v) => k -> v * p.ius }
  private def bits(n: Int) = 32 - Integer.numberOfLeadingZeros(math.max(1, n) - 1)
  private val entry = rtaccel.tu.TraversalUnit.entryBits.toDouble

  /** The caches the MC builds for `p`, with the geometry CachePath uses. */
  def caches(p: PlatformParams): Seq[CacheGeometry] = {
    val beat = p.axiDataBits / 8
    (if (p.nodeCache.entries > 0) Seq(CachePath.nodeGeometry(p.nodeCache, p, p.nodeSlotBytes / beat)) else Nil) ++
      (if (p.primCache.entries > 0) Seq(CachePath.primGeometry(p.primCache, p.mppl, p, beat)) else Nil)
  }

  /** Block RAM of the caches' data arrays as CachePath builds them: lines x beats deep, the beats of a line padded to a
    * power of two (the line index is a shift; a packed leaf row of 5 beats takes 8), one beat + its error bit wide. */
  def cacheDataBram(p: PlatformParams): Double = caches(p).map(g => BramMap.bram36(g.dataLines.toLong << g.beatBits, p.axiDataBits + 1)).sum

  val units: Seq[CostUnit] = Seq(
    CostUnit("TraversalUnit", "TraversalUnit".r, perInstance = true, p => {
      val full = p.shortStack == 0
      // a TU ranks its M children with M(M-1) comparators; its stack is LUT RAM (full) or a ring + trail (short)
      Seq("one" -> 1.0, "m" -> p.m.toDouble, "m2" -> (p.m * p.m).toDouble,
        "stack_bits" -> (if (full) p.stackDepth * entry else 0.0),
        "short_bits" -> (if (full) 0.0 else p.shortStack * (entry + bits(p.treeLevels + 1)) + (p.treeLevels + 1.0) * bits(p.m + 1)))
    }, _.tus.toLong),
    // the TC's own logic: ray set-up (three dividers are units of their own) and the TUs' result arbiter
    CostUnit("TraversalController", "TraversalController".r, perInstance = false, p => one(p) :+ ("tus" -> p.tus.toDouble), once),
    // the IU's own logic is mostly the request arbiter over the TUs (each request carries the ray)
    CostUnit("IntersectionUnit", "IntersectionUnit".r, perInstance = false, p => perIu(p, one(p) :+ ("tus" -> p.tusPerIu.toDouble)), once),
    CostUnit("BoxPipe", "BoxPipe".r, perInstance = false, p => perIu(p, one(p) :+ ("m" -> p.m.toDouble)), once),
    CostUnit("TriPipe", "TriPipe".r, perInstance = false, p => perIu(p, one(p)), once),
    // 1/d per axis in the TC, 1/det in the triangle pipe
    CostUnit("FpDivPipe", "FpDivPipe".r, perInstance = true, one, p => (rtaccel.tc.TraversalController.dividers + rtaccel.iu.TriPipe.dividers * p.ius).toLong),
    CostUnit("MemoryController", "MemoryController".r, perInstance = false, p => perIu(p, one(p)), once),
    // every cache of the MC together: tags and policy state grow with lines, data RAM is block RAM
    CostUnit("CachePath", "CachePath(_[0-9]+)?".r, perInstance = false, p => {
      val cs = caches(p)
      perIu(p, Seq("caches" -> cs.length.toDouble, "lines" -> cs.map(_.dataLines.toDouble).sum,
        "assoc_lines" -> cs.filter(g => g.c.ways > 1 || g.sideLines > 0).map(_.dataLines.toDouble).sum,
        "data_bram36" -> cacheDataBram(p)))
    }, once),
    CostUnit("RegFile", "RegFile".r, perInstance = false, one, once),
    CostUnit("PerfCounters", "PerfCounters".r, perInstance = false, one, once),
    CostUnit("RtAccelTop", "RtAccelTop".r, perInstance = false, one, once))

  def unitOf(module: String): Option[CostUnit] = units.find(_.modules.matches(module))

  /** Which features a resource is fitted on: block RAM of the caches follows their data arrays' tiling alone. */
  def featuresFor(u: CostUnit, resource: String, f: Seq[(String, Double)]): Seq[(String, Double)] =
    if (u.name == "CachePath") { if (resource == "bram36") f.filter(_._1 == "data_bram36") else f.filterNot(_._1 == "data_bram36") }
    else f

  /** A synthesis split into units: each unit's resources (all its instances) and instance count. */
  def decompose(s: Synthesis): Map[String, (Resources, Long)] = {
    val total = scala.collection.mutable.Map[String, Resources]().withDefaultValue(Resources())
    val count = scala.collection.mutable.Map[String, Long]().withDefaultValue(0L)
    val unknown = scala.collection.mutable.Set[String]()
    def walk(m: String, k: Long, owner: String): Unit = {
      val own = unitOf(m).map(_.name)
      own.foreach(u => count(u) += k)
      val g = own.getOrElse(owner)
      val cells = s.mods.getOrElse(m, Map.empty)
      val (subs, prims) = cells.partition { case (t, _) => s.mods.contains(t) }
      total(g) = total(g) + Resources.of(prims, unknown) * k
      subs.foreach { case (t, c) => walk(t, k * c, g) }
    }
    walk(s.top, 1, unitOf(s.top).map(_.name).getOrElse(s.top))
    total.keys.map(u => u -> (total(u), count(u))).toMap
  }

  def get(r: Resources, name: String): Double = name match {
    case "lut" => r.lut.toDouble; case "lutram" => r.lutram.toDouble; case "ff" => r.ff.toDouble
    case "dsp" => r.dsp.toDouble; case "bram36" => r.bram36; case "carry" => r.carry.toDouble
  }

  /** Fitted coefficients: unit -> resource -> feature -> coefficient, for one family, with per-family scales. */
  final case class Fitted(coef: Map[String, Map[String, Map[String, Double]]], family: String, yosysVersion: String,
                          familyScale: Map[String, Map[String, Double]], json: ujson.Obj) {
    /** Per-unit predictions (all instances of the unit) and instance counts for `p` on `fam`. */
    def predict(p: PlatformParams, fam: String): Seq[(String, Map[String, Double], Long)] = {
      // the fit has a term only for what it was calibrated on (config.Knobs: each knob's calibrated values); a figure
      // for anything else (a narrower box format, NodeDecode, the LeafAssembler, the path streams' FIFOs and tables,
      // the ray store, forwarded tags, more channels or shared banks) would be invented
      Knobs.uncalibrated(p).headOption.foreach { case (k, v) =>
        throw new InputError(s"the cost model is calibrated on ${k.make}=${k.calibrated.get.values.mkString(" or ")} only; ${k.make}=$v needs FIDELITY=yosys")
      }
      val scale = familyScale.getOrElse(fam, throw new InputError(
        s"the cost model has no calibration for family '$fam' (calibrated: ${familyScale.keys.toSeq.sorted.mkString(", ")}); use FIDELITY=yosys"))
      val extra = pipelineRegs(p, fam)
      units.map { u =>
        val n = u.instances(p); val f = u.features(p)
        val per = resources.map { r =>
          val c = coef.getOrElse(u.name, Map.empty).getOrElse(r, Map.empty)
          val v = featuresFor(u, r, f).map { case (k, x) => c.getOrElse(k, 0.0) * x }.sum
          // a linear fit can dip below zero far from its data; no unit has negative cost
          r -> (math.max(0.0, v) * (if (u.perInstance) n else 1) * scale.getOrElse(r, 1.0) + extra.get(r).flatMap(_.get(u.name)).getOrElse(0.0))
        }.toMap
        (u.name, per, n)
      }
    }
    /** The registers PIPELINE adds to each pipelined unit (all its instances): the register bits its Stagers place at
      * p's budget less those of the fixed stages the fit was made on, counted at elaboration (iu.PipeLatencies). On
      * Xilinx families a delay chain of three or more cycles is LUT RAM (SRLC32E), one LUT per 32 cycles of a bit;
      * elsewhere it is flip-flops. The triangle pipe's count holds its divider's, which the synthesis books under
      * FpDivPipe: it goes there. Resource -> unit -> amount.
      */
    def pipelineRegs(p: PlatformParams, fam: String): Map[String, Map[String, Double]] = if (p.stageBudget.isEmpty) Map.empty else {
      val Seq(b1, t1, d1) = rtaccel.iu.PipeLatencies.of(p).census
      val Seq(b0, t0, d0) = rtaccel.iu.PipeLatencies.of(p.copy(pipelining = rtaccel.config.Pipelining.Fixed)).census
      // the cost model takes fp32 triangles only: the triangle pipe's divider is the ray preparation's
      val perUnit = Map("BoxPipe" -> (b1 - b0) * p.ius, "TriPipe" -> ((t1 - d1) - (t0 - d0)) * p.ius,
        "FpDivPipe" -> (d1 - d0) * (rtaccel.tc.TraversalController.dividers + rtaccel.iu.TriPipe.dividers * p.ius).toLong)
      val srl = fam.startsWith("xc")
      Map("ff" -> perUnit.map { case (u, c) => u -> (if (srl) c.bits - c.chainBits else c.bits).toDouble },
        "lutram" -> perUnit.map { case (u, c) => u -> (if (srl) c.chainLuts else 0L).toDouble })
    }
    def total(p: PlatformParams, fam: String): Map[String, Double] = {
      val units = predict(p, fam) // once: its pipeline terms elaborate the pipes (PipeLatencies)
      resources.map(r => r -> units.map(_._2(r)).sum).toMap
    }
  }

  val defaultPath: Path = Paths.get("boards/cost-model.json")

  def load(path: Path = defaultPath): Fitted = {
    if (!Files.isRegularFile(path)) throw new InputError(s"cost model $path not found; run make cost-model (or use FIDELITY=yosys)")
    val j = try ujson.read(Files.readString(path)).obj catch {
      case e: ujson.ParseException => throw new InputError(s"cost model $path is not JSON: ${e.getMessage}")
    }
    fromJson(ujson.Obj.from(j))
  }

  def fromJson(j: ujson.Obj): Fitted = {
    val coef = j("units").obj.map { case (u, rs) => u -> rs.obj.map { case (r, fs) => r -> fs.obj.map { case (k, v) => k -> v.num }.toMap }.toMap }.toMap
    for ((u, rs) <- coef; un = units.find(_.name == u).getOrElse(throw new InputError(s"cost model: unit '$u' is not a unit of this version; run make cost-model"));
         (r, fs) <- rs; k <- fs.keys)
      if (!un.features(rtaccel.config.Presets.paper2017).exists(_._1 == k))
        throw new InputError(s"cost model: unit $u has no feature '$k' in this version; run make cost-model")
    val scale = j("family_scale").obj.map { case (f, rs) => f -> rs.obj.map { case (r, v) => r -> v.num }.toMap }.toMap
    Fitted(coef, j("family").str, j("yosys_version").str, scale, j)
  }
}
