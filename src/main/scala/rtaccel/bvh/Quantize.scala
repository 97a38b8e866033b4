package rtaccel.bvh

/** NODE_FORMAT=q<k> (docs/numerics.md, "Quantized nodes"): a node stores one origin per axis (fp32, the smallest
  * child lower bound), one power-of-two scale 2^e per axis (an 8-bit exponent) and, per child and plane, a k-bit
  * unsigned integer q; a plane decodes to fl(origin + q * 2^e) in fp32, rounded to nearest even (q * 2^e is exact).
  * Lower planes are rounded down and upper planes up, each checked on the decoded value, so every decoded child
  * box contains its exact box (Ylitie et al. 2017 use the same outward rounding for 8-bit planes). The layout per
  * node: 3 origins (96 bits), 3 exponents (24), M x 6 x k plane bits, M x 32 reference bits, in a power-of-two slot.
  */
object Quantize {
  final case class QNode(origin: Array[Float], exp: Array[Int], lo: Array[Array[Int]], hi: Array[Array[Int]])

  /** Bits of a node with M children at k bits per plane (before rounding to a power-of-two slot). */
  def nodeBits(m: Int, k: Int): Int = 3 * 32 + 3 * 8 + m * 6 * k + m * 32

  /** The 8-bit exponent field holds -127..127; a scale below 2^-127 is never needed after normalisation. */
  val MinExp: Int = -127

  def decode(origin: Float, exp: Int, q: Int): Float = origin + java.lang.Math.scalb(q.toFloat, exp)

  /** The children's boxes (min xyz, max xyz each; at least one) quantized to k bits per plane. */
  def encode(boxes: Seq[(Array[Float], Array[Float])], k: Int): QNode = {
    require(boxes.nonEmpty && k >= 2 && k <= 16, s"quantization needs children and 2..16 bits (got $k)")
    val top = (1 << k) - 1
    val origin = Array.tabulate(3)(a => boxes.map(_._1(a)).min)
    val exp = new Array[Int](3)
    val lo = Array.fill(boxes.size)(new Array[Int](3)); val hi = Array.fill(boxes.size)(new Array[Int](3))
    for (a <- 0 until 3) {
      val extent = boxes.map(_._2(a)).max.toDouble - origin(a)
      // the smallest scale whose top code reaches the extent, then larger while rounding pushes a plane past it
      var e = if (extent <= 0) MinExp else math.max(MinExp, java.lang.Math.getExponent(extent / top) - 1)
      var done = false
      while (!done) {
        done = true
        for ((b, c) <- boxes.zipWithIndex if done) {
          var ql = math.max(0, math.min(top, math.floor((b._1(a).toDouble - origin(a)) / math.pow(2, e)).toInt))
          while (ql > 0 && decode(origin(a), e, ql) > b._1(a)) ql -= 1
          var qh = math.max(0, math.min(top, math.ceil((b._2(a).toDouble - origin(a)) / math.pow(2, e)).toInt))
          while (qh < top && decode(origin(a), e, qh) < b._2(a)) qh += 1
          if (decode(origin(a), e, qh) < b._2(a)) { e += 1; done = false }
          else { lo(c)(a) = ql; hi(c)(a) = qh }
        }
      }
      exp(a) = e
    }
    QNode(origin, exp, lo, hi)
  }

  /** The decoded boxes, child by child. */
  def boxes(q: QNode): Seq[(Array[Float], Array[Float])] = q.lo.indices.map(c =>
    (Array.tabulate(3)(a => decode(q.origin(a), q.exp(a), q.lo(c)(a))), Array.tabulate(3)(a => decode(q.origin(a), q.exp(a), q.hi(c)(a)))))
}
