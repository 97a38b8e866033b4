package rtaccel.model

import java.math.{BigDecimal => JBig, MathContext}
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.fp.FpFormat

/** TRI_FORMAT's model (RayTriangleWide): at fp32 the SoftFloat twin is the Java float test bit for bit; at fp64 its
  * Java double path equals the twin; and its hits agree with an exact (BigDecimal) Möller–Trumbore where the case is
  * well conditioned, including scenes at 1e+-30 where fp32's determinant overflows or underflows.
  */
class TriFormatSpec extends AnyFunSuite {
  private val rnd = new Random(7)
  private val specials = Array(0f, -0f, Float.MinPositiveValue, java.lang.Float.MIN_NORMAL, Float.MaxValue,
    Float.PositiveInfinity, Float.NegativeInfinity, Float.NaN, 1e-30f, 1e30f)
  private def bits(x: Float) = java.lang.Float.floatToRawIntBits(x)
  private def ray(): (PreparedRay, Float) = {
    val o = Array.fill(3)((rnd.nextFloat() - 0.5f) * 4)
    val d = Array.fill(3)(if (rnd.nextInt(6) == 0) 0f else rnd.nextFloat() - 0.5f)
    if (d.forall(_ == 0f)) d(0) = 1f
    val tmin = if (rnd.nextInt(4) == 0) rnd.nextFloat() else 0f
    val tmax = if (rnd.nextInt(3) == 0) tmin + rnd.nextFloat() * 3 else Float.PositiveInfinity
    (new PreparedRay(o(0), o(1), o(2), d(0), d(1), d(2), tmin, tmax), tmax)
  }
  /** Random vertices with the degenerate and range classes of iu.IuPipesSpec. */
  private def tri(r: PreparedRay): Array[Float] = {
    val v = Array.fill(9)((rnd.nextFloat() - 0.5f) * 3)
    rnd.nextInt(10) match {
      case 0 => System.arraycopy(v, 0, v, 3, 3)
      case 1 => for (k <- 0 until 3) v(6 + k) = 2 * v(3 + k) - v(k)
      case 2 => for (k <- 0 until 9) v(k) *= 1e-20f
      case 3 => for (k <- 0 until 9) v(k) *= 1e13f
      case 4 => v(0) = r.ox; v(1) = r.oy; v(2) = r.oz
      case 5 => for (k <- 0 until 9) v(k) *= 1e-38f
      case 6 => v(rnd.nextInt(9)) = specials(rnd.nextInt(specials.length))
      case _ =>
    }
    v
  }
  private def same(name: String, n: Int, a: (PreparedRay, Float, Array[Float], RayTriangle.Result) => Boolean,
                   b: (PreparedRay, Float, Array[Float], RayTriangle.Result) => Boolean): Unit = {
    val oa = new RayTriangle.Result; val ob = new RayTriangle.Result
    var hits = 0
    for (i <- 0 until n) {
      val (r, tmax) = ray(); val v = tri(r)
      val ha = a(r, tmax, v, oa); val hb = b(r, tmax, v, ob)
      assert(ha == hb, s"$name: job $i hit ${ha} vs ${hb} (${v.mkString(",")})")
      if (ha) {
        hits += 1
        assert(bits(oa.t) == bits(ob.t) && bits(oa.u) == bits(ob.u) && bits(oa.v) == bits(ob.v), s"$name: job $i t/u/v bits")
      }
    }
    assert(hits > n / 50, s"$name: only $hits of $n hit")
    info(s"$hits hits of $n")
  }
  private def soft(f: FpFormat) = { val w = new RayTriangleWide(f)
    (r: PreparedRay, tmax: Float, v: Array[Float], o: RayTriangle.Result) => w.testSoft(r, tmax, v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8), o) }

  test("the SoftFloat twin at fp32 == RayTriangle (Java float), bit for bit, on 20000 random and degenerate triangles") {
    same("fp32", 20000, soft(FpFormat.fp32), (r, tmax, v, o) => RayTriangle.test(r, tmax, v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8), o))
  }

  test("fp64: the Java double path == the SoftFloat twin, bit for bit, on 20000 random and degenerate triangles") {
    same("fp64", 20000, soft(FpFormat.fp64), (r, tmax, v, o) => RayTriangleWide.testDouble(r, tmax, v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8), o))
  }

  // ---- exact reference: Cramer's rule on the fp32 inputs in BigDecimal (every sum and product exact)
  private final case class Exact(det: JBig, u: JBig, v: JBig, t: JBig)
  private val mc = new MathContext(60)
  private def exact(r: PreparedRay, c: Array[Float]): Exact = {
    def b(x: Float) = new JBig(x.toDouble)
    def sub(a: Array[JBig], o: Array[JBig]) = Array.tabulate(3)(k => a(k).subtract(o(k)))
    def cross(a: Array[JBig], q: Array[JBig]) = Array(a(1).multiply(q(2)).subtract(a(2).multiply(q(1))),
      a(2).multiply(q(0)).subtract(a(0).multiply(q(2))), a(0).multiply(q(1)).subtract(a(1).multiply(q(0))))
    def dot(a: Array[JBig], q: Array[JBig]) = a(0).multiply(q(0)).add(a(1).multiply(q(1))).add(a(2).multiply(q(2)))
    val v0 = Array(b(c(0)), b(c(1)), b(c(2)))
    val e1 = sub(Array(b(c(3)), b(c(4)), b(c(5))), v0); val e2 = sub(Array(b(c(6)), b(c(7)), b(c(8))), v0)
    val d = Array(b(r.dx), b(r.dy), b(r.dz)); val s = sub(Array(b(r.ox), b(r.oy), b(r.oz)), v0)
    val p = cross(d, e2); val q = cross(s, e1); val det = dot(e1, p)
    Exact(det, dot(s, p).divide(det, mc), dot(d, q).divide(det, mc), dot(e2, q).divide(det, mc))
  }
  /** |x - exact| within half an fp32 ulp of x (and a hair for fp64's own rounding before the final one). */
  private def closeHalfUlp(x: Float, e: JBig): Boolean =
    new JBig(x.toDouble).subtract(e).abs.compareTo(new JBig(math.ulp(x).toDouble * (0.5 + 1e-6))) <= 0

  /** A triangle around the point o + t d at barycentric (u, v), or just outside an edge; scaled by `scale`. */
  private def conditioned(scale: Float): (PreparedRay, Array[Float]) = {
    val o = Array.fill(3)((rnd.nextFloat() - 0.5f) * 4 * scale)
    val d = Array.fill(3)(rnd.nextFloat() - 0.5f)
    val t = (0.5f + rnd.nextFloat() * 8) * scale
    val inside = rnd.nextBoolean()
    val u = if (inside) 0.05f + 0.4f * rnd.nextFloat() else -0.05f - 0.4f * rnd.nextFloat()
    val v = 0.05f + 0.4f * rnd.nextFloat()
    val e1 = Array.fill(3)((rnd.nextFloat() - 0.5f) * 4 * scale); val e2 = Array.fill(3)((rnd.nextFloat() - 0.5f) * 4 * scale)
    val v0 = Array.tabulate(3)(k => o(k) + t * d(k) - u * e1(k) - v * e2(k))
    (new PreparedRay(o(0), o(1), o(2), d(0), d(1), d(2), 0f, Float.PositiveInfinity),
      Array.tabulate(9)(k => if (k < 3) v0(k) else if (k < 6) v0(k % 3) + e1(k % 3) else v0(k % 3) + e2(k % 3)))
  }

  test("fp64 agrees with exact Möller–Trumbore on 6000 well-conditioned cases, also at 1e+30 and 1e-30 where fp32 fails") {
    val w = new RayTriangleWide(FpFormat.fp64); val o = new RayTriangle.Result; val o32 = new RayTriangle.Result
    val margin = new JBig("1e-4")
    for (scale <- Seq(1f, 1e30f, 1e-30f)) {
      var checked = 0; var hits = 0; var fp32Hits = 0
      for (_ <- 0 until 2000) {
        val (r, c) = conditioned(scale)
        val ex = exact(r, c)
        val dl = new JBig(r.dx.toDouble).pow(2).add(new JBig(r.dy.toDouble).pow(2)).add(new JBig(r.dz.toDouble).pow(2))
        def len2(a: Int, b: Int) = (0 until 3).map(k => new JBig(c(b + k).toDouble - c(a + k).toDouble).pow(2)).reduce(_ add _)
        // well conditioned: det not small against |d| |e1| |e2|, every condition decided by a margin
        val detOk = ex.det.pow(2).compareTo(dl.multiply(len2(0, 3)).multiply(len2(0, 6)).multiply(new JBig("0.01"))) > 0
        val w1 = JBig.ONE.subtract(ex.u).subtract(ex.v)
        val decided = Seq(ex.u, ex.v, w1).forall(_.abs.compareTo(margin) > 0) && ex.t.compareTo(JBig.ZERO) > 0
        if (detOk && decided) {
          checked += 1
          val hitExact = ex.u.signum > 0 && ex.v.signum > 0 && w1.signum > 0
          val hit = w.testSoft(r, Float.PositiveInfinity, c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), c(8), o)
          assert(hit == hitExact, s"scale $scale: fp64 hit $hit, exact $hitExact (${c.mkString(",")})")
          if (hit) {
            hits += 1
            assert(closeHalfUlp(o.t, ex.t) && closeHalfUlp(o.u, ex.u) && closeHalfUlp(o.v, ex.v), s"scale $scale: t/u/v not the rounded exact values")
          }
          if (RayTriangle.test(r, Float.PositiveInfinity, c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), c(8), o32) && hitExact) fp32Hits += 1
        }
      }
      info(s"scale $scale: $checked well-conditioned cases, $hits hits in fp64, $fp32Hits in fp32")
      assert(checked > 1000 && hits > checked / 4, s"scale $scale: only $checked cases, $hits hits")
      if (scale != 1f) assert(fp32Hits == 0, s"fp32 was expected to lose every hit at scale $scale (det out of range)")
      else assert(fp32Hits > hits * 9 / 10, "at unit scale fp32 finds the hits too")
    }
  }
}
