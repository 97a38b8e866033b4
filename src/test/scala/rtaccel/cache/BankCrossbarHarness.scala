package rtaccel.cache

import chisel3._
import chisel3.util._
import rtaccel.cache.hw.BankCrossbar
import rtaccel.formal.{EnvBounds, FormalEnv}

/** A fault put around the crossbar, to show that the monitor sees it (docs/formal.md, "NODE_BANKS crossbar"). */
sealed abstract class XbarBug(val name: String)
object XbarBug {
  case object None extends XbarBug("none")
  /** a cluster sees a beat while the crossbar offers none */
  case object Spurious extends XbarBug("spurious beat")
  /** a beat's data bit 0 flipped on its way to the cluster */
  case object Corrupt extends XbarBug("corrupted data")
  /** the cluster number of a request's tag flipped on its way to the bank: its answer goes to the other cluster */
  case object Misroute extends XbarBug("answer routed to the other cluster")
}

/** The free inputs of one abstract bank. */
class BankFree extends Bundle {
  val acceptStall = Bool()
  val respStall = Bool()
  val pick = UInt(1.W) // which held request to answer next (any order)
}

/** BankCrossbar (NODE_BANKS) between 2 clusters of 2 TUs (1-bit inner tag) and 2 abstract banks, with a monitor.
  * Every input is free (written for the bounded checker, FormalEnv's conventions; driven at random by
  * BankCrossbarSimSpec, since the proof did not get past 2 cycles: docs/formal.md). Each TU has at most one request in flight (as in the platform); a cluster's request, its reference and its TU are
  * free in every cycle (the IU's arbiter may change its offer while it waits). An abstract bank holds up to 2
  * requests and answers any held one it likes (`pick`), with 2 beats whose data is a function of the reference and
  * the beat (the 3-bit reference and the beat number: four TUs' requests, two per bank, tell apart), stalling accept and answer freely (up to the bound). Asserted:
  *  - every beat a cluster receives belongs to a request of that cluster outstanding under its tag;
  *  - an answer's beats come back to back (no other tag inside it), exactly 2 with `last` on the second, each with
  *    the data of its own request's reference: so each request is answered at most once, by the bank it went to;
  *  - every request goes to the bank its reference's low bit names (a request in the wrong bank is answered by it
  *    just the same, so this is asserted where the bank accepts it);
  *  - with bounded stalls: each request is answered within `answerBound` cycles, so exactly once.
  */
class BankCrossbarHarness(bounds: EnvBounds, answerBound: Int, bug: XbarBug = XbarBug.None) extends Module {
  private val (n, k, inner, dataBits, refBits) = (2, 2, 1, 4, 3)
  val io = IO(new Bundle {
    val reqValid = Input(Vec(n, Bool()))
    val reqRef = Input(Vec(n, UInt(refBits.W)))
    val reqTag = Input(Vec(n, UInt(inner.W)))
    val sinkStall = Input(Vec(n, Bool()))
    val bank = Input(Vec(k, new BankFree))
    val bugFire = Input(Bool())
    /** a beat reached cluster c (the randomized run's coverage) */
    val beatTo = Output(Vec(n, Bool()))
  })
  val dut = Module(new BankCrossbar(n, k, inner, 1, dataBits))
  private def dataOf(ref: UInt, beat: UInt): UInt = Cat(ref, beat(0))
  val now = FormalEnv.cycle(5)

  // ---- clusters: free requests, each TU with at most one in flight; free sinks
  class Held extends Bundle { val childRef = UInt(refBits.W); val time = UInt(now.getWidth.W) }
  val held = Reg(Vec(n, Vec(2, new Held)))
  val holds = RegInit(VecInit(Seq.fill(n)(VecInit(false.B, false.B))))
  for (c <- 0 until n) {
    val r = dut.io.req(c)
    r.valid := io.reqValid(c) && !holds(c)(io.reqTag(c))
    r.bits.childRef := io.reqRef(c).pad(32)
    r.bits.tag.get := io.reqTag(c)
    when(r.fire) { holds(c)(io.reqTag(c)) := true.B; held(c)(io.reqTag(c)).childRef := io.reqRef(c); held(c)(io.reqTag(c)).time := now }
  }

  // ---- abstract banks: two slots each, any held request answered, two beats
  for (b <- 0 until k) {
    val q = dut.io.bankReq(b)
    val f = io.bank(b)
    val slotV = RegInit(VecInit(false.B, false.B)); val slotRef = Reg(Vec(2, UInt(refBits.W))); val slotTag = Reg(Vec(2, UInt(2.W)))
    val free = Mux(!slotV(0), 0.U, 1.U)
    q.ready := !slotV.asUInt.andR && !FormalEnv.stall(f.acceptStall, bounds.memStall)
    val inTag = if (bug == XbarBug.Misroute) Mux(io.bugFire, q.bits.tag.get ^ 2.U, q.bits.tag.get) else q.bits.tag.get
    when(q.fire) {
      slotV(free) := true.B; slotRef(free) := q.bits.childRef(refBits - 1, 0); slotTag(free) := inTag
      assert(q.bits.childRef(0) === b.U, "a request reached a bank its reference does not name")
    }
    // the answer under way keeps its slot until its last beat. With bounded stalls (liveness) the bank is fair: once
    // it has answered the younger request ahead of the older, the older goes next (else it could starve it for good)
    val busy = RegInit(false.B); val cur = Reg(UInt(1.W)); val beat = RegInit(0.U(1.W))
    val older = RegInit(0.U(1.W)); val passed = RegInit(false.B)
    when(q.fire) { older := Mux(slotV(~free), ~free, free) }
    val any = Mux(slotV(f.pick), f.pick, ~f.pick)
    val choice = if (bounds.live) Mux(passed && slotV(older), older, any) else any
    // a beat once offered stays offered until taken (a bank's answers leave its response buffer, a queue: a
    // valid is never withdrawn); without that, a bank that withdraws its beat each time its cluster frees up
    // loses every round of the cluster's round robin, for good (the randomized run found it)
    val offered = RegInit(false.B); val offSlot = Reg(UInt(1.W))
    val s = Mux(busy, cur, Mux(offered, offSlot, choice))
    val a = dut.io.bankResp(b)
    a.valid := slotV(s) && (offered || !FormalEnv.stall(f.respStall, bounds.memStall))
    offered := a.valid && !a.ready; offSlot := s
    a.bits.data := dataOf(slotRef(s), beat)
    a.bits.last := beat === 1.U
    a.bits.err := false.B
    a.bits.tag.get := slotTag(s)
    when(a.fire && beat === 0.U) { passed := s =/= older && slotV(older) }
    when(a.fire) {
      beat := beat + 1.U; busy := beat === 0.U; cur := s
      when(beat === 1.U) { slotV(s) := false.B }
    }
  }

  // ---- monitor, per cluster: the beats it receives (through the injected fault, if any)
  for (c <- 0 until n) {
    val o = dut.io.resp(c)
    val valid = if (bug == XbarBug.Spurious && c == 0) o.valid || io.bugFire else o.valid
    val data = if (bug == XbarBug.Corrupt) Mux(io.bugFire, o.bits.data ^ 1.U, o.bits.data) else o.bits.data
    o.ready := !FormalEnv.stall(io.sinkStall(c), bounds.sinkStall)
    val fire = valid && o.ready
    io.beatTo(c) := fire
    val tag = o.bits.tag.get
    val beat = RegInit(0.U(1.W)); val answering = Reg(UInt(1.W))
    when(fire) {
      assert(holds(c)(tag), "a beat with no request of this cluster outstanding under its tag")
      when(beat =/= 0.U) { assert(tag === answering, "another tag's beat inside an answer") }
      assert(data === dataOf(held(c)(tag).childRef, beat), "a beat with another request's data")
      assert(o.bits.last === (beat === 1.U), "an answer with other beats than two")
      answering := tag
      beat := beat + 1.U
      when(beat === 1.U) { holds(c)(tag) := false.B }
    }
    if (bounds.live) for (t <- 0 until 2) when(holds(c)(t)) {
      assert(now - held(c)(t).time <= answerBound.U, s"a request not answered within $answerBound cycles")
    }
  }
}
