package rtaccel.model

import rtaccel.fp.{FpFormat, SoftFloat}

/** Möller–Trumbore in the format TRI_FORMAT names (rtaccel.iu.TriPipe with p.triFormat), one SoftFloat operation per
  * operation of the pipe, in its order, each rounded to nearest even in `tf`:
  *   the fp32 inputs widened exactly; e1 = v1-v0, e2 = v2-v0, s = o-v0; p = d x e2, q = s x e1 (a.i*b.j - a.j*b.i);
  *   det = (e1.x*p.x + e1.y*p.y) + e1.z*p.z, u' = s.p, v' = d.q, t' = e2.q alike; inv = 1/det;
  *   u = u'*inv, v = v'*inv, t = t'*inv; hit iff det != 0, u >= 0, v >= 0, u+v <= 1, tmin <= t < tmax, all in tf;
  *   then t, u, v rounded to fp32 (nearest even) into `out`.
  * At fp32 this is RayTriangle.test bit for bit (model tests check it); the traversal takes RayTriangle there.
  * fp64 takes `testDouble`, the same operations in Java double (IEEE binary64, nearest even, subnormals kept): equal
  * to `testSoft` in every hit and its t, u, v (only NaN payloads differ, and a NaN never passes a comparison; a
  * model test checks it), and fast enough for whole scenes.
  * `test` is the pipe's own answer: the TU then keeps a hit only if its fp32 t is below the ray's tmax
  * (tu.TraversalUnit), which a wider t can fail after rounding up to tmax (Traversal applies that too).
  */
final class RayTriangleWide(val tf: FpFormat) {
  private val s32 = new SoftFloat(FpFormat.fp32); private val sf = new SoftFloat(tf)
  private val one = BigInt(tf.bias).toLong << tf.manBits
  private def w(x: Float): Long = sf.convertFrom(s32, java.lang.Float.floatToRawIntBits(x) & 0xffffffffL, SoftFloat.Nearest)
  private def n(x: Long): Float = java.lang.Float.intBitsToFloat(s32.convertFrom(sf, x, SoftFloat.Nearest).toInt)
  private def dot(a0: Long, a1: Long, a2: Long, b0: Long, b1: Long, b2: Long): Long =
    sf.add(sf.add(sf.mul(a0, b0), sf.mul(a1, b1)), sf.mul(a2, b2))

  def test(r: PreparedRay, tmax: Float, c: Int => Float, out: RayTriangle.Result): Boolean =
    test(r, tmax, c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), c(8), out)

  private val fp64 = tf == FpFormat.fp64
  def test(r: PreparedRay, tmax: Float, ax: Float, ay: Float, az: Float, bx: Float, by: Float, bz: Float,
           cx: Float, cy: Float, cz: Float, out: RayTriangle.Result): Boolean =
    if (fp64) RayTriangleWide.testDouble(r, tmax, ax, ay, az, bx, by, bz, cx, cy, cz, out)
    else testSoft(r, tmax, ax, ay, az, bx, by, bz, cx, cy, cz, out)

  def testSoft(r: PreparedRay, tmax: Float, ax: Float, ay: Float, az: Float, bx: Float, by: Float, bz: Float,
               cx: Float, cy: Float, cz: Float, out: RayTriangle.Result): Boolean = {
    val v0x = w(ax); val v0y = w(ay); val v0z = w(az)
    val e1x = sf.sub(w(bx), v0x); val e1y = sf.sub(w(by), v0y); val e1z = sf.sub(w(bz), v0z)
    val e2x = sf.sub(w(cx), v0x); val e2y = sf.sub(w(cy), v0y); val e2z = sf.sub(w(cz), v0z)
    val sx = sf.sub(w(r.ox), v0x); val sy = sf.sub(w(r.oy), v0y); val sz = sf.sub(w(r.oz), v0z)
    val dx = w(r.dx); val dy = w(r.dy); val dz = w(r.dz)
    val px = sf.sub(sf.mul(dy, e2z), sf.mul(dz, e2y)); val py = sf.sub(sf.mul(dz, e2x), sf.mul(dx, e2z))
    val pz = sf.sub(sf.mul(dx, e2y), sf.mul(dy, e2x))
    val qx = sf.sub(sf.mul(sy, e1z), sf.mul(sz, e1y)); val qy = sf.sub(sf.mul(sz, e1x), sf.mul(sx, e1z))
    val qz = sf.sub(sf.mul(sx, e1y), sf.mul(sy, e1x))
    val det = dot(e1x, e1y, e1z, px, py, pz)
    val inv = sf.div(one, det)
    val u = sf.mul(dot(sx, sy, sz, px, py, pz), inv)
    val v = sf.mul(dot(dx, dy, dz, qx, qy, qz), inv)
    val t = sf.mul(dot(e2x, e2y, e2z, qx, qy, qz), inv)
    val hit = !sf.eq(det, 0L) && sf.ge(u, 0L) && sf.ge(v, 0L) && sf.le(sf.add(u, v), one) && sf.ge(t, w(r.tmin)) && sf.lt(t, w(tmax))
    if (hit) { out.t = n(t); out.u = n(u); out.v = n(v) }
    hit
  }
}

object RayTriangleWide {
  /** testSoft at fp64, in Java double (see the class). */
  def testDouble(r: PreparedRay, tmax: Float, ax: Float, ay: Float, az: Float, bx: Float, by: Float, bz: Float,
                 cx: Float, cy: Float, cz: Float, out: RayTriangle.Result): Boolean = {
    val v0x = ax.toDouble; val v0y = ay.toDouble; val v0z = az.toDouble
    val e1x = bx - v0x; val e1y = by - v0y; val e1z = bz - v0z
    val e2x = cx - v0x; val e2y = cy - v0y; val e2z = cz - v0z
    val sx = r.ox - v0x; val sy = r.oy - v0y; val sz = r.oz - v0z
    val dx = r.dx.toDouble; val dy = r.dy.toDouble; val dz = r.dz.toDouble
    val px = dy * e2z - dz * e2y; val py = dz * e2x - dx * e2z; val pz = dx * e2y - dy * e2x
    val qx = sy * e1z - sz * e1y; val qy = sz * e1x - sx * e1z; val qz = sx * e1y - sy * e1x
    val det = (e1x * px + e1y * py) + e1z * pz
    val inv = 1.0 / det
    val u = ((sx * px + sy * py) + sz * pz) * inv
    val v = ((dx * qx + dy * qy) + dz * qz) * inv
    val t = ((e2x * qx + e2y * qy) + e2z * qz) * inv
    val hit = det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= r.tmin && t < tmax
    if (hit) { out.t = t.toFloat; out.u = u.toFloat; out.v = v.toFloat }
    hit
  }
}
