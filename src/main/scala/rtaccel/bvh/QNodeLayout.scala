package rtaccel.bvh

/** The stored layout of a NODE_FORMAT=q<k> node (docs/numerics.md, "Quantized nodes"), in 32-bit words of a
  * PlatformParams.nodeSlotBytes slot; the RTL's iu.NodeDecode slices the same bits.
  *   words 0..2      origin x, y, z (fp32 bits)
  *   words 3..3+M-1  child j's reference (as the full node's; 0 = empty slot)
  *   from word 3+M   a bit stream, bit i at bit i%32 of word 3+M+i/32:
  *                   bits 0..23 the exponents of x, y, z (8 bits each, two's complement, -127..127),
  *                   then per child j and plane k (k = 0..5: min x, y, z, max x, y, z) a k-bit unsigned q
  *                   at bit 24 + (6j+k)*bits.
  *   the rest of the slot is zero.
  * Origins and references are whole words so that the hardware takes them as they arrive; the stream is packed
  * so that every node of Quantize.nodeBits fits its power-of-two slot (M=4 q8: 14 words of the 16 of 64 B).
  * A plane decodes in the hardware's order: q to fp32 (exact), times 2^e (exact, or +inf past the fp32 range),
  * one fp32 add of the origin rounded to nearest even (Quantize.decode); a NaN result is the canonical one.
  */
final class QNodeLayout(val m: Int, val bits: Int) {
  require(bits >= 2 && bits <= 16, s"a quantized plane takes 2..16 bits (got $bits)")
  val refWord0: Int = 3
  val streamWord0: Int = 3 + m
  val streamBits: Int = 24 + 6 * m * bits
  /** Words the layout uses (the slot may be larger). */
  val usedWords: Int = streamWord0 + (streamBits + 31) / 32
  def expBit(axis: Int): Int = 8 * axis
  def planeBit(child: Int, plane: Int): Int = 24 + (6 * child + plane) * bits

  private def put(w: Array[Int], base: Int, bit: Int, width: Int, v: Int): Unit =
    for (i <- 0 until width) if (((v >>> i) & 1) != 0) { val b = bit + i; w(base + streamWord0 + b / 32) |= 1 << (b % 32) }
  private def get(w: Array[Int], base: Int, bit: Int, width: Int): Int = {
    var v = 0
    for (i <- 0 until width) { val b = bit + i; v |= ((w(base + streamWord0 + b / 32) >>> (b % 32)) & 1) << i }
    v
  }

  /** Writes node q with child references refs (empty slots past q's children: q = 0, ref 0) at word base of w. */
  def pack(q: Quantize.QNode, refs: Seq[Int], w: Array[Int], base: Int): Unit = {
    require(refs.length <= m && q.lo.length == refs.length, s"${refs.length} children for M=$m")
    for (a <- 0 until 3) {
      require(q.exp(a) >= Quantize.MinExp && q.exp(a) <= 127, s"exponent ${q.exp(a)} does not fit the 8-bit field")
      w(base + a) = java.lang.Float.floatToRawIntBits(q.origin(a))
      put(w, base, expBit(a), 8, q.exp(a) & 0xff)
    }
    for ((r, j) <- refs.zipWithIndex) {
      w(base + refWord0 + j) = r
      for (a <- 0 until 3) { put(w, base, planeBit(j, a), bits, q.lo(j)(a)); put(w, base, planeBit(j, 3 + a), bits, q.hi(j)(a)) }
    }
  }

  def origin(w: Array[Int], base: Int, axis: Int): Int = w(base + axis)
  def exp(w: Array[Int], base: Int, axis: Int): Int = (get(w, base, expBit(axis), 8) << 24) >> 24
  def q(w: Array[Int], base: Int, child: Int, plane: Int): Int = get(w, base, planeBit(child, plane), bits)
  def ref(w: Array[Int], base: Int, child: Int): Int = w(base + refWord0 + child)

  /** The node at word base of w in the full layout (child j: min xyz, max xyz, ref at 7j..7j+6) into out at outBase. */
  def decodeInto(w: Array[Int], base: Int, out: Array[Int], outBase: Int): Unit =
    for (j <- 0 until m) {
      for (k <- 0 until 6) out(outBase + 7 * j + k) = QNodeLayout.plane(origin(w, base, k % 3), exp(w, base, k % 3), q(w, base, j, k))
      out(outBase + 7 * j + 6) = ref(w, base, j)
    }
}

object QNodeLayout {
  private val CanonicalNaN = 0x7fc00000
  /** One plane as fp32 bits, as the hardware forms it (see the class comment). */
  def plane(originBits: Int, exp: Int, q: Int): Int = {
    val v = Quantize.decode(java.lang.Float.intBitsToFloat(originBits), exp, q)
    if (v.isNaN) CanonicalNaN else java.lang.Float.floatToRawIntBits(v)
  }
}
