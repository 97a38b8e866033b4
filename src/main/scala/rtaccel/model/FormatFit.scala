package rtaccel.model

import rtaccel.bvh.{Mbvh, MemoryImage}
import rtaccel.config.{BoxRange, PlatformParams}
import rtaccel.fp.FpFormat
import rtaccel.scene.{Rays, Scene}

/** BOX_FORMAT=m<M>: the fewest exponent bits the scene needs, by measurement. A narrow exponent never loses a
  * hit (the box test rounds outward) but costs work: differences plane - o below its smallest normal lose
  * fraction bits, and 1/d beyond its largest finite value becomes infinite, leaving that axis unconstrained. So
  * among the widths that represent the scene's ray distances (BoxRange) the fit takes the narrowest whose node
  * fetches on a sample of the rays stay within BoxRange.workTolerance of the 8-bit exponent's (fp32's range).
  */
object FormatFit {
  val sampleRays = 4096

  private def sample(rays: Rays): Rays = {
    val step = math.max(1, rays.count / sampleRays)
    Rays((0 until rays.count by step).flatMap(i => rays.data.slice(8 * i, 8 * i + 8)).toArray)
  }
  private def nodeFetches(img: MemoryImage, rays: Rays): Long = {
    val st = new RayStats
    new Traversal(img).traceAll(rays, AccessSink.none, st)
    st.nodeFetches
  }

  def boxExponent(img: MemoryImage, rays: Rays, manBits: Int, depth: Double): FpFormat = {
    val s = sample(rays)
    def fetches(f: FpFormat): Long = nodeFetches(img.copy(p = img.p.copy(boxFormat = f)), s)
    val full = fetches(FpFormat(8, manBits))
    (3 to 8).map(FpFormat(_, manBits)).filter(BoxRange.represents(_, depth))
      .find(f => f.expBits == 8 || fetches(f) <= full * (1 + BoxRange.workTolerance)).get
  }

  /** NODE_FORMAT=fit: quantization exists to cut node bytes, so the fit takes the narrowest quantization (q2..q16)
    * whose node bytes on the sample (fetches x slot) are within BoxRange.workTolerance of the fewest any format
    * reaches, full nodes included. Within one slot size wider planes only save fetches; a smaller slot (M=8 q2:
    * 64 B against 128 B) can pay for looser boxes.
    */
  def nodeFormat(bvh: Mbvh, scene: Scene, p: PlatformParams, rays: Rays): PlatformParams = {
    val s = sample(rays)
    val options = (0 +: (2 to 16)).map(k => p.copy(nodeQuantBits = k))
      .map(q => (q, nodeFetches(MemoryImage.pack(bvh, scene, q), s) * q.nodeSlotBytes.toDouble))
    val best = options.map(_._2).min
    val ok = options.filter(_._2 <= best * (1 + BoxRange.workTolerance)).map(_._1)
    ok.filter(_.nodeQuantBits > 0).sortBy(_.nodeQuantBits).headOption.getOrElse(ok.head)
  }
}
