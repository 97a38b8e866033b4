package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import rtaccel.io.InputError

/** The levels -> MHz rule of one family (boards/timing.json): a proxy with no placement, routing or retiming. */
final case class FamilyTiming(family: String, levelNs: Double, overheadNs: Double, capMhz: Double, source: String,
                              dsp: rtaccel.fp.DspShape = rtaccel.fp.DspShape.Dsp48, delayRamCycles: Option[Int] = None,
                              lutInputs: Int = rtaccel.fp.Depth.LutInputs) {
  def dspLevels: Int = dsp.levels
  def fmaxMhz(levels: Int): Double = math.min(capMhz, 1000.0 / (overheadNs + levels * levelNs))
  /** The most LUT levels a path may have at `mhz` by this rule (at least 1): what PIPELINE=auto budgets. */
  def levelsFor(mhz: Double): Int = math.max(1, math.floor((1000.0 / mhz - overheadNs) / levelNs + 1e-9).toInt)
  def rule: String = f"1000 / ($overheadNs%.2f + levels x $levelNs%.2f) ns, at most $capMhz%.0f MHz ($source)"
}

object Timing {
  val defaultPath: Path = Paths.get("boards/timing.json")

  def forFamily(family: String, path: Path = defaultPath): FamilyTiming = {
    if (!Files.isRegularFile(path)) throw new InputError(s"timing rules $path not found; run from the project root")
    val j = try ujson.read(Files.readString(path)) catch {
      case e: ujson.ParseException => throw new InputError(s"timing rules $path are not JSON: ${e.getMessage}")
    }
    val fams = j("families").obj
    val t = fams.getOrElse(family, throw new InputError(s"$path has no rule for family '$family'; add one (it has ${fams.keys.toSeq.sorted.mkString(", ")})"))
    def num(k: String) = t.obj.get(k).map(_.num).getOrElse(throw new InputError(s"family '$family' in $path has no '$k'"))
    val dspLevels = num("dsp_levels")
    if (dspLevels < 0 || dspLevels != dspLevels.toInt) throw new InputError(s"family '$family' in $path: dsp_levels must be a whole number >= 0 (got $dspLevels)")
    val dsp = t.obj.get("dsp_unsigned_bits").collect { case ujson.Arr(v) if v.length == 2 && v.forall(x => x.numOpt.exists(d => d >= 2 && d == d.toInt)) =>
      rtaccel.fp.DspShape(v(0).num.toInt, v(1).num.toInt, dspLevels.toInt)
    }.getOrElse(throw new InputError(s"family '$family' in $path needs dsp_unsigned_bits: [a, b], the widest unsigned operands one DSP block multiplies"))
    // dsp_primitive: the block instantiated with its own registers (fp.DspTile); absent where synthesis infers the blocks
    val registered = t.obj.get("dsp_primitive").filterNot(_.isNull) match {
      case None => false
      case Some(ujson.Str("MULT18X18D")) if dsp.a <= rtaccel.fp.DspTile.Bits && dsp.b <= rtaccel.fp.DspTile.Bits => true
      case Some(v) => throw new InputError(s"family '$family' in $path: dsp_primitive $v is not one rtaccel instantiates; use \"MULT18X18D\" (with dsp_unsigned_bits at most [18, 18]) or remove it")
    }
    // delay_ram_cycles: absent or null where delay chains map to shift-register LUTs
    val delayRam = t.obj.get("delay_ram_cycles").filterNot(_.isNull).map { v =>
      v.numOpt.filter(d => d >= 2 && d == d.toInt).map(_.toInt)
        .getOrElse(throw new InputError(s"family '$family' in $path: delay_ram_cycles must be a whole number >= 2 or null (got $v)"))
    }
    // lut_inputs: absent for the 6-input LUTs of the Xilinx families
    val lutInputs = t.obj.get("lut_inputs").filterNot(_.isNull).map { v =>
      v.numOpt.filter(d => (d == 4 || d == 6)).map(_.toInt)
        .getOrElse(throw new InputError(s"family '$family' in $path: lut_inputs must be 4 or 6 (got $v)"))
    }.getOrElse(rtaccel.fp.Depth.LutInputs)
    FamilyTiming(family, num("level_ns"), num("overhead_ns"), num("cap_mhz"), t.obj.get("source").map(_.str).getOrElse(""), dsp.copy(registered = registered), delayRam, lutInputs)
  }
}
