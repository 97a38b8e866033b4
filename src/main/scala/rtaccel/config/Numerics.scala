package rtaccel.config

import rtaccel.io.InputError

/** The ray-triangle test of the IU (TRI_TEST=), one value per test the model and the RTL build (docs/numerics.md). */
sealed abstract class TriTest(val name: String) {
  override def toString: String = name
}

object TriTest {
  /** Möller–Trumbore, as in the paper: not watertight at shared edges (fp32 rounding of the two cross products). */
  case object Mt extends TriTest("mt")
  /** Woop, Benthin and Wald (JCGT 2013): sheared edge functions whose signs are exact, so closed meshes do not leak. */
  case object Watertight extends TriTest("watertight")

  val all: Seq[TriTest] = Seq(Mt, Watertight)
  def parse(name: String): TriTest = all.find(_.name == name.toLowerCase).getOrElse(
    throw new InputError(s"TRI_TEST=$name is not a triangle test; use ${all.map(_.name).mkString(" or ")}"))
}

/** The numeric formats of a configuration, as every JSON last line names them under "numerics".
  * Box format and triangle test are knobs; the node and primitive layouts and the triangle arithmetic are the
  * only ones this version builds, and a request for another is refused here, naming what exists (a value that
  * silently meant the default would make a precision study measure nothing).
  */
object Numerics {
  /** With TRI_TEST=watertight every box's exit distance grows by at least 2^-19 relative: more than the slab
    * test's own rounding (Ize 2013: 1 + 2*gamma(3), about 2^-21.4) plus the shear's rounding in the triangle
    * test (a few ulps of the hit distance). In ulps of a format with M fraction bits: 2^(M+1-19), at least 1.
    */
  val watertightBoxSlackLog2: Int = 19
  /** NODE_FORMAT: M children x 6 fp32 planes + reference (paper QBVH: 112 B in a 128 B slot). */
  val nodeFormats: Seq[String] = Seq("full")
  /** PRIM_FORMAT: 9 fp32 coordinates + triangle id in a 64 B slot. */
  val primFormats: Seq[String] = Seq("slot64")
  /** TRI_FORMAT: the triangle arithmetic. */
  val triFormats: Seq[rtaccel.fp.FpFormat] = Seq(rtaccel.fp.FpFormat.fp32)

  private def only(knob: String, v: String, built: Seq[String]): Unit =
    if (!built.contains(v.toLowerCase))
      throw new InputError(s"$knob=$v is not built in this version; it supports $knob=${built.mkString(" | ")}")

  def checkNodeFormat(v: String): Unit = only("NODE_FORMAT", v, nodeFormats)
  def checkPrimFormat(v: String): Unit = only("PRIM_FORMAT", v, primFormats)
  def checkTriFormat(v: String): Unit = only("TRI_FORMAT", v, triFormats.map(_.name))

  def json(p: PlatformParams): ujson.Obj = ujson.Obj(
    "box_format" -> p.boxFormat.name, "node_format" -> nodeFormats.head, "prim_format" -> primFormats.head,
    "tri_test" -> p.triTest.name, "tri_format" -> triFormats.head.name)
}
