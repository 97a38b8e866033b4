package rtaccel.model

/** The reference model's arithmetic, written as the hardware datapath computes it: every operation is one
  * IEEE binary32 operation rounded to nearest-even (Java float arithmetic; no fused multiply-add), subnormals
  * kept, evaluated in the fixed order below. The RTL's floating-point units mirror each function here.
  */
object Fp32 {
  /** (a.x*b.x + a.y*b.y) + a.z*b.z: three multiplies, then a two-level adder tree. */
  @inline def dot(ax: Float, ay: Float, az: Float, bx: Float, by: Float, bz: Float): Float = {
    val p0 = ax * bx; val p1 = ay * by; val p2 = az * bz
    (p0 + p1) + p2
  }
  /** Components of a x b, each as a.i*b.j - a.j*b.i. */
  @inline def crossX(ay: Float, az: Float, by: Float, bz: Float): Float = ay * bz - az * by
  @inline def crossY(ax: Float, az: Float, bx: Float, bz: Float): Float = az * bx - ax * bz
  @inline def crossZ(ax: Float, ay: Float, bx: Float, by: Float): Float = ax * by - ay * bx

  /** Comparator-select min/max that ignore a NaN operand (IEEE 754-2008 minNum/maxNum); on equal
    * operands (including -0 vs +0) the second is returned.
    */
  @inline def minNum(a: Float, b: Float): Float = if (a.isNaN) b else if (b.isNaN) a else if (a < b) a else b
  @inline def maxNum(a: Float, b: Float): Float = if (a.isNaN) b else if (b.isNaN) a else if (a > b) a else b
  /** Min/max that propagate NaN (a slab whose t is 0*inf has no bound on that axis). */
  @inline def minProp(a: Float, b: Float): Float = if (a.isNaN || b.isNaN) Float.NaN else if (a < b) a else b
  @inline def maxProp(a: Float, b: Float): Float = if (a.isNaN || b.isNaN) Float.NaN else if (a > b) a else b
}
