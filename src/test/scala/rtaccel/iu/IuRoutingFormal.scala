package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.config.{HwLimits, PlatformParams, RefFormat}
import rtaccel.formal.{AbstractMem, EnvBounds, FormalEnv, MemFree}
import rtaccel.mc.{FetchBeat, MemReq}

/** A fault put between the IU and the monitor, to show that each property can fail (docs/formal.md). */
sealed abstract class IuBug(val name: String)
object IuBug {
  case object None extends IuBug("none")
  /** a triangle result appears out of nothing: a response without a request */
  case object Spurious extends IuBug("spurious result")
  /** a box result carries the other TU's tag */
  case object Retag extends IuBug("wrong TU tag")
  /** bit 0 of a box result's first child reference flipped: not the node's data */
  case object Corrupt extends IuBug("corrupted child ref")
  /** a box result given again in the next cycle: a request answered twice */
  case object Duplicate extends IuBug("repeated box result")
  /** after the first box result, box results are suppressed: a node request never answered */
  case object Starve extends IuBug("starved box results")
}

/** The small configuration of the IU proofs: 2 TUs, M = 2 (64-byte nodes), leaves of 1..2 primitives, 256-bit
  * beats (2 per node, 2 per primitive), 2 jobs in flight, no divider stages (the triangle pipe's latency does not
  * change the routing), 12-bit addresses with the primitives at 0x200.
  */
object IuRoutingFormal {
  val beatBits = 256
  val addrBits = 12
  val primBase = 0x200
  // the pipes at their fixed stages (PIPELINE=none): the proof is about routing, and its depth grows with their latency
  val platform: PlatformParams = PlatformParams(tus = 2, m = 2, mppl = 2, divStages = 0, pipelining = rtaccel.config.Pipelining.Fixed,
    refs = RefFormat(nodeIdBits = 3, primIndexBits = 3, countBits = 1, levelBits = 0),
    hw = HwLimits(axiAddrBits = addrBits, iuOutstanding = 2))
}

/** IntersectionUnit with two free TUs (each presents a request with a free child reference and ray, keeps it until
  * taken and issues its next only after its answer, as a TU does), the memory side decoded like the MC (node id /
  * leaf first + count) and served by an AbstractMem, and a monitor that asserts:
  *  - no result without a request: a box result only for a TU waiting for a node, a triangle result only for a
  *    TU waiting for a leaf;
  *  - order and tags: box results follow the order in which node requests were taken, triangle results that of
  *    leaf requests (a FIFO of TU ids per kind), so no result goes to the wrong TU;
  *  - exactly once: one box result per node request, count triangle results per leaf with `last` on the final;
  *  - data: each child reference of a box result and the triangle id of each triangle result equal the abstract
  *    memory's words of that node / primitive; a node or primitive read with the magic beat poisoned has err set;
  *  - with bounded memory stalls (bounds.live): a TU's request is answered within `answerBound` cycles of being
  *    presented.
  */
class IuRoutingFormal(bounds: EnvBounds, answerBound: Int, bug: IuBug = IuBug.None) extends Module {
  import IuRoutingFormal._
  val p = platform
  private val f = p.refs
  private val tus = p.tus
  val io = IO(new Bundle {
    val want = Input(Vec(tus, Bool()))
    val cref = Input(Vec(tus, UInt(f.refBits.W)))
    val ray = Input(new RayData)
    val tmax = Input(UInt(32.W))
    val mem = Input(new MemFree(beatBits))
    val bugFire = Input(Bool())
    val answered = Output(Bool()) // a request answered (the randomized run's coverage)
  })
  val dut = Module(new IntersectionUnit(p, beatBits, p.tus))
  val now = FormalEnv.cycle(6)

  // ---- the memory side: FetchReq -> (addr, beats), decoded independently of the MC
  private val beatsBits = log2Ceil(2 * f.maxLeafPrims + 1)
  private def isLeaf(r: UInt): Bool = r(f.refBits - 1)
  private def count(r: UInt): UInt = r(f.primIndexBits + f.countBits - 1, f.primIndexBits) +& 1.U
  private def first(r: UInt): UInt = r(f.primIndexBits - 1, 0)
  private def nodeAddr(r: UInt): UInt = (r(f.nodeIdBits - 1, 0) << log2Ceil(p.nodeStrideBytes)).pad(addrBits)
  private def slotAddr(r: UInt, k: UInt): UInt = (primBase.U(addrBits.W) + ((first(r) +& k) << log2Ceil(p.primStrideBytes)).pad(addrBits))(addrBits - 1, 0)
  private val nodeBeats = p.nodeStrideBytes * 8 / beatBits
  private val primBeats = p.primStrideBytes * 8 / beatBits
  val mem = new AbstractMem(addrBits, beatsBits, beatBits, depth = 2, bounds)
  mem.free := io.mem
  val memReq = Wire(Decoupled(new MemReq(addrBits, beatsBits)))
  val ref = dut.io.mem.req.bits.childRef(f.refBits - 1, 0)
  memReq.valid := dut.io.mem.req.valid
  memReq.bits.addr := Mux(isLeaf(ref), slotAddr(ref, 0.U), nodeAddr(ref))
  memReq.bits.beats := Mux(isLeaf(ref), count(ref) * primBeats.U, nodeBeats.U)
  dut.io.mem.req.ready := memReq.ready
  mem.serve(memReq, dut.io.mem.resp)

  // ---- the results as the monitor sees them (through the injected fault, if any)
  val box = WireDefault(dut.io.box)
  val tri = WireDefault(dut.io.tri)
  val boxSeen = RegInit(false.B)
  when(box.valid) { boxSeen := true.B }
  bug match {
    case IuBug.None =>
    case IuBug.Spurious => when(io.bugFire) { tri.valid := true.B }
    case IuBug.Retag => when(io.bugFire) { box.bits.tu := ~dut.io.box.bits.tu }
    case IuBug.Corrupt => when(io.bugFire) { box.bits.cref(0) := dut.io.box.bits.cref(0) ^ 1.U }
    case IuBug.Duplicate =>
      val again = RegNext(dut.io.box.valid, false.B); val bits = RegNext(dut.io.box.bits)
      when(io.bugFire && again) { box.valid := true.B; box.bits := bits }
    case IuBug.Starve => when(boxSeen) { box.valid := false.B }
  }

  io.answered := box.valid || (tri.valid && tri.bits.last)

  // ---- order of the requests taken, per kind (each TU has at most one outstanding: depth tus)
  val nodeOrder = Module(new Queue(UInt(p.tuBits.W), tus))
  val leafOrder = Module(new Queue(UInt(p.tuBits.W), tus))
  nodeOrder.io.enq.valid := false.B; nodeOrder.io.enq.bits := DontCare
  leafOrder.io.enq.valid := false.B; leafOrder.io.enq.bits := DontCare
  nodeOrder.io.deq.ready := box.valid
  leafOrder.io.deq.ready := tri.valid && tri.bits.last

  // ---- the TUs
  for (i <- 0 until tus) {
    val busy = RegInit(false.B)     // a request presented or outstanding
    val taken = RegInit(false.B)    // ... and accepted by the IU
    val cref = Reg(UInt(f.refBits.W))
    val since = Reg(UInt(now.getWidth.W))
    val got = RegInit(0.U((f.countBits + 1).W)) // triangle results received for the leaf
    val port = dut.io.req(i)
    when(!busy && io.want(i)) { busy := true.B; taken := false.B; cref := io.cref(i); since := now; got := 0.U }
    port.valid := busy && !taken
    port.bits.tu := i.U
    port.bits.cref := cref.pad(32)
    port.bits.ray.foreach(_ := io.ray) // RAY_STORE=0 here
    port.bits.tmax := io.tmax
    when(port.fire) {
      taken := true.B
      when(isLeaf(cref)) { leafOrder.io.enq.valid := true.B; leafOrder.io.enq.bits := i.U }
        .otherwise { nodeOrder.io.enq.valid := true.B; nodeOrder.io.enq.bits := i.U }
    }
    val waiting = busy && taken
    when(box.valid && box.bits.tu === i.U) {
      assert(waiting && !isLeaf(cref), "a box result for a TU not waiting for a node")
      assert(nodeOrder.io.deq.valid && nodeOrder.io.deq.bits === i.U, "a box result out of request order")
      for (j <- 0 until p.m) {
        val w = 7 * j + 6 // the child ref word of slot j
        val b = w * 32 / beatBits; val pos = w % (beatBits / 32)
        when(mem.beatAddr(nodeAddr(cref), b.U) === mem.magicBeat) {
          assert(box.bits.cref(j) === mem.magicData(32 * pos + 31, 32 * pos), "a child ref differs from the memory")
        }
      }
      when(mem.magicErr && (0 until nodeBeats).map(b => mem.beatAddr(nodeAddr(cref), b.U) === mem.magicBeat).reduce(_ || _)) {
        assert(box.bits.err, "a node read with an error not flagged")
      }
      busy := false.B
    }
    when(tri.valid && tri.bits.tu === i.U) {
      assert(waiting && isLeaf(cref), "a triangle result for a TU not waiting for a leaf")
      assert(leafOrder.io.deq.valid && leafOrder.io.deq.bits === i.U, "a triangle result out of request order")
      assert(tri.bits.last === (got === count(cref) - 1.U), "a leaf answered with other than its primitive count")
      val w = 9 // the triangle id word of a primitive slot
      val b = w * 32 / beatBits; val pos = w % (beatBits / 32)
      val slot = slotAddr(cref, got)
      when(mem.beatAddr(slot, b.U) === mem.magicBeat) {
        assert(tri.bits.prim === mem.magicData(32 * pos + 31, 32 * pos), "a triangle id differs from the memory")
      }
      when(mem.magicErr && (0 until primBeats).map(b => mem.beatAddr(slot, b.U) === mem.magicBeat).reduce(_ || _)) {
        assert(tri.bits.err, "a primitive read with an error not flagged")
      }
      got := got + 1.U
      when(tri.bits.last) { busy := false.B }
    }
    if (bounds.live) when(busy) { assert(now - since <= answerBound.U, s"a TU request not answered within $answerBound cycles") }
  }
  when(box.valid) { assert(box.bits.tu < tus.U, "a box result for no TU") }
  when(tri.valid) { assert(tri.bits.tu < tus.U, "a triangle result for no TU") }
}
