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
  * Each is a knob, and a value the RTL does not build is refused here, naming what exists (a value that
  * silently meant the default would make a precision study measure nothing).
  */
object Numerics {
  /** With TRI_TEST=watertight every box's exit distance grows by at least 2^-19 relative: more than the slab
    * test's own rounding (Ize 2013: 1 + 2*gamma(3), about 2^-21.4) plus the shear's rounding in the triangle
    * test (a few ulps of the hit distance). In ulps of a format with M fraction bits: 2^(M+1-19), at least 1.
    */
  val watertightBoxSlackLog2: Int = 19
  /** NODE_FORMAT: full = M children x 6 fp32 planes + reference (paper QBVH: 112 B in a 128 B slot); q<k> = k-bit
    * planes on a per-node origin and power-of-two scale (bvh.Quantize, stored as bvh.QNodeLayout, decoded in the
    * IU by iu.NodeDecode); 0 bits means full.
    */
  private val Q = """q(\d+)""".r
  def parseNodeFormat(v: String): Int = v.toLowerCase match {
    case "full" => 0
    case Q(k) if k.toInt >= 2 && k.toInt <= 16 => k.toInt
    case Q(k) => throw new InputError(s"NODE_FORMAT=$v: a quantized plane takes 2..16 bits (the node layout's field), not $k")
    case _ => throw new InputError(s"NODE_FORMAT=$v is not a node format; use full or q<bits> (q2..q16, e.g. q8)")
  }
  def parsePrimFormat(v: String): Boolean = v.toLowerCase match {
    case "slot64" => false
    case "packed" => true
    case _ => throw new InputError(s"PRIM_FORMAT=$v is not a primitive format; use ${primFormats.mkString(" or ")}")
  }
  def nodeFormatName(bits: Int): String = if (bits == 0) "full" else s"q$bits"
  /** PRIM_FORMAT: slot64 = 9 fp32 coordinates + triangle id in a 64 B slot; packed = the same 40 B records back to
    * back, a leaf per beat-aligned row of leafBytes(MPPL) (bvh.MemoryImage; the IU's iu.LeafAssembler cuts them out).
    */
  val primFormats: Seq[String] = Seq("slot64", "packed")
  val packedPrimBytes: Int = 40
  /** TRI_FORMAT: the arithmetic of the Möller–Trumbore test (iu.TriPipe, model.RayTriangleWide): fp32 (the paper's), or
    * any wider format (at least 8 exponent and 23 fraction bits, up to fp64): the fp32 inputs are widened exactly,
    * every operation rounds in that format, and t, u, v are rounded to fp32 at the end (docs/numerics.md, "Wider
    * triangle arithmetic"). A narrower one is refused: it would lose hits, not make the test more robust.
    */
  def parseTriFormat(v: String): rtaccel.fp.FpFormat = {
    val f = try rtaccel.fp.FpFormat.parse(v) catch {
      case e: IllegalArgumentException => throw new InputError(s"TRI_FORMAT=$v: ${e.getMessage.stripPrefix("requirement failed: ")}; use fp32, fp64 or e<E>m<M> with E >= 8, M >= 23")
    }
    if (!f.holds(rtaccel.fp.FpFormat.fp32))
      throw new InputError(s"TRI_FORMAT=$v (e${f.expBits}m${f.manBits}) is narrower than fp32: narrower triangle arithmetic " +
        "is not conservative (it loses hits); use fp32, fp64 or e<E>m<M> with E >= 8 and M >= 23 (e.g. e8m31)")
    f
  }

  def json(p: PlatformParams): ujson.Obj = ujson.Obj(
    "box_format" -> p.boxFormat.name, "node_format" -> nodeFormatName(p.nodeQuantBits), "prim_format" -> (if (p.primPacked) "packed" else "slot64"),
    "tri_test" -> p.triTest.name, "tri_format" -> p.triFormat.name)
}
