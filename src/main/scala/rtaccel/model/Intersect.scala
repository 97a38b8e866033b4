package rtaccel.model

import Fp32._

/** A ray prepared for the intersection unit: origin, direction and the reciprocal direction computed
  * once per ray (1/±0 = ±inf, so axis-parallel rays need no special case).
  * The traversal reuses one instance ray after ray (`set`, no allocation per ray): every per-ray value is
  * a var that `set` computes, and the constructor calls `set`; a new per-ray value belongs there too.
  */
final class PreparedRay private (var ox: Float, var oy: Float, var oz: Float, var dx: Float, var dy: Float, var dz: Float,
                                 var tmin: Float, var tmax: Float, var ix: Float, var iy: Float, var iz: Float) {
  def this(ox: Float, oy: Float, oz: Float, dx: Float, dy: Float, dz: Float, tmin: Float, tmax: Float) =
    this(ox, oy, oz, dx, dy, dz, tmin, tmax, 1f / dx, 1f / dy, 1f / dz)
  def set(ox: Float, oy: Float, oz: Float, dx: Float, dy: Float, dz: Float, tmin: Float, tmax: Float): this.type = {
    this.ox = ox; this.oy = oy; this.oz = oz; this.dx = dx; this.dy = dy; this.dz = dz; this.tmin = tmin; this.tmax = tmax
    ix = 1f / dx; iy = 1f / dy; iz = 1f / dz
    this
  }
  /** Ray i of `rays` (its 8 floats from offset 8i). */
  def set(rays: Array[Float], i: Int): this.type = {
    val b = 8 * i
    set(rays(b), rays(b + 1), rays(b + 2), rays(b + 3), rays(b + 4), rays(b + 5), rays(b + 6), rays(b + 7))
  }
  /** No slab-test operand can be NaN for this ray on NaN-free box words (RayBox.testRegular): the origin is
    * finite, each reciprocal direction finite and nonzero, tmin and tmax not NaN. Then (p - o) * inv is NaN
    * only for a NaN p.
    */
  def regular: Boolean = finite(ox) && finite(oy) && finite(oz) && finite(ix) && finite(iy) && finite(iz) &&
    ix != 0f && iy != 0f && iz != 0f && !tmin.isNaN && !tmax.isNaN
  private def finite(x: Float): Boolean = java.lang.Float.isFinite(x)
}

/** Ray-box slab test. Per axis t0=(min-o)*inv, t1=(max-o)*inv, lo/hi by NaN-propagating min/max; then
  * tnear = max(max(max(tmin, lo.x), lo.y), lo.z) and tfar = min(min(min(tmax, hi.x), hi.y), hi.z) with NaN
  * ignored, so a ray lying in a slab plane (0*inf) is unconstrained on that axis instead of leaking NaN.
  * Hit iff tnear <= tfar; the entry distance tnear orders the children.
  */
object RayBox {
  /** Returns tnear on a hit, NaN on a miss. `slack`: ulps added to tfar before the comparison (BoxSlack). */
  def test(r: PreparedRay, tmax: Float, mnx: Float, mny: Float, mnz: Float, mxx: Float, mxy: Float, mxz: Float,
           slack: Int = 0): Float = {
    val t0x = (mnx - r.ox) * r.ix; val t1x = (mxx - r.ox) * r.ix
    val t0y = (mny - r.oy) * r.iy; val t1y = (mxy - r.oy) * r.iy
    val t0z = (mnz - r.oz) * r.iz; val t1z = (mxz - r.oz) * r.iz
    val tnear = maxNum(maxNum(maxNum(r.tmin, minProp(t0x, t1x)), minProp(t0y, t1y)), minProp(t0z, t1z))
    val tfar = minNum(minNum(minNum(tmax, maxProp(t0x, t1x)), maxProp(t0y, t1y)), maxProp(t0z, t1z))
    if (tnear <= (if (slack == 0) tfar else BoxSlack.up32(tfar, slack))) tnear else Float.NaN
  }

  /** `test`, bit for bit, when no operand is NaN: a `regular` ray (PreparedRay) against box words none of
    * which is NaN, with tmax not NaN; the traversal's fast path. Without NaN every min/max of `test` is a plain
    * compare-select, which as a value is Math.min/max: those compile to branch-free instructions where the
    * compare-select is a data-dependent (often mispredicted) branch. The two differ only in the sign of a zero
    * (the compare-select returns the second operand on -0 vs +0), so only a zero tnear needs the compare-selects
    * to give its sign; tfar is only compared.
    */
  def testRegular(r: PreparedRay, tmax: Float, mnx: Float, mny: Float, mnz: Float, mxx: Float, mxy: Float, mxz: Float): Float = {
    val t0x = (mnx - r.ox) * r.ix; val t1x = (mxx - r.ox) * r.ix
    val t0y = (mny - r.oy) * r.iy; val t1y = (mxy - r.oy) * r.iy
    val t0z = (mnz - r.oz) * r.iz; val t1z = (mxz - r.oz) * r.iz
    val tnear = Math.max(Math.max(Math.max(r.tmin, Math.min(t0x, t1x)), Math.min(t0y, t1y)), Math.min(t0z, t1z))
    val tfar = Math.min(Math.min(Math.min(tmax, Math.max(t0x, t1x)), Math.max(t0y, t1y)), Math.max(t0z, t1z))
    if (!(tnear <= tfar)) Float.NaN
    else if (tnear != 0f) tnear
    else max(max(max(r.tmin, min(t0x, t1x)), min(t0y, t1y)), min(t0z, t1z))
  }
  // minNum/minProp and maxNum/maxProp (Fp32) on operands that are not NaN
  @inline private def min(a: Float, b: Float): Float = if (a < b) a else b
  @inline private def max(a: Float, b: Float): Float = if (a > b) a else b
}

/** The box test's slack (PlatformParams.boxSlackUlps, TRI_TEST=watertight): tfar moved `k` ulps toward +inf on
  * its raw bits (a positive value grows up to +inf, a negative one shrinks toward zero and past it, counting -0 and
  * +0 as one point; NaN and +inf stay).
  */
object BoxSlack {
  def up(f: rtaccel.fp.FpFormat, bits: Long, k: Int): Long = {
    val magMask = (1L << (f.width - 1)) - 1; val inf = f.maxExp.toLong << f.manBits
    val mag = bits & magMask; val neg = (bits >>> (f.width - 1)) == 1
    if (mag > inf) bits // NaN
    else if (!neg) math.min(mag + k, inf)
    else if (mag > k) bits - k else k - mag // across zero (-0 and +0 are one point)
  }
  def up32(x: Float, k: Int): Float =
    java.lang.Float.intBitsToFloat(up(rtaccel.fp.FpFormat.fp32, java.lang.Float.floatToRawIntBits(x) & 0xffffffffL, k).toInt)
}

/** Möller–Trumbore (as in the paper), in this order:
  *   e1=v1-v0, e2=v2-v0, p=d x e2, det=e1.p, inv=1/det, s=o-v0, u=(s.p)*inv, q=s x e1, v=(d.q)*inv, t=(e2.q)*inv
  * Hit iff det != 0, u >= 0, v >= 0, u+v <= 1, tmin <= t < tmax; every comparison is false on NaN, so an
  * overflowed or degenerate triangle is a miss, never a bogus hit.
  */
object RayTriangle {
  final class Result { var t = 0f; var u = 0f; var v = 0f }

  def test(r: PreparedRay, tmax: Float, c: Int => Float, out: Result): Boolean =
    test(r, tmax, c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), c(8), out)

  /** The same test on the vertex coordinates v0 = (ax, ay, az), v1 = (bx, by, bz), v2 = (cx, cy, cz), as the
    * traversal reads them from the memory image (no closure per primitive read).
    */
  def test(r: PreparedRay, tmax: Float, ax: Float, ay: Float, az: Float, bx: Float, by: Float, bz: Float,
           cx: Float, cy: Float, cz: Float, out: Result): Boolean = {
    val e1x = bx - ax; val e1y = by - ay; val e1z = bz - az
    val e2x = cx - ax; val e2y = cy - ay; val e2z = cz - az
    val px = crossX(r.dy, r.dz, e2y, e2z); val py = crossY(r.dx, r.dz, e2x, e2z); val pz = crossZ(r.dx, r.dy, e2x, e2y)
    val det = dot(e1x, e1y, e1z, px, py, pz)
    val inv = 1f / det
    val sx = r.ox - ax; val sy = r.oy - ay; val sz = r.oz - az
    val u = dot(sx, sy, sz, px, py, pz) * inv
    val qx = crossX(sy, sz, e1y, e1z); val qy = crossY(sx, sz, e1x, e1z); val qz = crossZ(sx, sy, e1x, e1y)
    val v = dot(r.dx, r.dy, r.dz, qx, qy, qz) * inv
    val t = dot(e2x, e2y, e2z, qx, qy, qz) * inv
    val hit = det != 0f && u >= 0f && v >= 0f && u + v <= 1f && t >= r.tmin && t < tmax
    if (hit) { out.t = t; out.u = u; out.v = v }
    hit
  }
}

/** The conservative slab test in a format narrower than fp32 (BOX_FORMAT=, BoxPipe's outward path), as the
  * hardware computes it, one SoftFloat operation per hardware operation (docs/numerics.md):
  *   d = min - o rounded down, max - o rounded up (fp32 operands, result in the narrow format);
  *   1/d converted down and up; each plane's t = d * (1/d at the bound that keeps the product on its side),
  *   rounded down where it bounds an entry (a min plane with 1/d >= 0, a max plane with 1/d < 0), else up;
  *   tmin rounded down, tmax up; then the fp32 test's min/max, chains and comparison in the narrow format.
  * A box the exact ray meets is never rejected. Returns tnear (widened to fp32, exactly) on a hit, NaN on a miss.
  */
final class RayBoxOutward(bf: rtaccel.fp.FpFormat, slack: Int = 0) {
  import rtaccel.fp.{FpFormat, SoftFloat}
  import SoftFloat.{Down, Up}
  private val s32 = new SoftFloat(FpFormat.fp32); private val sb = new SoftFloat(bf)
  private val signShift = bf.width - 1
  private def bits(x: Float): Long = java.lang.Float.floatToRawIntBits(x) & 0xffffffffL

  def test(r: PreparedRay, tmax: Float, mnx: Float, mny: Float, mnz: Float, mxx: Float, mxy: Float, mxz: Float): Float = {
    val mn = Array(mnx, mny, mnz); val mx = Array(mxx, mxy, mxz)
    val o = Array(r.ox, r.oy, r.oz); val inv = Array(r.ix, r.iy, r.iz)
    var tnear = sb.convertFrom(s32, bits(r.tmin), Down)
    var tfar = sb.convertFrom(s32, bits(tmax), Up)
    var a = 0
    while (a < 3) {
      val invBits = bits(inv(a)); val invNeg = (invBits >>> 31) == 1
      val invLo = sb.convertFrom(s32, invBits, Down); val invHi = sb.convertFrom(s32, invBits, Up)
      def plane(p: Float, isMax: Boolean): Long = {
        val d = sb.subFrom(s32, bits(p), bits(o(a)), if (isMax) Up else Down)
        val up = if (isMax) !invNeg else invNeg
        val useHi = (((d >>> signShift) & 1) == 1) ^ up
        sb.mul(d, if (useHi) invHi else invLo, if (up) Up else Down)
      }
      val t0 = plane(mn(a), isMax = false); val t1 = plane(mx(a), isMax = true)
      tnear = sb.maxNum(tnear, sb.minProp(t0, t1))
      tfar = sb.minNum(tfar, sb.maxProp(t0, t1))
      a += 1
    }
    if (sb.le(tnear, BoxSlack.up(bf, tfar, slack))) java.lang.Float.intBitsToFloat(s32.convertFrom(sb, tnear, Down).toInt) else Float.NaN
  }
}
