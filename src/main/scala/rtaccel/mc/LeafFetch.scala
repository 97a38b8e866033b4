package rtaccel.mc

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams

/** Where a leaf lies and what it reads, by primitive format (docs/numerics.md, "Packed primitives"):
  *  - slot64: `count` 64 B slots from slot `first`, count x slot beats;
  *  - packed: row `first` of leafRowBytes (a constant multiply, no table), ceil(count x 40 B / beat) beats, so that
  *    every leaf fetch moves exactly PlatformParams.leafBytes(count).
  */
final case class LeafFetch(p: PlatformParams, beatBytes: Int) {
  require(!p.primPacked || beatBytes * 8 == p.axiDataBits,
    s"PRIM_FORMAT=packed rounds leaves to the platform's ${p.axiDataBits}-bit beats; the memory bus has ${beatBytes * 8} bits")
  private val packed = p.primPacked
  private val slotBeats = p.primStrideBytes / beatBytes
  private val beatLog = log2Ceil(beatBytes)
  /** Beats of a leaf of `count` primitives (elaboration time). */
  def beatsOf(count: Int): Int = if (packed) (p.leafBytes(count) / beatBytes).toInt else count * slotBeats
  val maxBeats: Int = beatsOf(p.refs.maxLeafPrims)
  /** Byte address of the leaf whose reference's first field is `first`. */
  def addr(primBase: UInt, first: UInt): UInt =
    if (packed) LeafFetch.plusConstTimes(primBase, first, p.leafRowBytes) else primBase +& (first << log2Ceil(p.primStrideBytes))
  /** Beats of a leaf of `count` (1-based) primitives: a table by count with packed records (no rounding logic). */
  def beats(count: UInt): UInt =
    if (packed) VecInit((0 to p.refs.maxLeafPrims).map(c => beatsOf(c).U(log2Ceil(maxBeats + 1).W)))(count)
    else count << log2Ceil(slotBeats)
  /** DRAM bytes of that leaf. */
  def bytes(count: UInt): UInt = if (packed) beats(count) << beatLog else count << log2Ceil(p.primStrideBytes)
}

object LeafFetch {
  /** base + x * c (c > 0 a constant), exact: the shifted copies of x for c's set bits and the base reduced by 3:2
    * compressors (a LUT level each) to two words, then one carry chain. Written as `base + x * c`, a row of 160 B
    * was two chained carry chains after the reference (the multiply's add, then the base's): 7 LUT levels on xc5v
    * from the request into a cache path's lookup register, a memory controller's deepest path.
    */
  def plusConstTimes(base: UInt, x: UInt, c: Int): UInt = {
    require(c > 0, s"a positive constant (got $c)")
    val w = (base.getWidth max (x.getWidth + log2Ceil(c + 1))) + 1
    val terms = base.pad(w) +: (0 until log2Ceil(c + 1)).filter(b => (c >> b & 1) == 1).map(b => (x << b).pad(w))
    def reduce(ts: Seq[UInt]): Seq[UInt] = if (ts.length <= 2) ts else {
      val (three, rest) = ts.splitAt(3)
      val Seq(a, b, d) = three
      val sum = (a ^ b ^ d)(w - 1, 0)
      val carry = (((a & b) | (a & d) | (b & d)) << 1)(w - 1, 0)
      reduce(rest ++ Seq(sum, carry))
    }
    val two = reduce(terms)
    (if (two.length == 1) two.head else two(0) +& two(1))(w - 1, 0)
  }
}

