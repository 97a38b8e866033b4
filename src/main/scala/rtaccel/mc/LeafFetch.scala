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
    if (packed) primBase +& first * p.leafRowBytes.U else primBase +& (first << log2Ceil(p.primStrideBytes))
  /** Beats of a leaf of `count` (1-based) primitives: a table by count with packed records (no rounding logic). */
  def beats(count: UInt): UInt =
    if (packed) VecInit((0 to p.refs.maxLeafPrims).map(c => beatsOf(c).U(log2Ceil(maxBeats + 1).W)))(count)
    else count << log2Ceil(slotBeats)
  /** DRAM bytes of that leaf. */
  def bytes(count: UInt): UInt = if (packed) beats(count) << beatLog else count << log2Ceil(p.primStrideBytes)
}
