package rtaccel.model

import java.math.{BigDecimal => JBig}
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.TestScenes
import rtaccel.bvh.{Mbvh, MemoryImage, RefCodec}
import rtaccel.config.{Fit, PlatformParams}
import rtaccel.fp.FpFormat

/** BOX_FORMAT's promise (docs/numerics.md): the outward-rounded slab test never rejects a box that the exact
  * ray meets. "Exact" here is the slab test of the same fp32 inputs (origin, 1/d, planes, tmin, tmax) in exact
  * rational arithmetic, with the fp32 test's rules for infinities and 0 * inf (no bound on that axis).
  */
class BoxOutwardSpec extends AnyFunSuite {
  /** Extended reals: a finite exact value, or an infinity, or "no bound" (0 * inf). */
  private sealed trait X
  private final case class Fin(v: JBig) extends X
  private final case class Inf(neg: Boolean) extends X
  private case object Free extends X
  private def of(f: Float): X = if (f.isInfinite) Inf(f < 0) else Fin(new JBig(f.toDouble))
  private def sign(x: X): Int = x match { case Fin(v) => v.signum; case Inf(n) => if (n) -1 else 1; case Free => 0 }
  private def sub(a: X, b: X): X = (a, b) match {
    case (Fin(x), Fin(y)) => Fin(x.subtract(y))
    case (Inf(n), Fin(_)) => Inf(n)
    case (Fin(_), Inf(n)) => Inf(!n)
    case _ => Free // inf - inf: not produced by finite origins
  }
  private def mul(a: X, b: X): X = (a, b) match {
    case (Fin(x), Fin(y)) => Fin(x.multiply(y))
    case _ if sign(a) == 0 || sign(b) == 0 => Free
    case _ => Inf(sign(a) * sign(b) < 0)
  }
  private def cmp(a: X, b: X): Int = (a, b) match {
    case (Fin(x), Fin(y)) => x.compareTo(y)
    case (Inf(n), Inf(m)) => if (n == m) 0 else if (n) -1 else 1
    case (Inf(n), _) => if (n) -1 else 1
    case (_, Inf(m)) => if (m) 1 else -1
    case _ => 0
  }

  /** The exact slab test of RayBox's inputs: hit iff max(tmin, lo) <= min(tmax, hi) over the constrained axes.
    * Decided in double arithmetic where that is certain (`filtered`), else in exact rationals. */
  def exactHit(r: PreparedRay, tmax: Float, box: Array[Float]): Boolean = filtered(r, tmax, box).getOrElse(rationalHit(r, tmax, box))

  private val Undecided = Int.MinValue
  /** a against b when the doubles' errors cannot change the answer, else Undecided. Each finite side is an exact
    * value times (1 + e) with |e| <= 2^-52 (two roundings: the difference, the product; doubles of fp32 inputs never
    * underflow), and the subtraction below rounds once more: a margin of 2^-46 of the magnitudes is far beyond all
    * three. Infinities (tmin, tmax) compare exactly. */
  private def cmpD(a: Double, b: Double): Int =
    if (a.isInfinite || b.isInfinite) java.lang.Double.compare(a, b).sign
    else {
      val d = a - b; val margin = (math.abs(a) + math.abs(b)) * 1.4210854715202004e-14 // 2^-46
      if (d > margin) 1 else if (-d > margin) -1 else Undecided
    }
  /** rationalHit's answer from doubles, None when a comparison is too close to call or an input is not finite. */
  private def filtered(r: PreparedRay, tmax: Float, box: Array[Float]): Option[Boolean] = {
    val o = Array(r.ox, r.oy, r.oz); val inv = Array(r.ix, r.iy, r.iz)
    if (!(o ++ inv ++ box).forall(f => !f.isNaN && !f.isInfinite) || tmax.isNaN || r.tmin.isNaN) return None
    var near = r.tmin.toDouble; var far = tmax.toDouble
    for (a <- 0 until 3) {
      val t0 = (box(a).toDouble - o(a)) * inv(a); val t1 = (box(3 + a).toDouble - o(a)) * inv(a)
      val c01 = cmpD(t0, t1); if (c01 == Undecided) return None
      val (lo, hi) = if (c01 <= 0) (t0, t1) else (t1, t0)
      val cn = cmpD(lo, near); val cf = cmpD(hi, far)
      if (cn == Undecided || cf == Undecided) return None
      if (cn > 0) near = lo
      if (cf < 0) far = hi
    }
    val c = cmpD(near, far)
    if (c == Undecided) None else Some(c <= 0)
  }

  private def rationalHit(r: PreparedRay, tmax: Float, box: Array[Float]): Boolean = {
    val o = Array(r.ox, r.oy, r.oz); val inv = Array(r.ix, r.iy, r.iz)
    var near: X = of(r.tmin); var far: X = of(tmax)
    for (a <- 0 until 3) {
      val t0 = mul(sub(of(box(a)), of(o(a))), of(inv(a))); val t1 = mul(sub(of(box(3 + a)), of(o(a))), of(inv(a)))
      if (t0 != Free && t1 != Free) {
        val (lo, hi) = if (cmp(t0, t1) <= 0) (t0, t1) else (t1, t0)
        if (cmp(lo, near) > 0) near = lo
        if (cmp(hi, far) < 0) far = hi
      }
    }
    cmp(near, far) <= 0
  }

  private val formats = Seq("bf16", "fp16", "fp24", "e6m9", "e8m3").map(FpFormat.parse)

  test("random and edge-case boxes: the outward test keeps every box the exact ray meets, in every format") {
    val rnd = new Random(17)
    val specials = Array(0f, -0f, 1f, -1f, Float.MinPositiveValue, 1e-30f, -1e-30f, 1e30f, Float.PositiveInfinity, Float.NegativeInfinity, Float.MaxValue)
    def coord(): Float = rnd.nextInt(10) match {
      case 0 => specials(rnd.nextInt(specials.length))
      case 1 => rnd.nextInt(5) - 2f
      case _ => (rnd.nextFloat() - 0.5f) * math.pow(2, rnd.nextInt(16) - 8).toFloat
    }
    val outs = formats.map(f => f -> new RayBoxOutward(f))
    val extra = scala.collection.mutable.Map[String, Int]().withDefaultValue(0)
    var exactHits = 0; var fp32Lost = 0; var decided = 0
    for (_ <- 0 until 40000) {
      val o = Array.fill(3)(if (rnd.nextInt(6) == 0) rnd.nextInt(3) - 1f else (rnd.nextFloat() - 0.5f) * 4)
      val d = Array.fill(3)(if (rnd.nextInt(6) == 0) (if (rnd.nextBoolean()) 0f else -0f) else (rnd.nextFloat() - 0.5f) * math.pow(2, rnd.nextInt(20) - 10).toFloat)
      if (d.forall(_ == 0f)) d(0) = 1f
      val tmin = if (rnd.nextInt(4) == 0) rnd.nextFloat() else 0f
      val tmax = if (rnd.nextInt(3) == 0) tmin + rnd.nextFloat() * 3 else Float.PositiveInfinity
      val r = new PreparedRay(o(0), o(1), o(2), d(0), d(1), d(2), tmin, tmax)
      val a = Array.fill(3)(coord()); val b = Array.fill(3)(coord())
      // near-grazing boxes: a face on the ray's path at the ray's own coordinates
      if (rnd.nextInt(4) == 0) { val k = rnd.nextInt(3); a(k) = o(k); b(k) = o(k) + (if (rnd.nextBoolean()) 0f else Math.ulp(o(k))) }
      val box = a.zip(b).map(x => math.min(x._1, x._2)) ++ a.zip(b).map(x => math.max(x._1, x._2))
      // the rationals, and the doubles wherever they decide (near-grazing and extreme boxes among them): never apart
      val exact = rationalHit(r, tmax, box)
      val quick = filtered(r, tmax, box)
      assert(quick.forall(_ == exact), s"the double filter says ${quick.getOrElse("nothing")} where the exact test says $exact: ray ${o.mkString(",")} dir ${d.mkString(",")} box ${box.mkString(",")}")
      if (quick.isDefined) decided += 1
      val fp32 = !RayBox.test(r, tmax, box(0), box(1), box(2), box(3), box(4), box(5)).isNaN
      if (exact) exactHits += 1
      if (exact && !fp32) fp32Lost += 1
      for ((f, t) <- outs) {
        val hit = !t.test(r, tmax, box(0), box(1), box(2), box(3), box(4), box(5)).isNaN
        assert(hit || !exact, s"${f.name} rejects a box the exact ray meets: ray ${o.mkString(",")} dir ${d.mkString(",")} [$tmin, $tmax] box ${box.mkString(",")}")
        if (hit && !exact) extra(f.name) += 1
      }
    }
    info(s"$exactHits of 40000 exact hits; fp32 (nearest) rejects $fp32Lost of them; extra boxes kept: ${formats.map(f => s"${f.name} ${extra(f.name)}").mkString(", ")}; " +
      s"the double filter decided $decided")
    assert(exactHits > 1000 && extra("bf16") > 0 && decided > 10000 && decided < 40000, s"the filter decided $decided of 40000")
  }

  test("every node of the procedural fixtures' trees against their golden rays: no box the exact ray meets is lost") {
    assume(TestScenes.fixtures.nonEmpty, "no fixtures (RTACCEL_FIXTURES)")
    for ((name, scene, rays) <- TestScenes.fixtures) {
      val p = PlatformParams(m = 4, mppl = 4)
      val bvh = Mbvh.build(scene, p); val img = MemoryImage.pack(bvh, scene, Fit.fitTo(p, bvh))
      val codec = new RefCodec(img.p.refs)
      val t = new RayBoxOutward(FpFormat.parse("bf16"))
      var checked = 0
      for (i <- 0 until math.min(rays.count, 200); id <- 0 until img.numNodes; j <- 0 until p.m if !codec.isEmpty(img.childRef(id, j))) {
        val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
        val box = Array.tabulate(6)(k => java.lang.Float.intBitsToFloat(img.childWord(id, j, k)))
        if (exactHit(r, r.tmax, box)) {
          checked += 1
          assert(!t.test(r, r.tmax, box(0), box(1), box(2), box(3), box(4), box(5)).isNaN, s"$name ray $i node $id child $j")
        }
      }
      info(s"$name: $checked exact ray-box hits, all kept by bf16")
    }
  }
}
