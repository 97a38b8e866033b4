package rtaccel.top

import chisel3._
import chisel3.util._

/** Register port of the board top: word-addressed 64-bit registers, one write and one read port. */
class RegPort extends Bundle {
  val wr = Flipped(Valid(new Bundle { val addr = UInt(8.W); val data = UInt(64.W) }))
  val rdAddr = Input(UInt(8.W))
  val rdData = Output(UInt(64.W))
}

/** Register map (also in docs/platform.md):
  *  0x00 magic "RTAC" + version   0x01 configuration (M, max primitives per leaf, TUs, stack depth)   0x02 primitive base (RW)
  *  0x03 control (RW, bit 0 clears the counters)   0x10.. performance counters (read only, 64-bit).
  */
object RegMap {
  val Magic = 0x00; val Config = 0x01; val PrimBase = 0x02; val Control = 0x03; val Counters = 0x10
}

class RegFile(configWord: BigInt, counterNames: Seq[String], addrBits: Int) extends Module {
  val io = IO(new Bundle {
    val port = new RegPort
    val primBase = Output(UInt(addrBits.W))
    val clear = Output(Bool())
    val counters = Input(Vec(counterNames.length, UInt(64.W)))
  })
  val primBase = RegInit(0.U(addrBits.W)) // as wide as a memory address
  val control = RegInit(0.U(64.W))
  when(io.port.wr.valid) {
    when(io.port.wr.bits.addr === RegMap.PrimBase.U) { primBase := io.port.wr.bits.data(addrBits - 1, 0) }
    when(io.port.wr.bits.addr === RegMap.Control.U) { control := io.port.wr.bits.data }
  }
  io.primBase := primBase
  io.clear := control(0)
  val table = Seq(RegMap.Magic -> "h5254414300000001".U(64.W), RegMap.Config -> configWord.U(64.W),
    RegMap.PrimBase -> primBase.pad(64), RegMap.Control -> control) ++
    counterNames.indices.map(i => (RegMap.Counters + i) -> io.counters(i))
  io.port.rdData := MuxLookup(io.port.rdAddr, 0.U(64.W))(table.map { case (a, v) => a.U -> v })
}
