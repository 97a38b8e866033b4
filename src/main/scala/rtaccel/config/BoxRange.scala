package rtaccel.config

import rtaccel.fp.FpFormat
import rtaccel.io.InputError
import rtaccel.scene.{Rays, Scene}

/** What the box test's format (BOX_FORMAT) must represent of a scene: the distances along the rays.
  *
  * Normalisation (scene.Normalize) scales coordinates and directions by the same power of two, so the distances
  * t the slab test forms stay in the user's units: a 1e30 scene seen with unit directions has t near 1e30 after
  * normalisation too. A narrow format still rounds such a box outward (to infinity) and stays conservative, but
  * then every box passes and the tree stops pruning: it cannot represent the scene. So the format's normal range
  * must hold the scene's depth (the farthest distance at which a ray is still inside the scene's bounding box)
  * with headroom 2, and its smallest normal must be at most one ulp of that depth (depth x 2^-M), so that the
  * distances near the depth are not all subnormal.
  *
  * BOX_FORMAT=m<M> asks for M fraction bits and the fewest exponent bits (3..8) that represent the scene and
  * cost at most workTolerance more node fetches than 8 exponent bits (model.FormatFit measures it).
  */
object BoxRange {
  /** The extra traversal work (node fetches) a fitted format may cost: a fitted box exponent against fp32's 8 bits,
    * a fitted node quantization (NODE_FORMAT=fit) in node bytes against the fewest any node format reaches.
    */
  val workTolerance: Double = 0.01

  private val FitRequest = """m(\d+)""".r

  /** The fraction bits of a BOX_FORMAT=m<M> request, None for a named or e<E>m<M> format. */
  def fitRequest(v: String): Option[Int] = v.toLowerCase match {
    case FitRequest(m) => Some(m.toInt)
    case _ => None
  }

  def maxFinite(f: FpFormat): Double = (2.0 - math.pow(2, -f.manBits)) * math.pow(2, f.bias)
  def minNormal(f: FpFormat): Double = math.pow(2, 1 - f.bias)

  def represents(f: FpFormat, depth: Double): Boolean =
    depth == 0 || (maxFinite(f) >= 2 * depth && minNormal(f) <= depth * math.pow(2, -f.manBits))

  /** The farthest t (in doubles, clipped to the ray's [tmin, tmax]) at which any ray is inside the scene's
    * bounding box; 0 when no ray meets it. Inputs as the hardware sees them (normalised).
    */
  def depth(scene: Scene, rays: Rays): Double = {
    val lo = Array.fill(3)(Double.PositiveInfinity); val hi = Array.fill(3)(Double.NegativeInfinity)
    var i = 0
    while (i < scene.coords.length) {
      val a = i % 3; val c = scene.coords(i).toDouble
      if (c < lo(a)) lo(a) = c
      if (c > hi(a)) hi(a) = c
      i += 1
    }
    var far = 0.0
    for (r <- 0 until rays.count) {
      var tn = math.max(0.0, rays(r, 6).toDouble); var tf = rays(r, 7).toDouble
      var a = 0
      while (a < 3 && tn <= tf) {
        val o = rays(r, a).toDouble; val d = rays(r, 3 + a).toDouble
        if (d == 0) { if (o < lo(a) || o > hi(a)) tf = Double.NegativeInfinity }
        else {
          val t1 = (lo(a) - o) / d; val t2 = (hi(a) - o) / d
          tn = math.max(tn, math.min(t1, t2)); tf = math.min(tf, math.max(t1, t2))
        }
        a += 1
      }
      if (tn <= tf && !tf.isInfinite && !tf.isNaN && tf > far) far = tf
    }
    far
  }

  /** `p` with its box format fitted (BOX_FORMAT=m<M>, `fitBits` = M: `measure` picks among the widths that represent the
    * scene, narrowest first) or checked against the scene's depth.
    */
  def fit(p: PlatformParams, fitBits: Option[Int], depth: Double, sceneName: String,
          measure: (Int, Double) => FpFormat = (m, d) => (3 to 8).map(FpFormat(_, m)).find(represents(_, d)).get): PlatformParams =
    fitBits match {
      case Some(m) =>
        if (!represents(FpFormat(8, m), depth)) throw new InputError(
          f"BOX_FORMAT=m$m: no exponent width of 3..8 bits represents scene '$sceneName' (its rays reach t = $depth%.3g); " +
            "use BOX_FORMAT=fp32 or scale the rays' directions")
        p.copy(boxFormat = measure(m, depth))
      case None =>
        val f = p.boxFormat // fp32 is the paper's test and the reference of the others: never refused
        if (f != FpFormat.fp32 && !represents(f, depth)) throw new InputError(
          f"BOX_FORMAT=${f.name} cannot represent scene '$sceneName': its rays reach t = $depth%.3g, but ${f.name}'s normal " +
            f"range is ${minNormal(f)}%.3g..${maxFinite(f)}%.3g (${f.expBits} exponent bits; it must hold 2 x that distance, " +
            f"and one ulp of it, ${depth * math.pow(2, -f.manBits)}%.3g); use more exponent bits, e.g. BOX_FORMAT=m${f.manBits} to fit them")
        p
    }
}
