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

/** MC + DRAM model, with AR/R traffic counters for the test. */
class McHarness(p: PlatformParams, val axi: AxiParams, words: Int, hex: String, cfg: DramConfig,
                pathFactory: (McGeometry, Int) => FetchPathModule = FetchPath.passThrough,
                respBufferBeats: Int = 0) extends Module {
  val mc = Module(new MemoryController(p, axi, pathFactory = pathFactory, respBufferBeats = respBufferBeats))
  val dram = Module(new DramModel(axi, words, hex, cfg))
  dram.io.axi <> mc.io.axi
  val io = IO(new Bundle {
    val req = Flipped(chisel3.util.Decoupled(new FetchReq))
    val resp = chisel3.util.Decoupled(new FetchBeat(axi.dataBits))
    val primBase = Input(UInt(axi.addrBits.W))
    val maxLevel = Input(UInt(4.W))
    val counters = Output(new McCounters)
    val arBursts = Output(UInt(32.W))
    val maxLen = Output(UInt(8.W))
    val badBurst = Output(Bool())
    val overtaken = Output(UInt(32.W))
  })
  // Cycles in which DRAM delivers a beat for a different path than the one the response mux waits on.
  import chisel3.util.experimental.BoringUtils
  val orderValid = BoringUtils.bore(mc.order.io.deq.valid)
  val orderPath = BoringUtils.bore(mc.order.io.deq.bits)
  val memPath = BoringUtils.bore(mc.memOrder.io.deq.bits.path)
  val overtaken = RegInit(0.U(32.W))
  when(mc.io.axi.r.fire && orderValid && orderPath =/= memPath) { overtaken := overtaken + 1.U }
  io.overtaken := overtaken
  mc.io.req <> io.req
  io.resp <> mc.io.resp
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
  def allRefs(img: MemoryImage): IndexedSeq[Int] =
    0 +: (for (n <- 0 until img.numNodes; j <- 0 until img.p.m if img.childRef(n, j) != 0) yield img.childRef(n, j))

  def runCase(name: String, dataBits: Int, tris: Int, nReqs: Int, cfg: DramConfig, reqProb: Double, readyProb: Double,
              seed: Long, extraRefs: MemoryImage => Seq[Int] = _ => Nil, refFormat: Option[RefFormat] = None,
              pathFactory: (McGeometry, Int) => FetchPathModule = FetchPath.passThrough,
              respBufferBeats: Int = 0, maxCycles: Int = 30000, maxLevel: Int = 15,
              pick: (Random, IndexedSeq[Int]) => Int = (r, pool) => pool(r.nextInt(pool.length)),
              afterRun: (McHarness, Seq[Int], MemoryImage) => Unit = (_, _, _) => (),
              annotations: firrtl2.AnnotationSeq = Seq()): Unit =
    it should name in {
      val axi = AxiParams(dataBits = dataBits)
      val img = image(seed, tris, refFormat)
      val p = img.p
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
      val expected = refs.flatMap { ref =>
        val (a, n) = span(ref); val k = n / axi.beatBytes
        (0 until k).map(i => (beat(bytes, a + i * axi.beatBytes, axi), i == k - 1))
      }
      test(new McHarness(p, axi, lay.words, hex.toString, cfg, pathFactory, respBufferBeats)).withAnnotations(annotations) { dut =>
        dut.clock.setTimeout(0)
        dut.io.primBase.poke(lay.primBaseBytes.U)
        dut.io.maxLevel.poke(maxLevel.U)
        val got = ArrayBuffer[(BigInt, Boolean)]()
        var next = 0; var presenting = false; var cyc = 0
        var maxOutstanding = 0
        while (got.length < expected.length) {
          assert(cyc < maxCycles, s"timeout after ${got.length}/${expected.length} beats")
          if (!presenting && next < refs.length && r.nextDouble() < reqProb) presenting = true
          dut.io.req.valid.poke(presenting.B)
          if (presenting) dut.io.req.bits.childRef.poke((refs(next) & 0xffffffffL).U)
          val ready = r.nextDouble() < readyProb
          dut.io.resp.ready.poke(ready.B)
          if (ready && dut.io.resp.valid.peek().litToBoolean) {
            val b = (dut.io.resp.bits.data.peek().litValue, dut.io.resp.bits.last.peek().litToBoolean)
            val i = got.length
            assert(b == expected(i), s"beat $i (cycle $cyc) differs")
            got += b
          }
          if (presenting && dut.io.req.ready.peek().litToBoolean) { presenting = false; next += 1 }
          maxOutstanding = math.max(maxOutstanding, next - got.count(_._2))
          dut.clock.step(); cyc += 1
        }
        dut.clock.step(5)
        assert(!dut.io.resp.valid.peek().litToBoolean, "extra beats after the last expected one")
        val leaves = refs.filter(codec.isPrim)
        val prims = leaves.map(codec.count).sum
        val totalBytes = refs.map(span(_)._2.toLong).sum
        assert(dut.io.counters.nodeRequests.peek().litValue == refs.length - leaves.length)
        assert(dut.io.counters.leafRequests.peek().litValue == leaves.length)
        assert(dut.io.counters.primsRequested.peek().litValue == prims)
        assert(dut.io.counters.bytesRequested.peek().litValue == totalBytes)
        if (pathFactory eq FetchPath.passThrough) assert(dut.io.counters.busyBeats.peek().litValue == expected.length)
        assert(!dut.io.badBurst.peek().litToBoolean, "an AR burst crossed 4 KB or had a bad id/burst type")
        val bursts = dut.io.arBursts.peek().litValue
        info(f"${refs.length} refs (${leaves.length} leaves, $prims prims), ${expected.length} beats in $cyc cycles " +
          f"(${totalBytes.toDouble / cyc}%.2f B/cycle), $bursts AR bursts, max len ${dut.io.maxLen.peek().litValue}, " +
          s"max outstanding $maxOutstanding")
        if (pathFactory eq FetchPath.passThrough) assert(bursts >= refs.length) // a cache serves hits without DRAM
        val overtaken = dut.io.overtaken.peek().litValue
        info(s"$overtaken beats arrived for the other path than the one awaited")
        if (pathFactory eq FetchPath.passThrough) assert(overtaken == 0)
        afterRun(dut, refs, img)
      }
    }
}

class MemoryControllerSpec extends McCases {

  "MemoryController" should "emit SystemVerilog for the paper preset" in {
    val sv = _root_.circt.stage.ChiselStage.emitSystemVerilog(new MemoryController(rtaccel.config.Presets.paper2017, AxiParams()),
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
    afterRun = (dut, _, _) => assert(dut.io.overtaken.peek().litValue > 0, "the stalling path did not reorder DRAM traffic"))
}
