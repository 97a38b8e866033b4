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
}

object FpFormat {
  val fp32: FpFormat = FpFormat(8, 23)
}
