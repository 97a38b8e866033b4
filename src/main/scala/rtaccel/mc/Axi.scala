package rtaccel.mc

import chisel3._
import chisel3.util._

/** AXI4 read-channel geometry of the memory master. dataBits is the bus width (beat size). */
final case class AxiParams(addrBits: Int = 32, dataBits: Int = 256, idBits: Int = 4) {
  require(Seq(32, 64, 128, 256, 512).contains(dataBits), s"AXI data width must be 32..512 bits, a power of two (got $dataBits)")
  val beatBytes: Int = dataBits / 8
}

object AxiParams {
  /** The memory master of a platform: widths from PlatformParams (axiDataBits, hw.axiAddrBits, hw.axiIdBits). */
  def of(p: rtaccel.config.PlatformParams): AxiParams = AxiParams(p.hw.axiAddrBits, p.axiDataBits, p.hw.axiIdBits)
}

class AxiAr(p: AxiParams) extends Bundle {
  val id = UInt(p.idBits.W)
  val addr = UInt(p.addrBits.W)
  val len = UInt(8.W)   // beats - 1
  val size = UInt(3.W)  // log2(bytes per beat)
  val burst = UInt(2.W) // 1 = INCR
}

class AxiR(p: AxiParams) extends Bundle {
  val id = UInt(p.idBits.W)
  val data = UInt(p.dataBits.W)
  val resp = UInt(2.W)
  val last = Bool()
}

/** The read half of an AXI4 master port (the platform only reads onboard memory). */
class AxiReadMaster(p: AxiParams) extends Bundle {
  val ar = Decoupled(new AxiAr(p))
  val r = Flipped(Decoupled(new AxiR(p)))
}
