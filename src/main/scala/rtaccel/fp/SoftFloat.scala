package rtaccel.fp

/** Bit-accurate software model of the floating-point units for any [[FpFormat]], on raw bit patterns (Long).
  *
  * Written independently of the RTL: every finite operand is decoded to an exact value mant * 2^exp
  * (BigInt mant), the operation is carried out exactly (add/sub/mul) or as an exact quotient with a
  * remainder flag (div), and one rounding function takes the exact result to the format (round to
  * nearest, ties to even; subnormals kept; overflow to ±inf). Comparisons are exact comparisons of the
  * decoded values. NaN results are always `f.canonicalNaN`; minNum/maxNum return an operand's exact bits.
  */
final class SoftFloat(val f: FpFormat) {
  private val m = f.manBits
  private val width = f.width
  val mask: Long = if (width == 64) -1L else (1L << width) - 1
  val canonicalNaN: Long = f.canonicalNaN.toLong
  private val signBit: Long = 1L << (width - 1)
  private val emin = 1 - f.bias // exponent of the smallest normal binade
  private val hidden = BigInt(1) << m

  import SoftFloat._

  private[fp] def decode(x0: Long): V = {
    val x = x0 & mask
    val neg = (x & signBit) != 0
    val ef = ((x >>> m) & f.maxExp).toInt
    val frac = x & ((1L << m) - 1)
    if (ef == f.maxExp) { if (frac == 0) InfV(neg) else NaNV }
    else if (ef == 0) FinV(neg, BigInt(frac), emin - m)
    else FinV(neg, BigInt(frac) + hidden, ef - f.bias - m)
  }

  private def zero(neg: Boolean): Long = if (neg) signBit else 0L
  private def inf(neg: Boolean): Long = (if (neg) signBit else 0L) | (f.maxExp.toLong << m)

  /** Round (-1)^neg * (mant * 2^exp + t) to the format, where 0 <= t < 2^exp and t > 0 iff `sticky`. mant > 0. */
  private[fp] def round(neg: Boolean, mant: BigInt, exp: Int, sticky: Boolean, mode: Mode = Nearest): Long = {
    require(mant.signum > 0)
    val lead = exp + mant.bitLength - 1 // exponent of the leading bit
    var ulp = math.max(lead - m, emin - m) // exponent of the result's last place
    val shift = ulp - exp
    var r: BigInt =
      if (shift <= 0) {
        require(!sticky, "inexact value given without enough bits to round")
        mant << -shift
      } else {
        val q = mant >> shift
        val rem = mant - (q << shift)
        val half = BigInt(1) << (shift - 1)
        val c = rem.compare(half)
        val inexact = rem.signum != 0 || sticky
        val up = mode match {
          case Nearest => c > 0 || (c == 0 && (sticky || q.testBit(0)))
          case dir => inexact && away(dir, neg)
        }
        if (up) q + 1 else q
      }
    if (r.bitLength > m + 1) { r >>= 1; ulp += 1 } // rounded up to the next power of two
    val s = if (neg) signBit else 0L
    if (r.bitLength <= m) s | r.toLong // subnormal or zero (ulp == emin - m here)
    else {
      val biased = ulp + m + f.bias
      if (biased >= f.maxExp) { if (mode == Nearest || away(mode, neg)) inf(neg) else s | maxFinite }
      else s | (biased.toLong << m) | (r - hidden).toLong
    }
  }

  private val maxFinite: Long = ((f.maxExp - 1).toLong << m) | ((1L << m) - 1)
  /** Whether a directed mode rounds a value of this sign away from zero. */
  private def away(mode: Mode, neg: Boolean): Boolean = (mode == Up && !neg) || (mode == Down && neg)

  private def addExact(a: FinV, b: FinV, mode: Mode): Long = {
    val e = math.min(a.exp, b.exp)
    val sum = (a.signed << (a.exp - e)) + (b.signed << (b.exp - e))
    // x + (-x) = +0 (-0 when rounding toward -inf, IEEE 754 6.3); (-0) + (-0) = -0
    if (sum.signum == 0) zero(if (a.neg == b.neg) a.neg else mode == Down)
    else round(sum.signum < 0, sum.abs, e, sticky = false, mode)
  }

  private def addV(va: V, vb: V, mode: Mode): Long = (va, vb) match {
    case (NaNV, _) | (_, NaNV) => canonicalNaN
    case (InfV(x), InfV(y)) => if (x == y) inf(x) else canonicalNaN
    case (InfV(x), _) => inf(x)
    case (_, InfV(y)) => inf(y)
    case (x: FinV, y: FinV) => addExact(x, y, mode)
  }

  def add(a: Long, b: Long): Long = addV(decode(a), decode(b), Nearest)

  def neg(a: Long): Long = (a ^ signBit) & mask
  def sub(a: Long, b: Long): Long = add(a, neg(b))
  /** a - b of format `from` (exact), rounded into this format in `mode`. */
  def subFrom(from: SoftFloat, a: Long, b: Long, mode: Mode): Long = addV(from.decode(a), from.decode(from.neg(b)), mode)
  /** x of format `from` in this format: exact when it fits, else rounded in `mode`. */
  def convertFrom(from: SoftFloat, x: Long, mode: Mode): Long = from.decode(x) match {
    case NaNV => canonicalNaN
    case InfV(n) => inf(n)
    case v: FinV => if (v.isZero) zero(v.neg) else round(v.neg, v.mant, v.exp, sticky = false, mode)
  }

  def mul(a: Long, b: Long): Long = mul(a, b, Nearest)
  def mul(a: Long, b: Long, mode: Mode): Long = (decode(a), decode(b)) match {
    case (NaNV, _) | (_, NaNV) => canonicalNaN
    case (InfV(x), InfV(y)) => inf(x != y)
    case (InfV(x), y: FinV) => if (y.isZero) canonicalNaN else inf(x != y.neg)
    case (x: FinV, InfV(y)) => if (x.isZero) canonicalNaN else inf(x.neg != y)
    case (x: FinV, y: FinV) =>
      val p = x.mant * y.mant
      if (p.signum == 0) zero(x.neg != y.neg) else round(x.neg != y.neg, p, x.exp + y.exp, sticky = false, mode)
  }

  def div(a: Long, b: Long): Long = (decode(a), decode(b)) match {
    case (NaNV, _) | (_, NaNV) => canonicalNaN
    case (InfV(_), InfV(_)) => canonicalNaN
    case (InfV(x), y: FinV) => inf(x != y.neg)
    case (x: FinV, InfV(y)) => zero(x.neg != y)
    case (x: FinV, y: FinV) =>
      val n = x.neg != y.neg
      if (y.isZero) { if (x.isZero) canonicalNaN else inf(n) }
      else if (x.isZero) zero(n)
      else {
        // quotient with at least m+3 significant bits, the rest summarised by a nonzero-remainder flag
        val k = math.max(0, (m + 4) + y.mant.bitLength - x.mant.bitLength)
        val (q, r) = (x.mant << k) /% y.mant
        round(n, q, x.exp - y.exp - k, sticky = r.signum != 0)
      }
  }

  // ----- comparisons (exact), IEEE: false with a NaN, -0 == +0

  def isNaN(a: Long): Boolean = decode(a) == NaNV

  /** Some(sign of a - b) for non-NaN operands; None if either is NaN. */
  private def compare(a: Long, b: Long): Option[Int] = (decode(a), decode(b)) match {
    case (NaNV, _) | (_, NaNV) => None
    case (InfV(x), InfV(y)) => Some(if (x == y) 0 else if (x) -1 else 1)
    case (InfV(x), _) => Some(if (x) -1 else 1)
    case (_, InfV(y)) => Some(if (y) 1 else -1)
    case (x: FinV, y: FinV) =>
      val e = math.min(x.exp, y.exp)
      Some(((x.signed << (x.exp - e)) - (y.signed << (y.exp - e))).signum)
  }

  def lt(a: Long, b: Long): Boolean = compare(a, b).exists(_ < 0)
  def le(a: Long, b: Long): Boolean = compare(a, b).exists(_ <= 0)
  def gt(a: Long, b: Long): Boolean = compare(a, b).exists(_ > 0)
  def ge(a: Long, b: Long): Boolean = compare(a, b).exists(_ >= 0)
  def eq(a: Long, b: Long): Boolean = compare(a, b).contains(0)

  def minNum(a: Long, b: Long): Long = if (isNaN(a)) b else if (isNaN(b)) a else if (lt(a, b)) a else b
  def maxNum(a: Long, b: Long): Long = if (isNaN(a)) b else if (isNaN(b)) a else if (gt(a, b)) a else b
  def minProp(a: Long, b: Long): Long = if (isNaN(a) || isNaN(b)) canonicalNaN else if (lt(a, b)) a else b
  def maxProp(a: Long, b: Long): Long = if (isNaN(a) || isNaN(b)) canonicalNaN else if (gt(a, b)) a else b
}

object SoftFloat {
  /** Rounding: to nearest even (every unit's default), or toward -inf (Down) / +inf (Up) for outward bounds. */
  sealed trait Mode
  case object Nearest extends Mode
  case object Down extends Mode
  case object Up extends Mode

  /** A decoded operand. Finite values are (-1)^neg * mant * 2^exp exactly (mant = 0 for zeros). */
  private[fp] sealed trait V
  private[fp] case object NaNV extends V
  private[fp] final case class InfV(neg: Boolean) extends V
  private[fp] final case class FinV(neg: Boolean, mant: BigInt, exp: Int) extends V {
    def signed: BigInt = if (neg) -mant else mant
    def isZero: Boolean = mant == 0
  }
}
