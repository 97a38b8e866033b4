package rtaccel.model

import java.math.BigDecimal
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** TRI_TEST=watertight in the model (RayTriangleWatertight) against exact arithmetic, and the property that makes
  * it watertight: the signs of its edge functions are the exact signs of the sheared vertices' 2D orientations.
  */
class WatertightSpec extends AnyFunSuite {
  private val wt = new RayTriangleWatertight
  private val Inf = Float.PositiveInfinity
  private def hit(r: PreparedRay, v: Array[Float]): Option[RayTriangle.Result] = {
    val o = new RayTriangle.Result; if (wt.test(r, r.tmax, v, o)) Some(o) else None
  }
  private def exact(x: Float) = new BigDecimal(x.toDouble)
  /** The sign of a*b - c*d in exact arithmetic. */
  private def orient(a: Float, b: Float, c: Float, d: Float): Int = exact(a).multiply(exact(b)).subtract(exact(c).multiply(exact(d))).signum
  private def ulps(x: Float, k: Int) = java.lang.Float.intBitsToFloat(java.lang.Float.floatToRawIntBits(x) + k)

  test("the centre of a triangle: t, and u, v as Möller–Trumbore's weights of v1 and v2") {
    val r = new PreparedRay(0.25f, 0.25f, -1f, 0f, 0f, 1f, 0f, Inf)
    val h = hit(r, Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f)).get
    assert(h.t == 1f && h.u == 0.25f && h.v == 0.25f)
    val mt = new RayTriangle.Result
    assert(RayTriangle.test(r, Inf, Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f), mt) && mt.u == h.u && mt.v == h.v && mt.t == h.t)
  }

  test("both windings hit, from both sides; tmin/tmax window; degenerate triangles and NaN rays miss") {
    val tri = Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f)
    val flipped = Array(0f, 0f, 0f, 0f, 1f, 0f, 1f, 0f, 0f)
    for (dz <- Seq(1f, -1f); v <- Seq(tri, flipped)) {
      val r = new PreparedRay(0.2f, 0.3f, -dz, 0f, 0f, dz, 0f, Inf)
      assert(hit(r, v).map(_.t).contains(1f))
    }
    assert(hit(new PreparedRay(0.2f, 0.3f, -1f, 0f, 0f, 1f, 0f, 1f), tri).isEmpty, "t = tmax is outside [tmin, tmax)")
    assert(hit(new PreparedRay(0.2f, 0.3f, -1f, 0f, 0f, 1f, 1.5f, Inf), tri).isEmpty, "t < tmin")
    assert(hit(new PreparedRay(0.2f, 0.3f, -1f, 0f, 0f, 1f, 0f, Inf), Array(0f, 0f, 0f, 1f, 1f, 0f, 2f, 2f, 0f)).isEmpty, "collinear")
    assert(hit(new PreparedRay(0.2f, 0.3f, -1f, 0f, Float.NaN, 1f, 0f, Inf), tri).isEmpty, "NaN direction")
    assert(hit(new PreparedRay(0.2f, 0.3f, -1f, 1f, 0f, 0f, 0f, Inf), tri).isEmpty, "a ray in the triangle's plane")
  }

  test("a ray exactly through a shared edge or vertex hits (zero edge functions accept both sides)") {
    val a = Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f); val b = Array(1f, 0f, 0f, 1f, 1f, 0f, 0f, 1f, 0f)
    val onEdge = new PreparedRay(0.5f, 0.5f, -1f, 0f, 0f, 1f, 0f, Inf)
    assert(hit(onEdge, a).isDefined && hit(onEdge, b).isDefined)
    val atVertex = new PreparedRay(1f, 0f, -1f, 0f, -0f, 1f, 0f, Inf)
    assert(hit(atVertex, a).isDefined && hit(atVertex, b).isDefined)
  }

  test("edge-function signs are exact: 20000 near ties (coordinates 1 + k ulp) against BigDecimal") {
    val rnd = new Random(11)
    var fallbackDecided = 0
    for (_ <- 0 until 20000) {
      // a ray along ±z from the z axis shears nothing: the sheared x, y are the vertices' own coordinates
      val dz = if (rnd.nextBoolean()) 1f else -1f
      val r = new PreparedRay(0f, 0f, -4f * dz, 0f, 0f, dz, 0f, Inf)
      val v = Array.tabulate(9)(k => if (k % 3 == 2) rnd.nextFloat() - 0.5f else ulps(if (rnd.nextBoolean()) 1f else -1f, rnd.nextInt(5)))
      def x(i: Int) = v(3 * i); def y(i: Int) = v(3 * i + 1)
      val s = Seq(orient(x(2), y(1), y(2), x(1)), orient(x(0), y(2), y(0), x(2)), orient(x(1), y(0), y(1), x(0)))
      val want = !(s.contains(-1) && s.contains(1)) && s.exists(_ != 0)
      val naive = Seq(x(2) * y(1) - y(2) * x(1), x(0) * y(2) - y(0) * x(2), x(1) * y(0) - y(1) * x(0)).map(e => math.signum(e).toInt)
      if (!(naive.contains(-1) && naive.contains(1)) != !(s.contains(-1) && s.contains(1))) fallbackDecided += 1
      assert(hit(r, v).isDefined == want, s"signs $s, vertices ${v.mkString(",")}")
    }
    assert(fallbackDecided > 100, s"only $fallbackDecided cases where binary32 alone would decide wrongly")
    info(s"$fallbackDecided of 20000 decided by the binary64 recomputation")
  }

  test("a closed mesh does not leak: rays from inside an octahedron through every vertex and edge point") {
    val rnd = new Random(5)
    // an irregular octahedron around the origin: 6 vertices, 8 faces sharing every edge
    val pts = Array(Array(1.3f, 0.01f, -0.02f), Array(-0.9f, 0.03f, 0.01f), Array(0.02f, 1.1f, 0.03f),
      Array(-0.01f, -1.7f, 0.02f), Array(0.03f, -0.02f, 0.8f), Array(0.01f, 0.02f, -1.2f))
    val faces = for (x <- Seq(0, 1); y <- Seq(2, 3); z <- Seq(4, 5)) yield Seq(x, y, z)
    val tris = faces.map(f => f.flatMap(i => pts(i)).toArray)
    val edges = faces.flatMap(f => Seq((f(0), f(1)), (f(1), f(2)), (f(2), f(0)))).distinct
    var rays = 0; var leaksWt = 0; var leaksMt = 0
    for (_ <- 0 until 200) {
      val o = Array.fill(3)((rnd.nextFloat() - 0.5f) * 0.2f)
      val targets = pts.toSeq ++ edges.flatMap { case (a, b) =>
        Seq(0.5f, rnd.nextFloat()).map(w => Array.tabulate(3)(k => pts(a)(k) + w * (pts(b)(k) - pts(a)(k)))) }
      for (t <- targets) {
        val r = new PreparedRay(o(0), o(1), o(2), t(0) - o(0), t(1) - o(1), t(2) - o(2), 0f, Inf)
        val mt = new RayTriangle.Result
        rays += 1
        if (!tris.exists(v => hit(r, v).isDefined)) leaksWt += 1
        if (!tris.exists(v => RayTriangle.test(r, Inf, v, mt))) leaksMt += 1
      }
    }
    info(s"$rays rays: watertight leaks $leaksWt, Möller–Trumbore leaks $leaksMt")
    assert(leaksMt > 0, "the rays no longer probe the shared edges")
    assert(leaksWt == 0)
  }

  test("the box slack: k ulps toward +inf on the raw bits, saturating at +inf, across zero; none for Möller–Trumbore") {
    import rtaccel.config.{PlatformParams, TriTest}
    import rtaccel.fp.FpFormat
    def bits(x: Float) = java.lang.Float.floatToRawIntBits(x)
    assert(BoxSlack.up32(1f, 32) == ulps(1f, 32) && BoxSlack.up32(-1f, 32) == ulps(-1f, -32))
    assert(BoxSlack.up32(Float.MaxValue, 32) == Inf && BoxSlack.up32(Inf, 32) == Inf && BoxSlack.up32(Float.NaN, 32).isNaN)
    assert(BoxSlack.up32(-Float.MinPositiveValue, 32) == ulps(0f, 31) && BoxSlack.up32(-0f, 32) == ulps(0f, 32))
    assert(BoxSlack.up32(ulps(-0f, 32), 32) == 0f && bits(BoxSlack.up32(ulps(-0f, 32), 32)) == 0)
    val wt = PlatformParams(triTest = TriTest.Watertight)
    assert(PlatformParams().boxSlackUlps == 0 && wt.boxSlackUlps == 32)
    assert(wt.copy(boxFormat = FpFormat.parse("bf16")).boxSlackUlps == 1 && wt.copy(boxFormat = FpFormat.parse("e8m20")).boxSlackUlps == 4)
    // at least 2^-19 relative in every binade and format
    for (f <- Seq("fp32", "e8m20", "fp24", "bf16", "fp16").map(FpFormat.parse); k = wt.copy(boxFormat = f).boxSlackUlps)
      assert(k * math.pow(2, -(f.manBits + 1)) >= math.pow(2, -19), f.name)
    // a box whose exit is a hair before its entry (a ray grazing its corner) is kept with the slack only
    val r = new PreparedRay(0f, 0f, 0f, 1f, 1f, 0f, 0f, Inf)
    assert(RayBox.test(r, Inf, 1f, ulps(1f, -3), -1f, ulps(1f, 8), ulps(1f, -4), 1f).isNaN)
    assert(RayBox.test(r, Inf, 1f, ulps(1f, -3), -1f, ulps(1f, 8), ulps(1f, -4), 1f, slack = 32) == 1f)
  }
}
