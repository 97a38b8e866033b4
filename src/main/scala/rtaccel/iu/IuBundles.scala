package rtaccel.iu

import chisel3._
import chisel3.util.log2Ceil
import rtaccel.config.PlatformParams

/** A ray as the intersection unit needs it: origin, direction, reciprocal direction and tmin (fp32 bits). */
class RayData extends Bundle {
  val o = Vec(3, UInt(32.W))
  val d = Vec(3, UInt(32.W))
  val inv = Vec(3, UInt(32.W))
  val tmin = UInt(32.W)
}

/** One TU request: intersect `ray` (within [tmin, tmax]) with the node or leaf that `ref` names.
  * RAY_STORE=1: no ray; the IU reads the ray of TU `tu` from its ray store.
  */
class IuReq(tuBits: Int, rayStore: Boolean) extends Bundle {
  val tu = UInt(tuBits.W)
  val cref = UInt(32.W)
  val tmax = UInt(32.W)
  val ray = if (rayStore) None else Some(new RayData)
}

/** RAY_STORE=1: the ray the TC hands to the TU of index `slot` within an IU's cluster, written into that IU's ray
  * store in the same cycle (the TU is idle then, so none of its jobs still reads the entry).
  */
class RayWrite(slots: Int) extends Bundle {
  val slot = UInt(RayWrite.slotBits(slots).W)
  val ray = new RayData
}

object RayWrite {
  /** index bits of a ray store of `slots` entries (at least 2 entries, so at least 1 bit) */
  def slotBits(slots: Int): Int = chisel3.util.log2Ceil(math.max(2, slots))
}

/** Slab-test results for the M children of a node, in slot order. */
class BoxResult(p: PipeParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val hit = Vec(p.m, Bool())
  val tnear = Vec(p.m, UInt(32.W))
  val cref = Vec(p.m, UInt(32.W))
  val err = Bool() // the node came with a memory error: no child is hit
  /** Each hit child's rank by entry distance: nearer first, an equal one in an earlier slot first (BoxPipe; a non-hit
    * slot's rank means nothing). */
  val rank = Vec(p.m, UInt(log2Ceil(p.m).max(1).W))
}

/** Möller–Trumbore result for one primitive of a leaf; `last` marks the leaf's final primitive. */
class TriResult(p: PipeParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val hit = Bool()
  val t = UInt(32.W)
  val u = UInt(32.W)
  val v = UInt(32.W)
  val prim = UInt(32.W)
  val last = Bool()
  val err = Bool() // the primitive came with a memory error: not hit
}
