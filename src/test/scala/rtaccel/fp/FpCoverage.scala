package rtaccel.fp

import java.lang.Float.intBitsToFloat

/** Counts how often the fp32 operand stream hits the rounding edge classes, judged with float64 arithmetic
  * (exact for fp32 products and for sums of operands with nearby exponents; for quotients exact where it
  * matters here, i.e. division by powers of two). Used to assert that the test streams exercise each class.
  */
final class FpCoverage32 {
  val names: IndexedSeq[String] = IndexedSeq("tie", "tieUp", "subnormalResult", "overflowToInf", "underflowToZero",
    "roundUpNextBinade", "subnormalToNormal", "exactZero", "nanResult")
  /** counts(op)(class) for the four arithmetic ops */
  val counts: Array[Array[Long]] = Array.fill(4, names.length)(0L)

  def add(op: Int, a: Long, b: Long): Unit = {
    val x = intBitsToFloat(a.toInt); val y = intBitsToFloat(b.toInt)
    val (r, d) = op match {
      case 0 => (x + y, x.toDouble + y.toDouble)
      case 1 => (x - y, x.toDouble - y.toDouble)
      case 2 => (x * y, x.toDouble * y.toDouble)
      case _ => (x / y, x.toDouble / y.toDouble)
    }
    val c = counts(op)
    if (r.isNaN) { c(8) += 1; return }
    if (x.isInfinite || y.isInfinite || x.isNaN || y.isNaN || d.isNaN) return
    if (r.isInfinite) { if (!d.isInfinite) c(3) += 1; return }
    val rd = r.toDouble
    if (r == 0f) { if (d != 0.0) c(4) += 1 else c(7) += 1; return }
    val ar = math.abs(r)
    if (ar < java.lang.Float.MIN_NORMAL) c(2) += 1
    if (d != rd) {
      val up = Math.nextUp(r).toDouble; val dn = Math.nextDown(r).toDouble
      val tie = (!up.isInfinite && d == (rd + up) / 2) || (!dn.isInfinite && d == (rd + dn) / 2)
      if (tie) { c(0) += 1; if (math.abs(d) < math.abs(rd)) c(1) += 1 }
      if (math.abs(d) < math.abs(rd)) {
        if ((java.lang.Float.floatToRawIntBits(ar) & 0x7fffff) == 0) c(5) += 1
        if (ar == java.lang.Float.MIN_NORMAL) c(6) += 1
      }
    }
  }

  def report: String = (0 until 4).map { op =>
    s"${FpOps.names(op)}: " + names.indices.map(i => s"${names(i)}=${counts(op)(i)}").mkString(" ")
  }.mkString("\n")

  /** Classes that cannot occur: a sum of floats smaller than the smallest normal is exact (every float is a
    * multiple of the smallest subnormal), so add/sub never underflow to zero nor round up to the smallest
    * normal. (Division can: (2^24-1)*2^k / 2^(k+150) is a tie between the largest subnormal and the smallest
    * normal, which rounds up to the even one.)
    */
  private val impossible = Set((0, 4), (0, 6), (1, 4), (1, 6))

  /** Possible classes the stream never hit. */
  def missing: Seq[String] = for {
    op <- 0 until 4
    i <- names.indices
    if counts(op)(i) == 0 && !impossible((op, i))
  } yield s"${FpOps.names(op)}.${names(i)}"
}
