package rtaccel.model

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.bvh.{Mbvh, MemoryImage}
import rtaccel.config.{BoxRange, PlatformParams}
import rtaccel.fp.FpFormat

/** The fitted formats against their definitions, measured here with the model's own traversal on the full ray set. */
class FormatFitSpec extends AnyFunSuite {
  private val scene = TestScenes.soup(3, 400, 0.3f)
  private val rays = TestScenes.rays(5, 1500, -1f, 11f) // fewer than FormatFit.sampleRays: the fit sees them all
  private val tol = 1 + BoxRange.workTolerance
  private def fetches(img: MemoryImage) = { val st = new RayStats; new Traversal(img).traceAll(rays, AccessSink.none, st); st.nodeFetches }

  test("BOX_FORMAT=m<M>: the narrowest exponent whose node fetches stay within the tolerance of 8 bits") {
    val p = PlatformParams(m = 4, mppl = 4)
    val img = MemoryImage.pack(Mbvh.build(scene, p), scene, p)
    def at(f: FpFormat) = fetches(img.copy(p = p.copy(boxFormat = f)))
    val depth = BoxRange.depth(scene, rays)
    for (m <- Seq(3, 7)) {
      val f = FormatFit.boxExponent(img, rays, m, depth)
      val full = at(FpFormat(8, m))
      info(s"m$m -> ${f.name}: ${at(f)} node fetches against $full with 8 exponent bits")
      assert(f.manBits == m && BoxRange.represents(f, depth) && at(f) <= full * tol)
      if (f.expBits > 3 && BoxRange.represents(FpFormat(f.expBits - 1, m), depth)) assert(at(FpFormat(f.expBits - 1, m)) > full * tol)
    }
  }

  test("NODE_FORMAT=fit: the narrowest quantization within the tolerance of the fewest node bytes, M = 4 and M = 8") {
    for (m <- Seq(4, 8)) {
      val p = PlatformParams(m = m, mppl = 4)
      val bvh = Mbvh.build(scene, p)
      def bytes(k: Int) = { val q = p.copy(nodeQuantBits = k); fetches(MemoryImage.pack(bvh, scene, q)) * q.nodeSlotBytes.toDouble }
      val all = (0 +: (2 to 16)).map(k => k -> bytes(k)).toMap
      val best = all.values.min
      val k = FormatFit.nodeFormat(bvh, scene, p, rays).nodeQuantBits
      info(s"M=$m -> ${if (k == 0) "full" else s"q$k"}: ${all(k)} node bytes, fewest $best (full ${all(0)})")
      assert(all(k) <= best * tol)
      if (k > 0) assert((2 until k).forall(j => all(j) > best * tol), "a narrower quantization reaches the bound")
      else assert((2 to 16).forall(j => all(j) > best * tol))
    }
  }
}
