package rtaccel.cache.hw

import chisel3._
import chisel3.util._
import rtaccel.config.{CacheParams, PlatformParams}
import rtaccel.mc.{AxiParams, AxiReadMaster, FetchBeat, FetchReq, McCounters, McGeometry, MemoryController}

/** NODE_BANKS = k: one node cache of NODE_CACHE entries shared by the IUS clusters, in k banks (docs/caches.md,
  * "Shared node cache"). With a cache per cluster, every cluster holds its own copy of the top of the tree and
  * misses on what another cluster fetched; one shared cache holds each node once, for the BRAM of one cache.
  *
  * Bank b holds the nodes whose id is b modulo k; each bank is a node-only memory controller (an AXI4 master of
  * its own) whose node path is a CachePath of entries / k lines indexed by id / k, so the k banks together are one
  * cache of the configured sets (rtaccel.cache.CacheModel with banks = k replays exactly this). Each bank looks up
  * one request per tag cycle, so k banks take k lookups per cycle (TAG_FORWARD=1) from all the clusters together.
  *
  * Requests: bank b takes one request per cycle from the clusters whose head request is for it, round robin; the
  * request's tag gains the cluster's number above the TU's index. Answers: every bank answers in any order
  * (RESP_ORDER=tagged, which PlatformParams requires), each answer's beats back to back; cluster c takes whole
  * answers from the banks round robin and strips the cluster bits. Nothing waits on anything but the cluster's
  * own IU, which takes node beats for any of its TUs, so no bank waits on another.
  */
class NodeBanks(p: PlatformParams, axiP: AxiParams) extends Module {
  private val (k, n) = (p.nodeBanks, p.ius)
  require(p.nodeShared && p.respTagged, "NodeBanks needs NODE_BANKS > 0 and RESP_ORDER=tagged (PlatformParams checks both)")
  private val g = McGeometry(p, axiP, p.clusterBits)
  private val beat = new FetchBeat(axiP.dataBits, p.respTagBits)
  val io = IO(new Bundle {
    val req = Vec(n, Flipped(Decoupled(new FetchReq(p.respTagBits)))) // cluster c's node requests
    val resp = Vec(n, Decoupled(beat)) // cluster c's node answers, tagged by its TU
    val primBase = Input(UInt(axiP.addrBits.W))
    val maxLevel = Input(UInt(p.hw.levelCodeBits.W))
    val clearCounters = Input(Bool())
    val axi = Vec(k, new AxiReadMaster(axiP)) // one master per bank
    val counters = Output(Vec(k, new McCounters(p.hw.mcCounterBits)))
    val tap = Output(Vec(k, Valid(UInt(32.W)))) // the reference each bank accepts (its access order)
  })
  // a bank's cache: entries / k lines of the configured ways and policy (PlatformParams checks k divides the sets)
  private val bankCache = p.nodeCache.copy(entries = p.nodeCache.entries / k)
  val banks = Seq.tabulate(k)(b => Module(new MemoryController(p, axiP, CachePath.factory(bankCache, CacheParams(), p.mppl),
    respBufferBeats = 2 * g.maxBeats, extraTagBits = p.clusterBits, nodeLineShift = p.nodeBankBits)).suggestName(s"bank_$b"))

  val xbar = Module(new BankCrossbar(n, k, p.respTagBits, p.nodeBankBits, axiP.dataBits))
  xbar.io.req <> io.req
  // with PIPELINE a register slice on each side of the answers' crossbar: a bank's answer tag ran through the
  // cluster's choice back into the bank's ready (9 LUT levels on xc5v, the deepest path of the LX330T configuration
  // in docs/roofline.md), and the crossbar's valid on into the IU (8)
  for ((out, c) <- io.resp.zipWithIndex) out <> rtaccel.arb.Slice(p, xbar.io.resp(c))
  for ((bank, b) <- banks.zipWithIndex) {
    // with PIPELINE a register slice between the crossbar and the bank: a cluster's request ran through the crossbar's
    // choice into the bank's lookup in one cycle (10 LUT levels on xc5v, the deepest path of the shared cache)
    bank.io.req <> rtaccel.arb.Slice(p, xbar.io.bankReq(b))
    xbar.io.bankResp(b) <> rtaccel.arb.Slice(p, bank.io.resp)
    bank.io.primBase := io.primBase
    bank.io.maxLevel := io.maxLevel
    bank.io.clearCounters := io.clearCounters
    // a bank sees node references only: its primitive stream stays empty
    bank.io.primResp.get.ready := true.B
    assert(!bank.io.primResp.get.valid, "NodeBanks: a bank answered a primitive request")
    when(bank.io.req.fire) { assert(!bank.io.req.bits.childRef(p.refs.refBits - 1), "NodeBanks: a leaf reference reached a node bank") }
    io.axi(b) <> bank.io.axi
    io.counters(b) := bank.io.counters
    io.tap(b).valid := bank.io.req.fire
    io.tap(b).bits := bank.io.req.bits.childRef
  }
}

/** The crossbar of NodeBanks between n clusters and k banks (its own module so that the routing can be checked on
  * abstract banks: BankCrossbarSimSpec, docs/formal.md). Requests: bank b takes, round robin, one request per cycle
  * from the clusters whose head request's reference has b in its low `bankBits` bits, with the cluster's number
  * put above the `innerBits` tag. Answers: each bank's beats go to the cluster named in their tag, whole answers at
  * a time (round robin among the banks with an answer for that cluster), with the inner tag only.
  */
class BankCrossbar(n: Int, k: Int, innerBits: Int, bankBits: Int, dataBits: Int) extends Module {
  require(n >= 1 && k >= 1 && innerBits >= 1 && (1 << bankBits) == k, s"BankCrossbar: $n clusters, $k banks, $bankBits bank bits")
  private val clusterBits = if (n > 1) log2Ceil(n) else 0
  private val beat = new FetchBeat(dataBits, innerBits)
  private val bankBeat = new FetchBeat(dataBits, innerBits + clusterBits)
  val io = IO(new Bundle {
    val req = Vec(n, Flipped(Decoupled(new FetchReq(innerBits))))
    val resp = Vec(n, Decoupled(beat))
    val bankReq = Vec(k, Decoupled(new FetchReq(innerBits + clusterBits)))
    val bankResp = Vec(k, Flipped(Decoupled(bankBeat)))
  })

  // ---- requests: clusters -> banks (the bank number is the node id's low bits, which are the reference's)
  private def bankOf(r: FetchReq): UInt = if (k == 1) 0.U else r.childRef(bankBits - 1, 0)
  private val grants = for ((out, b) <- io.bankReq.zipWithIndex) yield {
    val arb = Module(new RRArbiter(new FetchReq(innerBits + clusterBits), n))
    for ((in, c) <- io.req.zipWithIndex) {
      arb.io.in(c).valid := in.valid && bankOf(in.bits) === b.U
      arb.io.in(c).bits.childRef := in.bits.childRef
      arb.io.in(c).bits.tag.get := (if (n == 1) in.bits.tag.get else Cat(c.U(clusterBits.W), in.bits.tag.get))
    }
    out <> arb.io.out
    arb.io.in.map(_.ready)
  }
  // a cluster's request is offered to one bank only, so that bank's grant is its ready
  for ((in, c) <- io.req.zipWithIndex) in.ready := VecInit(grants.map(_(c)))(bankOf(in.bits))

  // ---- answers: banks -> clusters, a whole answer at a time
  private def clusterOf(t: UInt): UInt = if (n == 1) 0.U else t(innerBits + clusterBits - 1, innerBits)
  private val takes = for ((out, c) <- io.resp.zipWithIndex) yield {
    val arb = Module(new RRArbiter(beat, k))
    // busy: an answer of bank `cur` has begun; only its beats may follow until its last
    val busy = RegInit(false.B); val cur = RegInit(0.U(math.max(1, log2Ceil(k)).W))
    // open(b): bank b may give this cluster a beat now. The arbiter's ready alone may be high for an input it holds
    // invalid, so a bank's ready takes the same condition (else a masked bank's beat would leave unseen)
    def open(b: Int): Bool = !busy || cur === b.U
    for ((a, b) <- io.bankResp.zipWithIndex) {
      arb.io.in(b).valid := a.valid && clusterOf(a.bits.tag.get) === c.U && open(b)
      arb.io.in(b).bits.data := a.bits.data
      arb.io.in(b).bits.last := a.bits.last
      arb.io.in(b).bits.err := a.bits.err
      arb.io.in(b).bits.tag.get := a.bits.tag.get(innerBits - 1, 0)
    }
    out <> arb.io.out
    when(out.fire) { busy := !out.bits.last; cur := arb.io.chosen }
    arb.io.in.zipWithIndex.map { case (in, b) => in.ready && open(b) }
  }
  for ((a, b) <- io.bankResp.zipWithIndex) a.ready := VecInit(takes.map(_(b)))(clusterOf(a.bits.tag.get))
}
