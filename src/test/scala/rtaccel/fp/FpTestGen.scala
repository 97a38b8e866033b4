package rtaccel.fp

import scala.util.Random

/** Operand generators for floating-point tests, generic in the format (raw bit patterns as Long). */
final class FpTestGen(val f: FpFormat, seed: Long) {
  val rnd = new Random(seed)
  private val m = f.manBits
  private val W = f.width
  val mask: Long = if (W == 64) -1L else (1L << W) - 1
  private val fracMask = (1L << m) - 1
  private val signBit = 1L << (W - 1)

  def bits(neg: Boolean, ef: Int, frac: Long): Long =
    (if (neg) signBit else 0L) | (ef.toLong << m) | (frac & fracMask)
  def expOf(x: Long): Int = ((x >>> m) & f.maxExp).toInt
  private def randFrac(): Long = rnd.nextLong() & fracMask
  private def randSign(): Boolean = rnd.nextBoolean()

  val posZero: Long = 0L
  val minSub: Long = 1L
  val maxSub: Long = fracMask
  val minNorm: Long = 1L << m
  val maxNorm: Long = bits(neg = false, f.maxExp - 1, fracMask)
  val inf: Long = bits(neg = false, f.maxExp, 0)
  val one: Long = bits(neg = false, f.bias, 0)
  val qNaN: Long = f.canonicalNaN.toLong
  val qNaNPayload: Long = bits(neg = false, f.maxExp, (1L << (m - 1)) | 1L)
  val sNaN: Long = bits(neg = false, f.maxExp, 1L) // fraction MSB clear: signalling
  val sNaNHigh: Long = bits(neg = false, f.maxExp, fracMask >> 1)

  /** Edge classes, both signs: zeros, subnormals (min, max, random), min/max normal, infinities, NaNs (quiet,
    * signalling, payloads, negative), ±1 and neighbours, powers of two at the overflow and underflow
    * boundaries, square roots of the extremes (for mul/div crossing the range limits).
    */
  val edges: IndexedSeq[Long] = {
    val e = f.maxExp
    val mid = f.bias
    val pos = Seq(
      posZero, minSub, 2L, 3L, maxSub, maxSub - 1, fracMask >> 1, (fracMask >> 1) + 1,
      minNorm, minNorm + 1, minNorm | fracMask, bits(false, 2, 0),
      maxNorm, maxNorm - 1, bits(false, e - 1, 0), bits(false, e - 2, fracMask), bits(false, e - 2, 0),
      one, one - 1, one + 1, bits(false, mid + 1, 0), bits(false, mid, 1L << (m - 1)), bits(false, mid - 1, fracMask),
      bits(false, (mid + 1) / 2, 0), bits(false, (mid + 1) / 2, fracMask), // ~ sqrt(min normal)
      bits(false, mid + (e - 1 - mid) / 2, 0), bits(false, mid + (e - 1 - mid) / 2, fracMask), // ~ sqrt(max)
      bits(false, math.max(1, mid - m), 0), bits(false, math.max(1, mid - m - 1), fracMask),
      inf, qNaN, qNaNPayload, sNaN, sNaNHigh
    )
    val subs = Seq.fill(4)((rnd.nextLong() & fracMask) | 1L)
    (pos ++ subs).flatMap(x => Seq(x, x | signBit)).distinct.toIndexedSeq
  }

  def randomEdge(): Long = edges(rnd.nextInt(edges.length))

  /** Uniform random bit pattern. */
  def uniform(): Long = rnd.nextLong() & mask

  /** Random finite value with biased exponent field ef (0 = subnormal). */
  def finiteWithExp(ef: Int): Long = bits(randSign(), ef, randFrac())

  /** Operands with nearby exponents (cancellation and rounding in add/sub, mixed ranges for mul/div). */
  def nearby(): (Long, Long) = {
    val ea = rnd.nextInt(f.maxExp) // 0 .. maxExp-1 (finite)
    val spread = if (rnd.nextInt(4) == 0) m + 4 else 3
    val eb = math.max(0, math.min(f.maxExp - 1, ea + rnd.nextInt(2 * spread + 1) - spread))
    (finiteWithExp(ea), finiteWithExp(eb))
  }

  /** Near-cancellation: b is -a (or a) with low fraction bits perturbed. */
  def cancel(): (Long, Long) = {
    val a = finiteWithExp(rnd.nextInt(f.maxExp))
    val k = rnd.nextInt(m + 1)
    val b0 = a ^ (rnd.nextLong() & ((1L << k) - 1))
    val b = if (rnd.nextBoolean()) b0 ^ signBit else b0
    (a, b & mask)
  }

  /** Exact add ties: b is an odd multiple of half an ulp of a (random signs: ties under add and sub). */
  def addTie(): (Long, Long) = {
    val ea = 1 + rnd.nextInt(f.maxExp - 1)
    val k = 1 + rnd.nextInt(m + 1) // b's exponent is k below a's
    val eb = ea - k
    val a = if (rnd.nextInt(4) == 0) bits(randSign(), ea, fracMask) else finiteWithExp(ea) // all-ones: carry into next binade
    if (eb < 1) (a, bits(randSign(), 0, 1L << rnd.nextInt(m))) // subnormal b: still exact, ties at the low end
    else {
      // b's significand has its lowest set bit at position k-1, i.e. at a's half-ulp
      val sigBits = if (k - 1 >= m) 0L else ((randFrac() >> k) << k) | (1L << (k - 1))
      (a, bits(randSign(), eb, sigBits))
    }
  }

  /** Exact representation of (-1)^neg * odd * 2^e2 (odd < 2^(m+1)), normal or subnormal; None if out of range. */
  def fromExact(neg: Boolean, odd: Long, e2: Int): Option[Long] = {
    val bl = 64 - java.lang.Long.numberOfLeadingZeros(odd)
    val lead = e2 + bl - 1
    val ef = lead + f.bias
    if (ef >= f.maxExp) None
    else if (ef >= 1) Some(bits(neg, ef, (odd << (m - (bl - 1))) & fracMask))
    else {
      val sh = e2 - (1 - f.bias - m) // position of the odd number's LSB in the subnormal grid
      if (sh < 0) None else Some(bits(neg, 0, odd << sh))
    }
  }

  /** Products whose exact value has m+2 significant bits ending in 1: a tie, at random exponents
    * (normal, subnormal and overflow ranges).
    */
  def mulTie(): (Long, Long) = {
    val p = m + 1
    var res: Option[(Long, Long)] = None
    while (res.isEmpty) {
      val ka = 2 + rnd.nextInt(p - 1) // bits of a's odd significand
      val oa = (1L << (ka - 1)) | (rnd.nextLong() & ((1L << (ka - 1)) - 1)) | 1L
      val lo = ((1L << p) + oa - 1) / oa
      val hi = ((1L << (p + 1)) - 1) / oa
      if (hi >= lo) {
        var ob = lo + (if (hi > lo) (rnd.nextLong() & Long.MaxValue) % (hi - lo + 1) else 0L)
        if ((ob & 1) == 0) ob = if (ob + 1 <= hi) ob + 1 else ob - 1
        if (ob >= lo && ob <= hi && (ob & 1) == 1 && ob < (1L << p)) {
          val ea = rnd.nextInt(2 * f.bias + 2 * m) - f.bias - m
          val eb = rnd.nextInt(2 * f.bias + 2 * m) - f.bias - m
          for (a <- fromExact(randSign(), oa, ea); b <- fromExact(randSign(), ob, eb)) res = Some((a, b))
        }
      }
    }
    res.get
  }

  /** Divisions by powers of two into and around the subnormal range (exact ties and inexact rounding),
    * and products/quotients near the overflow threshold.
    */
  def rangeEdge(): (Long, Long) = rnd.nextInt(5) match {
    case 4 => // product just below/above the smallest normal: may round up from subnormal to normal
      val ea = 1 + rnd.nextInt(f.bias - 1)
      (bits(randSign(), ea, fracMask - rnd.nextInt(3)), bits(randSign(), f.bias - ea, rnd.nextInt(3).toLong))
    case 0 => // a / 2^k landing in the subnormal range (all-ones a: ties that round up to the smallest normal)
      val ea = math.min(1 + rnd.nextInt(m + 3), f.maxExp - 1)
      val a = if (rnd.nextBoolean()) bits(randSign(), ea, fracMask) else finiteWithExp(ea)
      val k = 1 + rnd.nextInt(m + 4)
      (a, bits(randSign(), math.min(f.bias + k, f.maxExp - 1), 0))
    case 1 => // a * 2^-k into subnormals, or b tiny
      val a = finiteWithExp(math.min(1 + rnd.nextInt(m + 3), f.maxExp - 1))
      val k = 1 + rnd.nextInt(m + 4)
      (a, bits(randSign(), math.max(f.bias - k, 0), if (rnd.nextBoolean()) 0L else randFrac()))
    case 2 => // near overflow: large * slightly-above/below one
      val a = finiteWithExp(f.maxExp - 1 - rnd.nextInt(3))
      (a, bits(randSign(), f.bias - rnd.nextInt(2), if (rnd.nextBoolean()) rnd.nextInt(4).toLong else fracMask - rnd.nextInt(4)))
    case _ => // all-ones significand times (1 + few ulps): rounds into the next binade
      (bits(randSign(), 1 + rnd.nextInt(f.maxExp - 1), fracMask - rnd.nextInt(3)), bits(randSign(), f.bias, rnd.nextInt(4).toLong))
  }

  /** The random mix used by the million-pair runs. */
  def mixed(): (Long, Long) = rnd.nextInt(20) match {
    case 0 | 1 | 2 | 3 | 4 | 5 | 6 | 7 => (uniform(), uniform())
    case 8 | 9 | 10 | 11 | 12 => nearby()
    case 13 | 14 => cancel()
    case 15 => addTie()
    case 16 => mulTie()
    case 17 => rangeEdge()
    case 18 => (randomEdge(), uniform())
    case _ => (uniform(), randomEdge())
  }

  /** Every ordered pair of edge values. */
  def edgePairs: IndexedSeq[(Long, Long)] = for (a <- edges; b <- edges) yield (a, b)
}
