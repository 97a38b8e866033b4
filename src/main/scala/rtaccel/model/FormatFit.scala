package rtaccel.model

import rtaccel.bvh.MemoryImage
import rtaccel.config.{BoxRange, PlatformParams}
import rtaccel.fp.FpFormat
import rtaccel.scene.Rays

/** BOX_FORMAT=m<M>: the fewest exponent bits the scene needs, by measurement. A narrow exponent never loses a
  * hit (the box test rounds outward) but costs work: differences plane - o below its smallest normal lose
  * fraction bits, and 1/d beyond its largest finite value becomes infinite, leaving that axis unconstrained. So
  * among the widths that represent the scene's ray distances (BoxRange) the fit takes the narrowest whose node
  * fetches on a sample of the rays stay within BoxRange.workTolerance of the 8-bit exponent's (fp32's range).
  */
object FormatFit {
  val sampleRays = 4096

  def boxExponent(img: MemoryImage, rays: Rays, manBits: Int, depth: Double): FpFormat = {
    val step = math.max(1, rays.count / sampleRays)
    val sample = Rays((0 until rays.count by step).flatMap(i => rays.data.slice(8 * i, 8 * i + 8)).toArray)
    def fetches(f: FpFormat): Long = {
      val st = new RayStats
      new Traversal(img.copy(p = img.p.copy(boxFormat = f))).traceAll(sample, AccessSink.none, st)
      st.nodeFetches
    }
    val full = fetches(FpFormat(8, manBits))
    (3 to 8).map(FpFormat(_, manBits)).filter(BoxRange.represents(_, depth))
      .find(f => f.expBits == 8 || fetches(f) <= full * (1 + BoxRange.workTolerance)).get
  }
}
