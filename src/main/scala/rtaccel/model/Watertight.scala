package rtaccel.model

/** The watertight ray-triangle test of Woop, Benthin and Wald (JCGT 2013), TRI_TEST=watertight, in the order
  * and rounding of rtaccel.iu.WatertightPipe (docs/numerics.md, "The watertight triangle test"):
  *   shear: kz = the axis of the largest |d| (ties to x, then y; compared on magnitude bits), kx = kz+1, ky = kx+1
  *          (mod 3); Sz = 1/d[kz] (the ray's reciprocal), Sx = d[kx]*Sz, Sy = d[ky]*Sz;
  *   A, B, C = v0-o, v1-o, v2-o;  Ax = A[kx] - Sx*A[kz], Ay = A[ky] - Sy*A[kz], Az = Sz*A[kz] (B, C alike);
  *   U = Cx*By - Cy*Bx, V = Ax*Cy - Ay*Cx, W = Bx*Ay - By*Ax;
  *   an edge function that is exactly 0 is recomputed from the same operands in binary64, where both products are
  *   exact, then rounded to binary32 (nearest even);
  *   miss if the three have mixed signs (some < 0 and some > 0; zeros accept both sides);
  *   det = (U+V)+W, miss if 0; T = (U*Az + V*Bz) + W*Cz; r = 1/det; t = T*r, u = V*r, v = W*r;
  *   hit iff tmin <= t < tmax (false on NaN, as in Möller–Trumbore).
  * u and v are the weights of v1 and v2, as Möller–Trumbore's. The edge function of a shared edge is computed from
  * the same two sheared vertices in both triangles, with the operands swapped, so it is exactly negated; and its
  * binary32 sign is either the exact sign or 0, which the binary64 recomputation resolves. A ray through a closed
  * mesh therefore finds a triangle whose three signs agree: no leak through shared edges and vertices.
  */
final class RayTriangleWatertight {
  // the sheared vertices A, B, C as (x, y, z) each; per instance so a test allocates nothing
  private val sv = new Array[Float](9)

  @inline private def mag(x: Float): Int = java.lang.Float.floatToRawIntBits(x) & 0x7fffffff
  @inline private def pick(a: Int, x: Float, y: Float, z: Float): Float = if (a == 0) x else if (a == 1) y else z
  /** a*b - c*d, recomputed exactly in binary64 when binary32 gives 0 (the sign is then exact). */
  @inline private def edge(a: Float, b: Float, c: Float, d: Float): Float = {
    val e = a * b - c * d
    if (e != 0f) e else (a.toDouble * b.toDouble - c.toDouble * d.toDouble).toFloat
  }

  def test(r: PreparedRay, tmax: Float, c: Int => Float, out: RayTriangle.Result): Boolean =
    test(r, tmax, c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), c(8), out)

  /** The same test on v0 = (ax, ay, az), v1 = (bx, by, bz), v2 = (cx, cy, cz), as the traversal reads them. */
  def test(r: PreparedRay, tmax: Float, ax0: Float, ay0: Float, az0: Float, bx0: Float, by0: Float, bz0: Float,
           cx0: Float, cy0: Float, cz0: Float, out: RayTriangle.Result): Boolean = {
    val mx = mag(r.dx); val my = mag(r.dy); val mz = mag(r.dz)
    val kz = if (mx >= my && mx >= mz) 0 else if (my >= mz) 1 else 2
    val kx = (kz + 1) % 3; val ky = (kx + 1) % 3
    val sz = pick(kz, r.ix, r.iy, r.iz)
    val sx = pick(kx, r.dx, r.dy, r.dz) * sz; val sy = pick(ky, r.dx, r.dy, r.dz) * sz
    // vertex v relative to the origin, sheared into sv(3v .. 3v+2)
    def shear(v: Int, x: Float, y: Float, z: Float): Unit = {
      val px = x - r.ox; val py = y - r.oy; val pz = z - r.oz
      val k = pick(kz, px, py, pz)
      sv(3 * v) = pick(kx, px, py, pz) - sx * k; sv(3 * v + 1) = pick(ky, px, py, pz) - sy * k; sv(3 * v + 2) = sz * k
    }
    shear(0, ax0, ay0, az0); shear(1, bx0, by0, bz0); shear(2, cx0, cy0, cz0)
    val ax = sv(0); val ay = sv(1); val az = sv(2); val bx = sv(3); val by = sv(4); val bz = sv(5)
    val cx = sv(6); val cy = sv(7); val cz = sv(8)
    val eu = edge(cx, by, cy, bx); val ev = edge(ax, cy, ay, cx); val ew = edge(bx, ay, by, ax)
    val mixed = (eu < 0f || ev < 0f || ew < 0f) && (eu > 0f || ev > 0f || ew > 0f)
    val det = (eu + ev) + ew
    val tt = (eu * az + ev * bz) + ew * cz
    val rcp = 1f / det
    val t = tt * rcp
    val hit = !mixed && det != 0f && t >= r.tmin && t < tmax
    if (hit) { out.t = t; out.u = ev * rcp; out.v = ew * rcp }
    hit
  }
}
