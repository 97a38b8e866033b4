package rtaccel.model

import rtaccel.config.{PlatformParams, TriTest}
import rtaccel.scene.{Hits, Rays, Scene}

/** The traversal's hits against every triangle tested with the same triangle test and no boxes at all (make
  * trace --exhaustive N, make precision): a ray whose traversal hit is farther than the closest exhaustive hit,
  * or missing, lost it to a box test. A conservative box test loses none.
  */
object Exhaustive {
  final case class Result(rays: Int, lost: Int, firstLost: Seq[Int])

  /** The closest t in [tmin, tmax) over all triangles of `scene` for ray i (+inf when none). */
  def closest(p: PlatformParams, scene: Scene, rays: Rays, i: Int): Float = {
    val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
    val wt = if (p.triTest == TriTest.Watertight) new RayTriangleWatertight else null
    val wide = if (p.triFormat == rtaccel.fp.FpFormat.fp32) null else new RayTriangleWide(p.triFormat)
    val out = new RayTriangle.Result
    var best = r.tmax; var found = false
    var k = 0
    while (k < scene.triangles) {
      val base = 9 * k
      val c: Int => Float = j => scene.coords(base + j)
      if (if (wide != null) wide.test(r, best, c, out) && out.t < best // the TU's fp32 check, as Traversal
          else if (wt == null) RayTriangle.test(r, best, c, out) else wt.test(r, best, c, out)) { best = out.t; found = true }
      k += 1
    }
    if (found) best else Float.PositiveInfinity
  }

  /** The first `n` rays (ray faults - overflow, read error - are not judged). */
  def check(p: PlatformParams, scene: Scene, rays: Rays, hits: Hits, n: Int): Result = {
    val m = math.min(n, rays.count)
    val lost = (0 until m).filter(i => hits.prim(i) >= Hits.Miss && closest(p, scene, rays, i) < hits.t(i))
    Result(m, lost.size, lost.take(10))
  }
}
