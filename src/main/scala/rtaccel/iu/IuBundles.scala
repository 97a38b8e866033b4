package rtaccel.iu

import chisel3._
import rtaccel.config.PlatformParams

/** A ray as the intersection unit needs it: origin, direction, reciprocal direction and tmin (fp32 bits). */
class RayData extends Bundle {
  val o = Vec(3, UInt(32.W))
  val d = Vec(3, UInt(32.W))
  val inv = Vec(3, UInt(32.W))
  val tmin = UInt(32.W)
}

/** One TU request: intersect `ray` (within [tmin, tmax]) with the node or leaf that `ref` names. */
class IuReq(p: PlatformParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val cref = UInt(32.W)
  val tmax = UInt(32.W)
  val ray = new RayData
}

/** Slab-test results for the M children of a node, in slot order. */
class BoxResult(p: PlatformParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val hit = Vec(p.m, Bool())
  val tnear = Vec(p.m, UInt(32.W))
  val cref = Vec(p.m, UInt(32.W))
  val err = Bool() // the node came with a memory error: no child is hit
}

/** Möller–Trumbore result for one primitive of a leaf; `last` marks the leaf's final primitive. */
class TriResult(p: PlatformParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val hit = Bool()
  val t = UInt(32.W)
  val u = UInt(32.W)
  val v = UInt(32.W)
  val prim = UInt(32.W)
  val last = Bool()
  val err = Bool() // the primitive came with a memory error: not hit
}
