package rtaccel.host

import chisel3._
import chiseltest._
import rtaccel.io.InputError
import rtaccel.top.{AxiLite, RegMap}

/** The host side of the board's AXI4-Lite port in a chiseltest simulation, one transaction at a time, as a
  * driver on a real host would issue them. Every access checks its response: a register access that the
  * board answers with an error is a broken driver contract, not something to carry on from.
  */
final class HostDriver(lite: AxiLite, clock: Clock, timeoutCycles: Int = 1000) {
  private def waitFor(what: String)(cond: => Boolean): Unit = {
    var n = 0
    while (!cond) {
      clock.step(); n += 1
      if (n > timeoutCycles) throw new InputError(s"AXI4-Lite $what: no handshake within $timeoutCycles cycles")
    }
  }
  def idle(): Unit = {
    lite.aw.valid.poke(false.B); lite.w.valid.poke(false.B); lite.b.ready.poke(false.B)
    lite.ar.valid.poke(false.B); lite.r.ready.poke(false.B); lite.w.bits.strb.poke(15.U)
  }

  /** Writes one register; returns the B response (OKAY = 0). */
  def writeResp(r: RegMap.Reg, data: Long, strb: Int = 15): Int = {
    lite.aw.valid.poke(true.B); lite.aw.bits.addr.poke(r.offset.U)
    lite.w.valid.poke(true.B); lite.w.bits.data.poke((data & 0xffffffffL).U); lite.w.bits.strb.poke(strb.U)
    waitFor(s"write ${r.name}")(lite.aw.ready.peek().litToBoolean)
    clock.step()
    lite.aw.valid.poke(false.B); lite.w.valid.poke(false.B); lite.b.ready.poke(true.B)
    waitFor(s"write response ${r.name}")(lite.b.valid.peek().litToBoolean)
    val resp = lite.b.bits.resp.peek().litValue.toInt
    clock.step(); lite.b.ready.poke(false.B)
    resp
  }
  def write(r: RegMap.Reg, data: Long): Unit = {
    val resp = writeResp(r, data)
    if (resp != AxiLite.Okay) throw new InputError(s"the board answered a write of ${r.name} with response $resp")
  }

  /** Reads one word at a byte offset; returns (data, response). */
  def readResp(offset: Int): (Long, Int) = {
    lite.ar.valid.poke(true.B); lite.ar.bits.addr.poke(offset.U)
    waitFor(f"read 0x$offset%03x")(lite.ar.ready.peek().litToBoolean)
    clock.step()
    lite.ar.valid.poke(false.B); lite.r.ready.poke(true.B)
    waitFor(f"read data 0x$offset%03x")(lite.r.valid.peek().litToBoolean)
    val d = lite.r.bits.data.peek().litValue.toLong; val resp = lite.r.bits.resp.peek().litValue.toInt
    clock.step(); lite.r.ready.poke(false.B)
    (d, resp)
  }
  def read(r: RegMap.Reg): Long = {
    val (d, resp) = readResp(r.offset)
    if (resp != AxiLite.Okay) throw new InputError(s"the board answered a read of ${r.name} with response $resp")
    d
  }
  def field(r: RegMap.Reg, name: String): Long = {
    val f = r.fields.find(_.name == name).get
    (read(r) >> f.lsb) & ((1L << f.width) - 1)
  }
  /** A 64-bit counter: LO (which snapshots the counter), then HI. */
  def counter(index: Int): Long = {
    val (lo, r1) = readResp(RegMap.CounterBase + 8 * index); val (hi, r2) = readResp(RegMap.CounterBase + 8 * index + 4)
    if (r1 != AxiLite.Okay || r2 != AxiLite.Okay) throw new InputError(s"the board answered a read of counter $index with an error")
    (hi << 32) | lo
  }
}
