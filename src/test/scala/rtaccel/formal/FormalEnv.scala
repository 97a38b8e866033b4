package rtaccel.formal

import chisel3._
import chisel3.util._
import rtaccel.mc.{FetchBeat, MemReq}

/** Building blocks of the formal harnesses (docs/formal.md). A harness is a Module whose inputs are free: the
  * checker may drive them with any value in any cycle, so every choice the environment could make (requests,
  * stalls, memory data) is explored up to the bound. These helpers turn free inputs into a constrained
  * environment and into the monitors' bookkeeping; they generate logic in the calling module.
  */
object FormalEnv {
  /** A symbolic constant: a register without reset that keeps its value, so its initial value is free and
    * fixed for the whole trace (the "magic" address and data every property is quantified over).
    */
  def frozen[T <: Data](t: T): T = { val r = Reg(t); r := r; r }

  /** Stall of a handshake chosen freely by `want`; with `maxRun` = Some(k) never more than k cycles in a row (the
    * fairness a liveness bound needs), with None unbounded (safety only).
    */
  def stall(want: Bool, maxRun: Option[Int]): Bool = maxRun match {
    case None => want
    case Some(k) =>
      val run = RegInit(0.U(log2Ceil(k + 2).W))
      val s = want && run < k.U
      run := Mux(s, run + 1.U, 0.U)
      s
  }

  /** Free-running cycle count (wraps; ages are taken modulo its width, which exceeds every bound checked). */
  def cycle(bits: Int = 8): UInt = { val c = RegInit(0.U(bits.W)); c := c + 1.U; c }
}

/** Where the checker is free to choose and how long the environment may stall. */
final case class EnvBounds(memStall: Option[Int], sinkStall: Option[Int]) {
  def live: Boolean = memStall.isDefined && sinkStall.isDefined
}

/** Free inputs of an abstract memory (wired from the harness's IO: only top-level inputs are free). */
class MemFree(dataBits: Int) extends Bundle {
  val acceptStall = Bool()
  val respStall = Bool()
  val data = UInt(dataBits.W) // what any beat other than the magic one returns
  val err = Bool()
}

/** An abstract DRAM behind a (MemReq, FetchBeat) pair: reads are queued (up to `depth`), answered in order,
  * one beat per cycle when the free stall lets it, `last` on each read's final beat. The beat at byte address
  * `magicBeat` * beatBytes always holds (`magicData`, `magicErr`); every other beat is a fresh free value each
  * time it is read. So the memory is per-address fixed exactly where the properties look, and arbitrary
  * elsewhere (a design that returned another address's data for the magic one would be caught).
  */
class AbstractMem(addrBits: Int, beatsBits: Int, dataBits: Int, depth: Int, bounds: EnvBounds) {
  private val beatShift = log2Ceil(dataBits / 8)
  val magicBeat: UInt = FormalEnv.frozen(UInt((addrBits - beatShift).W))
  val magicData: UInt = FormalEnv.frozen(UInt(dataBits.W))
  val magicErr: Bool = FormalEnv.frozen(Bool())
  val free: MemFree = Wire(new MemFree(dataBits))
  free := DontCare

  /** Beat address (addr / beatBytes) of beat `i` of a read at byte address `addr`. */
  def beatAddr(addr: UInt, i: UInt): UInt = ((addr >> beatShift) + i)(addrBits - beatShift - 1, 0)

  /** Connects the memory to a requester; returns nothing, the ports are driven. */
  def serve(req: DecoupledIO[MemReq], resp: DecoupledIO[FetchBeat]): Unit = {
    val q = Module(new Queue(new MemReq(addrBits, beatsBits), depth))
    val refuse = FormalEnv.stall(free.acceptStall, bounds.memStall)
    q.io.enq.valid := req.valid && !refuse
    q.io.enq.bits := req.bits
    req.ready := q.io.enq.ready && !refuse
    val beat = RegInit(0.U(beatsBits.W))
    val head = q.io.deq.bits
    val last = beat === head.beats - 1.U
    val magic = beatAddr(head.addr, beat) === magicBeat
    resp.valid := q.io.deq.valid && !FormalEnv.stall(free.respStall, bounds.memStall)
    resp.bits.data := Mux(magic, magicData, free.data)
    resp.bits.err := Mux(magic, magicErr, free.err)
    resp.bits.last := last
    when(resp.fire) { beat := Mux(last, 0.U, beat + 1.U) }
    q.io.deq.ready := resp.fire && last
  }
}
