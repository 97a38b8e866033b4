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
  *  0x03 control (RW, bit 0 clears the counters)   0x04 MAX_LEVEL of the level replacement policy (RW, 4 bits)
  *  0x10.. performance counters (read only, 64-bit).
  */
object RegMap {
  val Magic = 0x00; val Config = 0x01; val PrimBase = 0x02; val Control = 0x03; val MaxLevel = 0x04; val Counters = 0x10
}

class RegFile(configWord: BigInt, counterNames: Seq[String], addrBits: Int, maxLevelReset: Int = 15) extends Module {
  val io = IO(new Bundle {
    val port = new RegPort
    val primBase = Output(UInt(addrBits.W))
    val clear = Output(Bool())
    val maxLevel = Output(UInt(4.W))
    val counters = Input(Vec(counterNames.length, UInt(64.W)))
  })
  val primBase = RegInit(0.U(addrBits.W)) // as wide as a memory address
  val control = RegInit(0.U(64.W))
  val maxLevel = RegInit(maxLevelReset.U(4.W))
  when(io.port.wr.valid) {
    when(io.port.wr.bits.addr === RegMap.PrimBase.U) { primBase := io.port.wr.bits.data(addrBits - 1, 0) }
    when(io.port.wr.bits.addr === RegMap.Control.U) { control := io.port.wr.bits.data }
    when(io.port.wr.bits.addr === RegMap.MaxLevel.U) { maxLevel := io.port.wr.bits.data(3, 0) }
  }
  io.primBase := primBase
  io.clear := control(0)
  io.maxLevel := maxLevel
  val table = Seq(RegMap.Magic -> "h5254414300000001".U(64.W), RegMap.Config -> configWord.U(64.W),
    RegMap.PrimBase -> primBase.pad(64), RegMap.Control -> control, RegMap.MaxLevel -> maxLevel.pad(64)) ++
    counterNames.indices.map(i => (RegMap.Counters + i) -> io.counters(i))
  io.port.rdData := MuxLookup(io.port.rdAddr, 0.U(64.W))(table.map { case (a, v) => a.U -> v })
}
