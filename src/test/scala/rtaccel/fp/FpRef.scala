package rtaccel.fp

import java.lang.Float.{floatToRawIntBits, intBitsToFloat}
import rtaccel.model.Fp32

/** The operations under test, in a fixed order (index = position). Compare ops give 0/1. */
object FpOps {
  val names: IndexedSeq[String] =
    IndexedSeq("add", "sub", "mul", "div", "minNum", "maxNum", "minProp", "maxProp", "lt", "le", "gt", "ge", "eq")
  val numValueOps = 8 // ops 0..7 return a float, 8..12 a Bool
  val n: Int = names.length
  def isArith(op: Int): Boolean = op < 4
}

/** Expected results. */
object FpRef {
  private val canonical32 = 0x7fc00000L

  /** Java float (fp32). Where Java's arithmetic result is NaN the expectation is the canonical NaN: the payload
    * of a NaN produced by Java/the CPU is platform dependent (x86 gives 0xFFC00000 for invalid operations and
    * propagates input payloads), while the RTL always produces f.canonicalNaN. min/max are compared bit for bit
    * against rtaccel.model.Fp32 (they select an operand, or return Float.NaN = 0x7FC00000).
    */
  def java32(op: Int, a: Long, b: Long): Long = {
    val x = intBitsToFloat(a.toInt)
    val y = intBitsToFloat(b.toInt)
    @inline def arith(r: Float): Long = if (r.isNaN) canonical32 else floatToRawIntBits(r) & 0xffffffffL
    @inline def sel(r: Float): Long = floatToRawIntBits(r) & 0xffffffffL
    @inline def bool(c: Boolean): Long = if (c) 1L else 0L
    (op: @annotation.switch) match {
      case 0 => arith(x + y)
      case 1 => arith(x - y)
      case 2 => arith(x * y)
      case 3 => arith(x / y)
      case 4 => sel(Fp32.minNum(x, y))
      case 5 => sel(Fp32.maxNum(x, y))
      case 6 => sel(Fp32.minProp(x, y))
      case 7 => sel(Fp32.maxProp(x, y))
      case 8 => bool(x < y)
      case 9 => bool(x <= y)
      case 10 => bool(x > y)
      case 11 => bool(x >= y)
      case _ => bool(x == y)
    }
  }

  /** Java double (fp64), same conventions as java32; min/max with the Fp32 reference semantics on doubles. */
  def java64(op: Int, a: Long, b: Long): Long = {
    import java.lang.Double.{doubleToRawLongBits, longBitsToDouble}
    val x = longBitsToDouble(a)
    val y = longBitsToDouble(b)
    @inline def arith(r: Double): Long = if (r.isNaN) 0x7ff8000000000000L else doubleToRawLongBits(r)
    @inline def sel(r: Double): Long = doubleToRawLongBits(r)
    @inline def bool(c: Boolean): Long = if (c) 1L else 0L
    val nan = 0x7ff8000000000000L
    (op: @annotation.switch) match {
      case 0 => arith(x + y)
      case 1 => arith(x - y)
      case 2 => arith(x * y)
      case 3 => arith(x / y)
      case 4 => if (x.isNaN) b else if (y.isNaN) a else if (x < y) a else b
      case 5 => if (x.isNaN) b else if (y.isNaN) a else if (x > y) a else b
      case 6 => if (x.isNaN || y.isNaN) nan else if (x < y) a else b
      case 7 => if (x.isNaN || y.isNaN) nan else if (x > y) a else b
      case 8 => bool(x < y)
      case 9 => bool(x <= y)
      case 10 => bool(x > y)
      case 11 => bool(x >= y)
      case _ => bool(x == y)
    }
  }

  def soft(sf: SoftFloat)(op: Int, a: Long, b: Long): Long = {
    @inline def bool(c: Boolean): Long = if (c) 1L else 0L
    (op: @annotation.switch) match {
      case 0 => sf.add(a, b)
      case 1 => sf.sub(a, b)
      case 2 => sf.mul(a, b)
      case 3 => sf.div(a, b)
      case 4 => sf.minNum(a, b)
      case 5 => sf.maxNum(a, b)
      case 6 => sf.minProp(a, b)
      case 7 => sf.maxProp(a, b)
      case 8 => bool(sf.lt(a, b))
      case 9 => bool(sf.le(a, b))
      case 10 => bool(sf.gt(a, b))
      case 11 => bool(sf.ge(a, b))
      case _ => bool(sf.eq(a, b))
    }
  }
}

/** Per-op check counters with the first few mismatches kept for the failure message. */
final class FpCheck(label: String) {
  val checked: Array[Long] = Array.fill(FpOps.n)(0L)
  val failed: Array[Long] = Array.fill(FpOps.n)(0L)
  private val firstFails = scala.collection.mutable.ArrayBuffer[String]()

  def check(op: Int, a: Long, b: Long, got: Long, want: Long): Unit = {
    checked(op) += 1
    if (got != want) {
      failed(op) += 1
      if (firstFails.length < 20)
        firstFails += f"$label ${FpOps.names(op)}%-7s a=0x$a%x b=0x$b%x got=0x$got%x want=0x$want%x"
    }
  }
  def totalFailed: Long = failed.sum
  def minChecked: Long = checked.min
  def report: String =
    FpOps.names.indices.map(i => s"${FpOps.names(i)}=${checked(i)}" + (if (failed(i) > 0) s"(FAIL ${failed(i)})" else ""))
      .mkString(s"$label checked: ", " ", "") + firstFails.mkString("\n  ", "\n  ", "")
}
