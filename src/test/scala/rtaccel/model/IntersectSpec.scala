package rtaccel.model

import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

class IntersectSpec extends AnyFunSuite {
  private val Inf = Float.PositiveInfinity
  private def ray(o: (Float, Float, Float), d: (Float, Float, Float), tmin: Float = 0f, tmax: Float = Inf) =
    new PreparedRay(o._1, o._2, o._3, d._1, d._2, d._3, tmin, tmax)
  private def box(r: PreparedRay, lo: Float = 0f, hi: Float = 1f) = RayBox.test(r, r.tmax, lo, lo, lo, hi, hi, hi)
  private def tri(r: PreparedRay, c: Array[Float]) = { val o = new RayTriangle.Result; (RayTriangle.test(r, r.tmax, c, o), o) }
  private val unit = Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f)

  test("axis-parallel rays: exact entry distance, and ±0 direction components behave the same") {
    assert(box(ray((-1f, 0.5f, 0.5f), (1f, 0f, 0f))) == 1f)
    assert(box(ray((-1f, 0.5f, 0.5f), (1f, -0f, -0f))) == 1f)
    assert(box(ray((0.5f, 0.5f, 3f), (-0f, 0f, -2f))) == 1f)
    assert(box(ray((-1f, 2f, 0.5f), (1f, 0f, 0f))).isNaN, "parallel ray outside the y slab must miss")
  }

  test("a ray lying in a slab plane (0*inf = NaN) is unconstrained on that axis, not a NaN leak") {
    for (y <- Seq(0f, 1f); dz <- Seq(0f, -0f)) {
      val t = box(ray((-1f, y, 0.5f), (1f, 0f, dz)))
      assert(t == 1f, s"ray along the face y=$y, dz=$dz")
    }
    assert(box(ray((-1f, Math.nextDown(0f), 0.5f), (1f, 0f, 0f))).isNaN)
  }

  test("origin inside the box enters at tmin; boxes behind the ray or beyond tmax miss") {
    assert(box(ray((0.5f, 0.5f, 0.5f), (0.3f, -0.2f, 0.9f), tmin = 0.125f)) == 0.125f)
    assert(box(ray((2f, 0.5f, 0.5f), (1f, 0f, 0f))).isNaN)
    assert(box(ray((-1f, 0.5f, 0.5f), (1f, 0f, 0f), tmax = 0.5f)).isNaN)
    assert(box(ray((-1f, 0.5f, 0.5f), (1f, 0f, 0f), tmax = 1f)) == 1f, "tmax is inclusive for boxes")
  }

  test("flat (zero-thickness) boxes are hit") {
    val r = ray((0.5f, 0.5f, 2f), (0f, 0f, -1f))
    assert(RayBox.test(r, Inf, 0f, 0f, 1f, 1f, 1f, 1f) == 1f)
  }

  test("random boxes: agrees with a float64 slab test wherever that one has a margin; never NaN on a hit") {
    val rnd = new Random(11)
    def f(): Float = rnd.nextInt(8) match {
      case 0 => 0f; case 1 => -0f; case 2 => Float.MinPositiveValue; case _ => (rnd.nextFloat() - 0.5f) * 8
    }
    var checked = 0
    for (_ <- 0 until 200000) {
      val o = Array.fill(3)((rnd.nextFloat() - 0.5f) * 8); val d = Array.fill(3)(f())
      if (d.exists(_ != 0f)) {
        val a = Array.fill(3)((rnd.nextFloat() - 0.5f) * 4); val b = Array.fill(3)((rnd.nextFloat() - 0.5f) * 4)
        val lo = a.zip(b).map(p => math.min(p._1, p._2)); val hi = a.zip(b).map(p => math.max(p._1, p._2))
        val r = new PreparedRay(o(0), o(1), o(2), d(0), d(1), d(2), 0f, Inf)
        val t = RayBox.test(r, Inf, lo(0), lo(1), lo(2), hi(0), hi(1), hi(2))
        // float64 reference interval
        var tn = 0.0; var tf = Double.PositiveInfinity; var clear = true
        for (k <- 0 until 3) {
          if (d(k) == 0f) { if (o(k) < lo(k) || o(k) > hi(k)) tf = -1.0 ; if (o(k) == lo(k) || o(k) == hi(k)) clear = false }
          else {
            val t0 = (lo(k).toDouble - o(k)) / d(k); val t1 = (hi(k).toDouble - o(k)) / d(k)
            tn = math.max(tn, math.min(t0, t1)); tf = math.min(tf, math.max(t0, t1))
          }
        }
        val margin = tf - tn
        if (clear && math.abs(margin) > 1e-4 * (1 + math.abs(tn)) && d.forall(x => x == 0f || math.abs(x) > 1e-30)) {
          checked += 1
          assert(!t.isNaN == (margin >= 0), s"o=${o.toSeq} d=${d.toSeq} lo=${lo.toSeq} hi=${hi.toSeq}")
        }
        if (!t.isNaN) assert(t >= 0f)
      }
    }
    assert(checked > 100000)
  }

  test("Möller–Trumbore: exact centre hit, barycentrics and t") {
    val (hit, o) = tri(ray((0.25f, 0.25f, 1f), (0f, 0f, -1f)), unit)
    assert(hit && o.t == 1f && o.u == 0.25f && o.v == 0.25f)
  }

  test("Möller–Trumbore: parallel rays, repeated vertices and collinear triangles never hit") {
    assert(!tri(ray((0.25f, 0.25f, 1f), (1f, 0f, -0f)), unit)._1)
    val repeated = Array(0f, 0f, 0f, 0f, 0f, 0f, 0f, 1f, 0f)
    val collinear = Array(0f, 0f, 0f, 1f, 0f, 0f, 2f, 0f, 0f)
    for (c <- Seq(repeated, collinear); d <- Seq((0f, 0f, -1f), (0.1f, 0.2f, -1f), (0f, 1f, 0f)))
      assert(!tri(ray((0.5f, 0.25f, 1f), d), c)._1, s"degenerate ${c.toSeq} hit along $d")
  }

  test("Möller–Trumbore: tmin/tmax window, edges and vertices of the triangle are inside") {
    assert(!tri(ray((0.25f, 0.25f, 1f), (0f, 0f, -1f), tmax = 1f), unit)._1, "t < tmax is strict")
    assert(tri(ray((0.25f, 0.25f, 1f), (0f, 0f, -1f), tmin = 1f), unit)._1, "t >= tmin is inclusive")
    for ((x, y) <- Seq((0f, 0f), (1f, 0f), (0f, 1f), (0.5f, 0f), (0f, 0.5f), (0.5f, 0.5f)))
      assert(tri(ray((x, y, 1f), (0f, 0f, -1f)), unit)._1, s"point ($x,$y) on the boundary")
  }

  test("needle triangles: hits agree with a float64 test away from the thin edges") {
    val rnd = new Random(5)
    for (_ <- 0 until 20000) {
      val w = math.pow(10, -rnd.nextInt(6)).toFloat
      val c = Array(0f, 0f, 0f, 1000f, 0f, 0f, 0f, w, 0f)
      val x = rnd.nextFloat() * 1000f; val y = rnd.nextFloat() * w
      val (hit, o) = tri(ray((x, y, 5f), (0f, 0f, -1f)), c)
      val inside = y / w.toDouble + x / 1000.0 // barycentric sum in float64
      // t of a needle is a ratio of tiny products: allow a few ulps, not a wrong answer
      if (inside < 0.999 && y > 0.001 * w && x > 0.001f) assert(hit && math.abs(o.t - 5f) <= 4 * Math.ulp(5f), s"x=$x y=$y w=$w t=${o.t}")
      if (inside > 1.001) assert(!hit)
    }
  }

  test("overflowing coordinates give a miss, never a NaN hit") {
    val big = unit.map(_ * 1e30f)
    val (hit, _) = tri(ray((0.25e30f, 0.25e30f, 1e30f), (0f, 0f, -1f)), big)
    assert(!hit)
  }
}
