package rtaccel.mc

import java.nio.file.Files
import scala.collection.mutable.ArrayBuffer
import scala.util.Random
import chisel3._
import chisel3.util.Queue
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.bvh.{MemoryImage, RefCodec}
import rtaccel.config.{PlatformParams, RefFormat}
import rtaccel.host.{ImageFile, MemTestImages}
import rtaccel.sim.{DramConfig, DramModel}

/** A stand-in for a cache that makes DRAM order differ from request order: its requests wait in a queue and
  * leave only on cycles an LFSR allows (so the other path's later requests overtake them).
  */
class StallingPath(g: McGeometry, seed: Int) extends FetchPathModule(g) {
  val inQ = Queue(io.in, 4)
  val gate = chisel3.util.random.LFSR(8, true.B, Some(BigInt(seed)))(2, 0) === 0.U // ~1 cycle in 8
  io.memReq.valid := inQ.valid && gate
  io.memReq.bits.addr := inQ.bits.addr
  io.memReq.bits.beats := inQ.bits.beats
  inQ.ready := io.memReq.ready && gate
  io.out <> io.memResp
  io.stats := 0.U.asTypeOf(io.stats)
}

/** McHarness's ports (named, so that a test's check after the run takes them from the firtool-built shell). */
class McHarnessIO(p: PlatformParams, axi: AxiParams) extends Bundle {
  val req = Flipped(chisel3.util.Decoupled(new FetchReq(p.respTagBits)))
  val resp = chisel3.util.Decoupled(new FetchBeat(axi.dataBits, p.respTagBits))
  val primResp = if (p.respByPath) Some(chisel3.util.Decoupled(new FetchBeat(axi.dataBits, p.respTagBits))) else None
  val primBase = Input(UInt(axi.addrBits.W))
  val maxLevel = Input(UInt(4.W))
  val counters = Output(new McCounters(p.hw.mcCounterBits))
  val arBursts = Output(UInt(32.W))
  val maxLen = Output(UInt(8.W))
  val badBurst = Output(Bool())
  val overtaken = Output(UInt(32.W))
}

/** MC + DRAM model, with AR/R traffic counters for the test. */
class McHarness(p: PlatformParams, val axi: AxiParams, words: Int, hex: String, cfg: DramConfig,
                pathFactory: (McGeometry, Int) => FetchPathModule = FetchPath.passThrough,
                respBufferBeats: Int = 0, errorSticky: Boolean = true) extends Module {
  val mc = Module(new MemoryController(p, axi, pathFactory = pathFactory, respBufferBeats = respBufferBeats))
  val dram = Module(new DramModel(axi, words, hex, cfg))
  dram.io.axi <> mc.io.axi
  dram.io.sticky := errorSticky.B
  val io = IO(new McHarnessIO(p, axi))
  // Cycles in which DRAM delivers a beat for a different path than the one the response mux waits on
  // (RESP_ORDER=request; with RESP_ORDER=path there is no single awaited path, and the count stays 0).
  import chisel3.util.experimental.BoringUtils
  val overtaken = RegInit(0.U(32.W))
  for (o <- mc.order) {
    val orderValid = BoringUtils.bore(o.io.deq.valid)
    val orderPath = BoringUtils.bore(o.io.deq.bits)
    val memPath = BoringUtils.bore(mc.memOrder.io.deq.bits.path)
    when(mc.io.axi.r.fire && orderValid && orderPath =/= memPath) { overtaken := overtaken + 1.U }
  }
  io.overtaken := overtaken
  mc.io.req <> io.req
  io.resp <> mc.io.resp
  for ((h, m) <- io.primResp.zip(mc.io.primResp)) h <> m
  mc.io.primBase := io.primBase
  mc.io.maxLevel := io.maxLevel
  mc.io.clearCounters := false.B
  io.counters := mc.io.counters
  val ars = RegInit(0.U(32.W))
  val maxLen = RegInit(0.U(8.W))
  val bad = RegInit(false.B)
  val ar = mc.io.axi.ar
  when(ar.fire) {
    ars := ars + 1.U
    when(ar.bits.len > maxLen) { maxLen := ar.bits.len }
    // AXI4: an INCR burst must not cross a 4 KB boundary
    val start = ar.bits.addr(11, 0)
    val bytes = (ar.bits.len +& 1.U) << chisel3.util.log2Ceil(axi.beatBytes)
    when((start +& bytes) > 4096.U || ar.bits.burst =/= 1.U || ar.bits.id =/= 0.U) { bad := true.B }
  }
  io.arBursts := ars
  io.maxLen := maxLen
  io.badBurst := bad
}

/** Random-traffic runs of the MC + DRAM model: every beat is checked against the image bytes, in order. */
trait McCases extends AnyFlatSpec with ChiselScalatestTester {
  import MemTestImages._

  /** Every fetchable ref of the image: the root (ref 0 = node 0) and every non-empty child. */
  /** RESP_ORDER=path: node beats of the running case that left while an older leaf was still unanswered;
    * tagged: answers that began ahead of an older request's on their port (set before afterRun, which may check it). */
  var overtakes = 0

  def allRefs(img: MemoryImage): IndexedSeq[Int] =
    0 +: (for (n <- 0 until img.numNodes; j <- 0 until img.p.m if img.childRef(n, j) != 0) yield img.childRef(n, j))

  def runCase(name: String, dataBits: Int, tris: Int, nReqs: Int, cfg: DramConfig, reqProb: Double, readyProb: Double,
              seed: Long, extraRefs: MemoryImage => Seq[Int] = _ => Nil, refFormat: Option[RefFormat] = None,
              pathFactory: (McGeometry, Int) => FetchPathModule = FetchPath.passThrough,
              respBufferBeats: Int = 0, maxCycles: Int = 30000, maxLevel: Int = 15,
              pick: (Random, IndexedSeq[Int]) => Int = (r, pool) => pool(r.nextInt(pool.length)),
              afterRun: (McHarnessIO, Seq[Int], MemoryImage) => Unit = (_, _, _) => (),
              respByPath: Boolean = false, tagged: Int = 0,
              tagForward: Boolean = false, memRetries: Int = -1, errorSticky: Boolean = true): Unit =
    it should name in {
      val axi = AxiParams(dataBits = dataBits)
      val img = image(seed, tris, refFormat)
      // tagged > 0: RESP_ORDER=tagged with that many requesters (the TUs), each with at most one request in flight
      val p = (if (tagged > 0) img.p.copy(tus = tagged, respByPath = true, respTagged = true) else img.p.copy(respByPath = respByPath))
        .copy(tagForward = tagForward)
        // MEM_RETRIES: the preset's where the MC has response buffers (re-reads need them), else 0
        .copy(memRetries = if (memRetries >= 0) memRetries else if (respBufferBeats > 0) img.p.memRetries else 0)
      val codec = new RefCodec(p.refs)
      val hex = Files.createTempDirectory("mc").resolve("img.hex").toAbsolutePath
      val lay = ImageFile.write(img, axi, hex)
      val bytes = dramBytes(img, lay, axi)
      val r = new Random(seed)
      val pool = allRefs(img)
      val refs = extraRefs(img) ++ Seq.fill(nReqs)(pick(r, pool))
      def span(ref: Int): (Long, Int) =
        if (codec.isPrim(ref)) (lay.primBaseBytes + 64L * codec.firstPrim(ref), 64 * codec.count(ref))
        else (codec.nodeId(ref).toLong * p.nodeStrideBytes, p.nodeStrideBytes)
      // DRAM errors (cfg.errorThreshold): what each request's beats carry, and the re-reads the MC makes. Every read
      // reaches DRAM (no cache here) in its path's request order, and the two paths' beats never overlap, so the
      // transient errors a read spends are known from the request order: a read fails if it holds a poisoned beat
      // not spent yet (sticky: any poisoned beat); it is re-read min(1, MEM_RETRIES) times if transient (the re-read is
      // clean), MEM_RETRIES times if sticky; the beats delivered are inverted where the last read failed.
      val faults = rtaccel.model.MemFaults(cfg.errorThreshold, cfg.errorSeed, axi.beatBytes, 64, 0, 64)
      val spent = scala.collection.mutable.Set[Long]()
      val inverted = Array.fill(refs.length)(Set.empty[Long]); var expectRetries = 0L; var reReadBeats = 0L
      for (j <- refs.indices) {
        val (a, n) = span(refs(j))
        val bad = (a / axi.beatBytes until (a + n) / axi.beatBytes).filter(faults.beatBad).toSet
        val failing = if (errorSticky) bad else bad -- spent
        spent ++= bad
        if (failing.nonEmpty) {
          val k = if (errorSticky) p.memRetries else math.min(1, p.memRetries)
          expectRetries += k; reReadBeats += k * (n / axi.beatBytes)
        }
        inverted(j) = if (errorSticky || p.memRetries == 0) failing else Set.empty
      }
      val allOnes = (BigInt(1) << axi.dataBits) - 1
      // each beat with the index of the request it answers
      def beatsOf(ix: Seq[Int]) = ix.flatMap { j =>
        val (a, n) = span(refs(j)); val k = n / axi.beatBytes
        (0 until k).map { i =>
          val d = beat(bytes, a + i * axi.beatBytes, axi)
          ((if (inverted(j)(a / axi.beatBytes + i)) d ^ allOnes else d, i == k - 1), j)
        }
      }
      // RESP_ORDER=request: one stream of every beat in request order; path: node beats and leaf beats, each in
      // its own request order
      val (leafIx, nodeIx) = refs.indices.partition(j => codec.isPrim(refs(j)))
      val streams = if (p.respByPath) Seq(beatsOf(nodeIx), beatsOf(leafIx)) else Seq(beatsOf(refs.indices))
      val expected = streams.flatten.map(_._1)
      // tagged: which request each requester has in flight, and per port the answer under way (tag, request, beat)
      val inFlight = Array.fill(math.max(1, tagged))(-1)
      val underWay = Array.fill(streams.length)(Option.empty[(Int, Int, Int)])
      var tag = 0
      def harness = new McHarness(p, axi, lay.words, hex.toString, cfg, pathFactory, respBufferBeats, errorSticky)
      def drive(dut: { def io: McHarnessIO; def clock: Clock }): Unit = {
        dut.clock.setTimeout(0)
        dut.io.primBase.poke(lay.primBaseBytes.U)
        dut.io.maxLevel.poke(maxLevel.U)
        val ports = dut.io.resp +: dut.io.primResp.toSeq
        val got = streams.map(_ => ArrayBuffer[(BigInt, Boolean)]())
        val done = Array.fill(refs.length)(false)
        var next = 0; var presenting = false; var cyc = 0
        var maxOutstanding = 0
        var overtook = 0 // node beats that left while an older leaf was unanswered (RESP_ORDER=path)
        while (got.map(_.length).sum < expected.length) {
          assert(cyc < maxCycles, s"timeout after ${got.map(_.length).sum}/${expected.length} beats")
          val free = inFlight.indices.filter(inFlight(_) < 0)
          if (!presenting && next < refs.length && (tagged == 0 || free.nonEmpty) && r.nextDouble() < reqProb) {
            presenting = true; if (tagged > 0) tag = free(r.nextInt(free.length))
          }
          dut.io.req.valid.poke(presenting.B)
          if (presenting) dut.io.req.bits.childRef.poke((refs(next) & 0xffffffffL).U)
          dut.io.req.bits.tag.foreach(_.poke(tag.U))
          for (((port, g), k) <- ports.zip(got).zipWithIndex) {
            val ready = r.nextDouble() < readyProb
            port.ready.poke(ready.B)
            val fired = ready && port.valid.peek().litToBoolean
            lazy val b = (port.bits.data.peek().litValue, port.bits.last.peek().litToBoolean)
            if (fired && tagged > 0) {
              // each beat belongs to the request in flight under its tag, beats of one answer back to back
              val t = port.bits.tag.get.peek().litValue.toInt
              val (t0, j, i) = underWay(k).getOrElse {
                assert(t < tagged && inFlight(t) >= 0, s"port $k: a beat tagged $t, which has no request in flight (cycle $cyc)")
                val j = inFlight(t)
                assert(codec.isPrim(refs(j)) == (k == 1), s"port $k: request $j (tag $t) answered on the other kind's port")
                if (inFlight.exists(o => o >= 0 && o < j && codec.isPrim(refs(o)) == (k == 1))) overtook += 1
                (t, j, 0)
              }
              assert(t == t0, s"port $k: a beat tagged $t inside the answer to tag $t0 (request $j, cycle $cyc): not back to back")
              val want = beatsOf(Seq(j))
              assert(i < want.length, s"port $k: request $j (tag $t) got a beat after its last")
              assert(b == want(i)._1, s"port $k: beat $i of request $j (tag $t, cycle $cyc) differs")
              g += b
              if (b._2) { done(j) = true; inFlight(t) = -1; underWay(k) = None } else underWay(k) = Some((t, j, i + 1))
            } else if (fired) {
              val i = g.length
              assert(i < streams(k).length, s"stream $k: a beat after its last expected one (cycle $cyc)")
              val (want, j) = streams(k)(i)
              assert(b == want, s"stream $k beat $i (request $j, cycle $cyc) differs")
              g += b
              if (b._2) done(j) = true
              if (k == 0 && respByPath && leafIx.exists(l => l < j && !done(l))) overtook += 1
            }
          }
          if (presenting && dut.io.req.ready.peek().litToBoolean) { if (tagged > 0) inFlight(tag) = next; presenting = false; next += 1 }
          maxOutstanding = math.max(maxOutstanding, next - done.count(identity))
          dut.clock.step(); cyc += 1
        }
        dut.clock.step(5)
        for (port <- ports) assert(!port.valid.peek().litToBoolean, "extra beats after the last expected one")
        val leaves = refs.filter(codec.isPrim)
        val prims = leaves.map(codec.count).sum
        val totalBytes = refs.map(span(_)._2.toLong).sum
        assert(dut.io.counters.nodeRequests.peek().litValue == refs.length - leaves.length)
        assert(dut.io.counters.leafRequests.peek().litValue == leaves.length)
        assert(dut.io.counters.primsRequested.peek().litValue == prims)
        assert(dut.io.counters.bytesRequested.peek().litValue == totalBytes)
        if (pathFactory eq FetchPath.passThrough) assert(dut.io.counters.busyBeats.peek().litValue == expected.length + reReadBeats)
        assert(!dut.io.badBurst.peek().litToBoolean, "an AR burst crossed 4 KB or had a bad id/burst type")
        val bursts = dut.io.arBursts.peek().litValue
        info(f"${refs.length} refs (${leaves.length} leaves, $prims prims), ${expected.length} beats in $cyc cycles " +
          f"(${totalBytes.toDouble / cyc}%.2f B/cycle), $bursts AR bursts, max len ${dut.io.maxLen.peek().litValue}, " +
          s"max outstanding $maxOutstanding")
        if (pathFactory eq FetchPath.passThrough) assert(bursts >= refs.length) // a cache serves hits without DRAM
        if (cfg.errorThreshold > 0) {
          val (retries, errBeats) = (dut.io.counters.retries.peek().litValue, dut.io.counters.readErrors.peek().litValue)
          info(s"$errBeats beats answered with an error, $retries re-reads (expected $expectRetries)")
          assert(retries == expectRetries, s"$retries re-reads, expected $expectRetries")
        } else assert(dut.io.counters.retries.peek().litValue == 0)
        val overtaken = dut.io.overtaken.peek().litValue
        info(s"$overtaken beats arrived for the other path than the one awaited")
        // response buffers let one pass-through path's reads go ahead while the other's wait for room
        if ((pathFactory eq FetchPath.passThrough) && respBufferBeats == 0) assert(overtaken == 0)
        if (tagged > 0) info(s"$overtook answers began ahead of an older request's on their port")
        else if (respByPath) info(s"$overtook node beats left ahead of an older unanswered leaf")
        overtakes = overtook
        afterRun(dut.io, refs, img)
      }
      val mc = rtaccel.TestSim.firtool(s"MemoryControllerSpec/${name.filter(_.isLetterOrDigit).take(80)}")(harness)(_.io)
      test(mc.gen()).withAnnotations(mc.annotations)(drive(_))
    }
}

class MemoryControllerSpec extends McCases {

  "MemoryController" should "emit SystemVerilog for the paper preset" in {
    val p = rtaccel.config.Presets.paper2017
    val sv = _root_.circt.stage.ChiselStage.emitSystemVerilog(new MemoryController(p, AxiParams(), respBufferBeats = 2 * McGeometry(p, AxiParams()).maxBeats),
      firtoolOpts = Array("-disable-all-randomization", "-strip-debug-info"))
    val out = java.nio.file.Paths.get("build/verilog/MemoryController.sv")
    Files.createDirectories(out.getParent)
    Files.writeString(out, sv)
    assert(sv.contains("module MemoryController") && sv.contains("module BurstSplitter"))
  }

  behavior of "MemoryController with DramModel"

  runCase("return image bytes in request order (256-bit, random latency and backpressure)", dataBits = 256, tris = 400,
    nReqs = 120, DramConfig(12, 4, 1, randomExtraLatency = 15, seed = 5), reqProb = 0.8, readyProb = 0.6, seed = 21)
  runCase("keep up with a saturated DRAM and many outstanding requests (paper timing)", dataBits = 256, tris = 300,
    nReqs = 100, DramConfig.paper, reqProb = 1.0, readyProb = 1.0, seed = 22)
  // 32-bit bus, 5-bit counts: a 32-primitive leaf is 512 beats (two bursts of 256); leaves straddling 4 KB are split.
  runCase("split bursts over 256 beats and at 4 KB boundaries (32-bit bus, 32-prim leaves)", dataBits = 32, tris = 200,
    nReqs = 25, DramConfig(5, 8, 1, randomExtraLatency = 3), reqProb = 0.5, readyProb = 0.7, seed = 23,
    refFormat = Some(RefFormat(nodeIdBits = 26, primIndexBits = 26, countBits = 5, levelBits = 0)),
    extraRefs = img => {
      val c = new RefCodec(img.p.refs)
      val n = math.min(img.p.refs.maxLeafPrims, img.numPrims)
      // the largest leaf the format allows: page aligned (2 bursts of 256), and from slot 60 (3840 B into
      // the page: 4 beats, 256, 252)
      Seq(c.leaf(0, n), c.leaf(math.min(60, img.numPrims - n), n), c.leaf(16, 16))
    })
  // The cache plug-in point: a node path that holds its DRAM reads back, so primitive reads overtake them;
  // responses must still leave in request order.
  runCase("keep request order when a path reorders DRAM traffic (stalling node path, response buffers)",
    dataBits = 256, tris = 300, nReqs = 80, DramConfig(8, 8, 1, randomExtraLatency = 5), reqProb = 0.9,
    readyProb = 0.5, seed = 24, respBufferBeats = 40, maxCycles = 6000,
    pathFactory = (g, i) => if (i == FetchPath.Node) new StallingPath(g, 0x5a) else new FetchPath(g),
    afterRun = (io, _, _) => assert(io.overtaken.peek().litValue > 0, "the stalling path did not reorder DRAM traffic"))

  behavior of "MemoryController with RESP_ORDER=path"

  // Two streams, each checked beat by beat against the image in its own request order, with independent
  // random backpressure; a stalling primitive path holds leaves back, and node beats must then leave ahead of
  // older leaves (what RESP_ORDER=request forbids), else the knob would change nothing.
  runCase("answer nodes and leaves in two streams, each in its own order (stalling primitive path)",
    dataBits = 256, tris = 300, nReqs = 80, DramConfig(8, 8, 1, randomExtraLatency = 5), reqProb = 0.9,
    readyProb = 0.5, seed = 25, respBufferBeats = 40, maxCycles = 6000, respByPath = true,
    pathFactory = (g, i) => if (i == FetchPath.Prim) new StallingPath(g, 0x3c) else new FetchPath(g),
    afterRun = (_, _, _) => assert(overtakes > 0, "no node beat left ahead of an older leaf: the streams are not independent"))
  runCase("answer both streams under a saturated DRAM (pass-through paths, paper timing)", dataBits = 256, tris = 300,
    nReqs = 100, DramConfig.paper, reqProb = 1.0, readyProb = 0.7, seed = 26, respBufferBeats = 16, respByPath = true)
  behavior of "MemoryController with MEM_RETRIES"

  // Poisoned beats (about 1 in 20) under random latency and backpressure, a stalling node path so that the re-reads
  // and later reads of both paths interleave; every beat is checked against the image, with the re-reads counted.
  private val errors = DramConfig(8, 8, 1, randomExtraLatency = 7, seed = 9, errorThreshold = 3300, errorSeed = 77)
  runCase("re-read transient errors: every beat clean, one re-read per failed read", dataBits = 256, tris = 300,
    nReqs = 90, errors, reqProb = 0.9, readyProb = 0.6, seed = 27, respBufferBeats = 40, maxCycles = 8000,
    pathFactory = (g, i) => if (i == FetchPath.Node) new StallingPath(g, 0x33) else new FetchPath(g),
    memRetries = 1, errorSticky = false)
  // make regress: make test meets sticky re-reads through the whole platform (PlatformSpec's read-error and NODE_BANKS
  // circuits, two streams and tagged answers), which keeps its time from growing
  if (rtaccel.Regress.full)
    runCase("re-read sticky errors MEM_RETRIES times, then deliver them marked (two streams)", dataBits = 256, tris = 300,
      nReqs = 60, errors, reqProb = 0.9, readyProb = 0.6, seed = 28, respBufferBeats = 40, maxCycles = 8000,
      respByPath = true, memRetries = 2, errorSticky = true)
  // make regress only, as PlatformSpec's MEM_RETRIES=0 case: the flag-at-once path is the re-read logic left out
  if (rtaccel.Regress.full)
    runCase("deliver a transient error at once with MEM_RETRIES=0 (the re-read of the same beat is clean)", dataBits = 256,
      tris = 300, nReqs = 90, errors, reqProb = 0.9, readyProb = 0.6, seed = 29, respBufferBeats = 40, maxCycles = 8000,
      memRetries = 0, errorSticky = false)
  it should "refuse MEM_RETRIES without response buffers" in {
    val e = intercept[IllegalArgumentException](_root_.circt.stage.ChiselStage.emitCHIRRTL(
      new MemoryController(rtaccel.config.Presets.paper2017.copy(memRetries = 1), AxiParams())))
    assert(e.getMessage.contains("MEM_RETRIES=1") && e.getMessage.contains("respBufferBeats"))
  }

  it should "refuse RESP_ORDER=path without response buffers" in {
    val e = intercept[IllegalArgumentException](_root_.circt.stage.ChiselStage.emitCHIRRTL(
      new MemoryController(rtaccel.config.Presets.paper2017.copy(respByPath = true), AxiParams())))
    assert(e.getMessage.contains("respBufferBeats"))
  }
}
