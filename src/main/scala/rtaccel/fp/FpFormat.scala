package rtaccel.fp

/** A binary floating-point format: 1 sign bit, expBits exponent bits (biased), manBits fraction bits.
  * fp32 is (8, 23). Other widths serve precision studies of the intersection unit.
  */
final case class FpFormat(expBits: Int = 8, manBits: Int = 23) {
  require(expBits >= 3 && expBits <= 11, s"exponent width must be 3..11 bits (got $expBits)")
  require(manBits >= 2 && manBits <= 52, s"fraction width must be 2..52 bits (got $manBits)")
  val width: Int = 1 + expBits + manBits
  val bias: Int = (1 << (expBits - 1)) - 1
  val maxExp: Int = (1 << expBits) - 1
  /** The one NaN the units produce: sign 0, exponent all ones, fraction MSB set (fp32: 0x7FC00000). */
  val canonicalNaN: BigInt = (BigInt(maxExp) << manBits) | (BigInt(1) << (manBits - 1))
  /** The name a knob takes (BOX_FORMAT=): a well-known name, else e<E>m<M>. */
  def name: String = FpFormat.named.collectFirst { case (n, f) if f == this => n }.getOrElse(s"e${expBits}m$manBits")
  /** Every value of `f` is a value of this format (so converting f to it is exact). */
  def holds(f: FpFormat): Boolean = expBits >= f.expBits && manBits >= f.manBits
}

object FpFormat {
  val fp32: FpFormat = FpFormat(8, 23)
  /** binary64: holds the product of two fp32 values exactly (the watertight test's zero fallback); TRI_FORMAT=fp64;
    * not a box format.
    */
  val fp64: FpFormat = FpFormat(11, 52)
  val named: Seq[(String, FpFormat)] = Seq("fp32" -> fp32, "fp64" -> fp64, "fp24" -> FpFormat(8, 15), "bf16" -> FpFormat(8, 7), "fp16" -> FpFormat(5, 10))
  private val Em = """e(\d+)m(\d+)""".r
  /** fp32 | fp64 | fp24 | bf16 | fp16 | e<E>m<M>; IllegalArgumentException with the accepted names otherwise. */
  def parse(s: String): FpFormat = named.toMap.get(s.toLowerCase).getOrElse(s.toLowerCase match {
    case Em(e, m) => FpFormat(e.toInt, m.toInt)
    case _ => throw new IllegalArgumentException(s"format '$s' is not one of ${named.map(_._1).mkString(", ")} or e<E>m<M> (e.g. e8m10)")
  })
}
