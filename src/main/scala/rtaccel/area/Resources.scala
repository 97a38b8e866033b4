package rtaccel.area

/** FPGA resources of a circuit, counted from Yosys' Xilinx cells. LUTs are logic LUTs; LUT RAM (distributed
  * RAM and shift registers) is counted apart, as vendor reports do; block RAM in 36 Kb equivalents (a RAMB18
  * is half a RAMB36).
  */
final case class Resources(lut: Long = 0, lutram: Long = 0, ff: Long = 0, dsp: Long = 0, bram18: Long = 0, carry: Long = 0) {
  def bram36: Double = bram18 / 2.0
  def +(o: Resources): Resources = Resources(lut + o.lut, lutram + o.lutram, ff + o.ff, dsp + o.dsp, bram18 + o.bram18, carry + o.carry)
  def *(k: Long): Resources = Resources(lut * k, lutram * k, ff * k, dsp * k, bram18 * k, carry * k)
  def json: ujson.Obj = ujson.Obj("lut" -> lut.toDouble, "lutram" -> lutram.toDouble, "ff" -> ff.toDouble, "dsp" -> dsp.toDouble,
    "bram36" -> bram36, "carry" -> carry.toDouble)
}

object Resources {
  private val lut = "LUT[1-6]".r
  private val lutram = "(RAM(16|32|64|128|256|512)X[0-9]+[SD]|RAM32M16|RAM32M|RAM64M8|RAM64M|SRL16E?|SRLC16E|SRLC32E)".r
  private val ff = "(FD[RSCP]E(_1)?|FD[RSCP]|FD|LD[CP]E?)".r
  private val dsp = "(DSP48E?[12]?|DSP48A1|DSP48E1|DSP48E2)".r
  private val bram36 = "(RAMB36E?[12]?|RAMB36SDP|RAMB36)".r
  private val bram18 = "(RAMB18E?[12]?|RAMB18SDP|RAMB18|RAMB16BWER)".r
  private val carry = "(CARRY4|CARRY8|MUXCY)".r
  /** Cell types that cost nothing (buffers, constants) or are accounted elsewhere (wide muxes share LUT slices). */
  private val free = "(IBUF|OBUF|BUFG|BUFGCTRL|IOBUF|GND|VCC|MUXF[5-9]|XORCY|INV|\\$assert|\\$assume|\\$cover)".r // $assert: simulation checks

  /** Resources of one module's own primitive cells; `unknown` collects cell types we do not classify. */
  def of(cells: Map[String, Long], unknown: scala.collection.mutable.Set[String]): Resources =
    cells.foldLeft(Resources()) { case (r, (t, n)) => t match {
      case lut() => r.copy(lut = r.lut + n)
      case lutram(_*) => r.copy(lutram = r.lutram + n)
      case ff(_*) => r.copy(ff = r.ff + n)
      case dsp(_*) => r.copy(dsp = r.dsp + n)
      case bram36(_*) => r.copy(bram18 = r.bram18 + 2 * n)
      case bram18(_*) => r.copy(bram18 = r.bram18 + n)
      case carry(_*) => r.copy(carry = r.carry + n)
      case free(_*) => r
      case other => unknown += other; r
    } }
}
