package rtaccel.cache

import chisel3._
import chisel3.util._
import rtaccel.cache.hw.{CacheGeometry, CachePath}
import rtaccel.config.{CacheParams, HwLimits, PlatformParams, RefFormat}
import rtaccel.formal.{AbstractMem, EnvBounds, FormalEnv, MemFree}
import rtaccel.mc.{AxiParams, FetchBeat, McGeometry}

/** A fault put between the cache path and the monitor, to show that each property can fail (docs/formal.md). */
sealed abstract class PathBug(val name: String)
object PathBug {
  case object None extends PathBug("none")
  /** a beat appears while the path has nothing valid: a response without a request */
  case object Spurious extends PathBug("spurious beat")
  /** a beat's data bit 0 flipped: wrong data */
  case object Corrupt extends PathBug("corrupted data")
  /** `last` dropped from a beat: a response runs into the next (answered with the wrong beats / not once) */
  case object NoLast extends PathBug("lost last")
  /** once a request has been answered, output is held back for good: never answered */
  case object Starve extends PathBug("starved output")
  /** inside the design: TAG_FORWARD=1 takes a lookup per cycle but reads the set as the RAM has it, missing the write
    * of the decision before (a hit on the line that decision just evicted reads the other line's data) */
  case object NoForward extends PathBug("one lookup per cycle without forwarding")
}

/** The small configuration the cache-path proofs run on: lines of two 32-bit beats (8-byte stride: the data
  * path's width does not change its control, and narrow beats keep the solver fast), 2 tickets, 2 queued misses,
  * a 3-beat output queue (tagged: 2 clean hits queued), 16-bit byte addresses.
  */
object CachePathFormal {
  val axi: AxiParams = AxiParams(addrBits = 16, dataBits = 32)
  val lineBeats = 2
  /** tagged: RESP_ORDER=tagged with two requesters (TUs), so requests and beats carry a 1-bit tag */
  def platform(c: CacheParams, tagged: Boolean = false): PlatformParams = PlatformParams(m = 2, mppl = 1, nodeCache = c,
    tus = if (tagged) 2 else 32, respByPath = tagged, respTagged = tagged,
    refs = RefFormat(nodeIdBits = 8, primIndexBits = 8, countBits = 0, levelBits = 0),
    hw = HwLimits(axiAddrBits = 16, cacheTickets = 2, cacheMissQueue = 2, cacheOutQueue = 3, cacheHitQueue = 2))
  /** requests the path can hold unanswered: the lookup register (and PIPELINE's stage 2 after it), every ticket (with
    * PIPELINE: two more in the head ticket's register slice), one per beat of the output queue */
  def maxOutstanding(p: PlatformParams): Int = {
    val sliced = p.cacheSliceCycles > 0
    1 + (if (sliced) 1 else 0) + p.hw.cacheTickets + (if (sliced) 2 else 0) + p.hw.cacheOutQueue
  }
}

/** CachePath (node geometry) between free requests of `lineBits`-bit line numbers, an AbstractMem and a free
  * consumer, with a monitor that asserts:
  *  - no response beat without a request outstanding;
  *  - responses leave in request order, each with exactly its request's beats (`last` on its final beat only),
  *    so every accepted request is answered at most once;
  *  - the data and error bit of every beat equal the abstract memory's at that beat's address;
  *  - at most maxOutstanding requests are ever unanswered;
  *  - with bounded stalls (bounds.live): the oldest request is answered within `answerBound` cycles of its
  *    acceptance, so every accepted request is answered exactly once.
  * tagged (RESP_ORDER=tagged, hits under misses): two requesters, each with at most one request in flight (as a
  * TU), and answers in any order; the monitor keeps each requester's request and asserts instead that every beat
  * belongs to a request outstanding under its tag, that an answer's beats come back to back (no other tag in
  * between), that each answer has exactly its request's beats and the memory's data, and that each request is
  * answered within `answerBound` cycles of its acceptance.
  * CachePath's own assertions are checked too.
  */
class CachePathFormal(c: CacheParams, bounds: EnvBounds, answerBound: Int, bug: PathBug = PathBug.None,
                      lineBits: Int = 4, tagged: Boolean = false, forward: Boolean = false) extends Module {
  val p = CachePathFormal.platform(c, tagged).copy(tagForward = forward)
  val g = McGeometry(p, CachePathFormal.axi)
  val cg = CacheGeometry(c, 1, CachePathFormal.lineBeats, CachePathFormal.lineBeats * g.axi.beatBytes)
  val io = IO(new Bundle {
    val reqValid = Input(Bool())
    val reqLine = Input(UInt(lineBits.W))
    val reqLevel = Input(UInt(p.hw.levelCodeBits.W))
    val reqTag = Input(UInt(1.W)) // tagged: the requester
    val maxLevel = Input(UInt(p.hw.levelCodeBits.W))
    val sinkStall = Input(Bool())
    val mem = Input(new MemFree(g.axi.dataBits))
    val bugFire = Input(Bool()) // when the injected fault strikes (unused without one)
    val answered = Output(Bool()) // an answer's last beat left (the randomized run's coverage)
  })
  // PathBug.NoForward: TAG_FORWARD's one lookup per cycle without the forwarding of the set just written
  val dut = Module(new CachePath(g, cg, forwardWrites = bug != PathBug.NoForward))
  // tagged: a requester with a request in flight asks for nothing more (set by the monitor below)
  val busyTag = WireDefault(false.B)
  dut.io.in.valid := io.reqValid && !busyTag
  for (t <- dut.io.in.bits.tag) t := io.reqTag
  dut.io.in.bits.line := io.reqLine.pad(32)
  dut.io.in.bits.addr := (io.reqLine.pad(g.axi.addrBits) << log2Ceil(cg.strideBytes))(g.axi.addrBits - 1, 0)
  dut.io.in.bits.beats := cg.lineBeats.U
  dut.io.in.bits.level := io.reqLevel
  dut.io.primBase := (cg.lines * cg.strideBytes).U
  dut.io.maxLevel := io.maxLevel
  dut.io.clearStats := false.B

  val mem = new AbstractMem(g.axi.addrBits, g.beatsBits, g.axi.dataBits, depth = 2, bounds)
  mem.free := io.mem
  mem.serve(dut.io.memReq, dut.io.memResp)

  // ---- the output as the monitor sees it (through the injected fault, if any)
  val out = Wire(Decoupled(g.respBeat))
  out.bits := dut.io.out.bits
  out.valid := dut.io.out.valid
  dut.io.out.ready := out.ready
  val answeredOnce = RegInit(false.B)
  bug match {
    case PathBug.None | PathBug.NoForward => // NoForward: inside the design
    case PathBug.Spurious => out.valid := dut.io.out.valid || io.bugFire
    case PathBug.Corrupt => when(io.bugFire) { out.bits.data := dut.io.out.bits.data ^ 1.U }
    case PathBug.NoLast => when(io.bugFire) { out.bits.last := false.B }
    case PathBug.Starve => when(answeredOnce) { out.valid := false.B; dut.io.out.ready := false.B }
  }
  out.ready := !FormalEnv.stall(io.sinkStall, bounds.sinkStall)
  io.answered := out.fire && out.bits.last

  // ---- monitor
  val now = FormalEnv.cycle(6)
  class Pending extends Bundle {
    val addr = UInt(g.axi.addrBits.W)
    val beats = UInt(g.beatsBits.W)
    val time = UInt(now.getWidth.W)
  }
  val pending = Wire(new Pending)
  pending.addr := dut.io.in.bits.addr
  pending.beats := dut.io.in.bits.beats
  pending.time := now
  val beat = RegInit(0.U(g.beatsBits.W))
  def checkBeat(head: Pending): Unit = {
    assert(out.bits.last === (beat === head.beats - 1.U), "a response with other beats than its request")
    when(mem.beatAddr(head.addr, beat) === mem.magicBeat) {
      assert(out.bits.data === mem.magicData && out.bits.err === mem.magicErr, "a beat differs from the memory")
    }
    beat := Mux(out.bits.last, 0.U, beat + 1.U)
    when(out.bits.last) { answeredOnce := true.B }
  }
  def timely(head: Pending): Unit = assert(now - head.time <= answerBound.U, s"a request not answered within $answerBound cycles")
  if (!tagged) {
    // a shadow FIFO of the accepted requests (address, beats, acceptance time)
    val pend = Module(new Queue(new Pending, CachePathFormal.maxOutstanding(p)))
    pend.io.enq.valid := dut.io.in.fire
    pend.io.enq.bits := pending
    when(dut.io.in.fire) { assert(pend.io.enq.ready, "more requests unanswered than the path can hold") }
    val head = pend.io.deq.bits
    when(out.fire) {
      assert(pend.io.deq.valid, "a response beat with no request outstanding")
      checkBeat(head)
    }
    pend.io.deq.ready := out.fire && out.bits.last
    if (bounds.live) when(pend.io.deq.valid) { timely(head) }
  } else {
    // each requester's request in flight, and the tag of the answer under way (between its first and last beat)
    val held = Reg(Vec(2, new Pending)); val holds = RegInit(VecInit(false.B, false.B))
    busyTag := holds(io.reqTag)
    val tag = out.bits.tag.get
    val midAnswer = beat =/= 0.U; val answering = Reg(UInt(1.W))
    when(out.fire) {
      assert(holds(tag), "a response beat with no request outstanding under its tag")
      when(midAnswer) { assert(tag === answering, "another tag's beat inside an answer") }
      answering := tag
      checkBeat(held(tag))
      when(out.bits.last) { holds(tag) := false.B }
    }
    when(dut.io.in.fire) { held(io.reqTag) := pending; holds(io.reqTag) := true.B }
    if (bounds.live) for (t <- 0 until 2) when(holds(t)) { timely(held(t)) }
  }
}
