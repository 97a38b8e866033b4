package rtaccel.sim

import chisel3._
import chisel3.util._
import chisel3.util.experimental.loadMemoryFromFileInline
import chisel3.util.random.LFSR
import rtaccel.config.PlatformParams
import rtaccel.top.{AxiLite, RtAccelTop}

/** What a simulation build needs besides the platform parameters. Capacities are powers of two and the
  * files live at fixed names in one folder, so that scenes of similar size reuse a compiled simulator; the
  * ray count and the primitive base address are inputs, not parameters, for the same reason.
  */
final case class SimSetup(rayCapacity: Int, raysHex: String, imageHex: String, imageWords: Int,
                          dram: DramConfig, hostStallPercent: Int = 0, seed: Int = 1, accessLogCapacity: Int = 0) {
  require(accessLogCapacity == 0 || (Integer.bitCount(accessLogCapacity) == 1 && accessLogCapacity >= SimSetup.logWords),
    s"access log capacity must be 0 or a power of two >= ${SimSetup.logWords}")
  require(rayCapacity >= 1 && Integer.bitCount(rayCapacity) == 1, "ray capacity must be a power of two")
  require(imageWords >= 1 && Integer.bitCount(imageWords) == 1, "image capacity must be a power of two")
  require(hostStallPercent >= 0 && hostStallPercent < 100, "host stall percentage must be 0..99")
  for (f <- Seq(raysHex, imageHex) if f.length > SimSetup.maxFileNameChars) throw new rtaccel.io.InputError(
    s"the simulator's input file $f is ${f.length} characters long; Verilator reads at most ${SimSetup.maxFileNameChars} " +
      "characters of a $readmemh file name: move the checkout to a shorter path")
}

object SimSetup {
  /** Access-log entries read out per peek: the host reads a whole row of the log at a time, since every
    * peek through the simulator interface costs microseconds and a scene run logs tens of millions of accesses.
    */
  val logWords = 16
  /** Step between the jitter seeds of the DRAM channels' models: channel k > 0 starts its LFSR from
    * dram.seed + k x this step (16 bits, odd): a prime step, so that the seeds of up to 16 channels differ
    * for every dram.seed and their jitter does not move in lockstep. A simulation choice, no hardware's.
    */
  val channelSeedStep = 7919
  /** The longest `$readmemh` file name Verilator 5.006 takes: it copies the name into a buffer of
    * VL_VALUE_STRING_MAX_CHARS (256) characters without a bound (VL_CVT_PACK_STR_NW), so a longer name overruns its
    * stack, which loaded a wrong memory image at one checkout's path and not at another's. */
  val maxFileNameChars = 256
  /** Where a simulator build's input files go: a short folder named by the digest of the build's key, beside the
    * builds in `work`, so that their absolute names stay far below [[maxFileNameChars]] however long the key. */
  def inputDir(work: java.nio.file.Path, key: String): java.nio.file.Path = {
    work.resolve("inputs").resolve(rtaccel.io.Digest.hexOf(6, key))
  }
  def pow2(n: Long): Int = { var c = 1L; while (c < n) c <<= 1; require(c <= (1 << 30), s"$n entries is too large to simulate"); c.toInt }
  /** The smallest capacities `make simulate` builds (simulator memory only, no hardware's): every frame up to
    * 128×96 + 5 bounces on every scene up to the paper's sizes (conference's image, the larger, is 29 MB) then lands
    * in one class and shares one compiled simulator per platform, so `make paper` builds each circuit once
    * instead of once per scene and frame size. The price is simulator memory: 64 MiB per DRAM channel, 2^17
    * rays and hits, 8 MiB of access log per IU cluster, whatever the run needs.
    */
  val minRays: Int = 1 << 17
  val minImageBytes: Long = 64L << 20
  val minLogEntries: Int = 1 << 21
  /** The capacity of a build that must hold `n` entries: a power of two, at least `floor`. */
  def capacity(n: Long, floor: Long): Int = pow2(math.max(n, floor))
}

/** SimHarness's ports, a named type so that the firtool-built harness's shell (FirtoolHarness) has the very same
  * ports. `memControllers`: one access log per IU cluster's MC, then per node bank.
  */
class SimHarnessIO(memControllers: Int) extends Bundle {
  val lite = Flipped(new AxiLite(RtAccelTop.liteAddrBits))
  val irq = Output(Bool())
  val rayCount = Input(UInt(32.W)) // rays the host streams (RAY_COUNT of the batch)
  val errorSticky = Input(Bool()) // MEM_ERROR_MODE=sticky (DramModel.io.sticky), an input so that one build runs both
  val received = Output(UInt(32.W))
  val sent = Output(UInt(32.W))
  val tlasts = Output(UInt(32.W))   // hit beats that carried TLAST
  val tlastAt = Output(UInt(32.W))  // the index of the last of them (0 before any)
  val readIdx = Input(UInt(32.W))
  val readData = Output(UInt(RtAccelTop.HitBits.W))
  // per IU cluster: entries readIdx * logWords .. + logWords - 1 of its log, the first lowest
  // (then per node bank with NODE_BANKS: one log per MC, memControllers)
  val logCount = Output(Vec(memControllers, UInt(32.W)))
  val logData = Output(Vec(memControllers, UInt((32 * SimSetup.logWords).W)))
  // per MC: the lookups its caches turned into refetches of a poisoned line (CachePath.eForced), each as its path
  // (bit 31: primitive) and its index among that path's lookups; entry readIdx
  val refetchCount = Output(Vec(memControllers, UInt(32.W)))
  val refetchData = Output(Vec(memControllers, UInt(32.W)))
}

/** Simulation-only wrapper: the board top with the rays in a ROM (the host's ray stream), the memory image in a
  * DRAM model (loaded by the host before the run) and the hits captured in a RAM (the host's hit stream), so
  * that a whole scene runs without per-cycle work in Scala. The host side can refuse hits at random
  * (backpressure). Everything else goes through the board's AXI4-Lite port, `lite`, which the host driver
  * (HostDriver) works from outside in the order docs/registers.md gives; `irq` is the board's interrupt.
  * Results are read out through `readIdx`/`readData` at the end.
  * With accessLogCapacity > 0 every child reference each IU cluster's MC accepts is logged in order in that
  * cluster's log (`logCount(c)`, read out through `readIdx`/`logData(c)`, SimSetup.logWords entries per row):
  * the access order its caches saw, for replay through the trace model.
  */
class SimHarness(p: PlatformParams, s: SimSetup) extends Module {
  val top = Module(new RtAccelTop(p, tapAccesses = s.accessLogCapacity > 0))
  val io = IO(new SimHarnessIO(p.memControllers))
  // one DRAM model per memory channel, each holding the whole image (the channel only decides who serves an
  // address) with its own bandwidth and latency; channel k > 0 draws its jitter from its own seed
  val drams = top.memPorts.zipWithIndex.map { case (port, k) =>
    val cfg = if (k == 0) s.dram else s.dram.copy(seed = ((s.dram.seed + SimSetup.channelSeedStep * k) & 0xffff) | 1)
    val d = Module(new DramModel(top.axiP, s.imageWords, s.imageHex, cfg, p.hw.dramQueueDepth))
    d.io.axi <> port
    d.io.sticky := io.errorSticky
    d
  }
  top.io.lite <> io.lite
  io.irq := top.io.irq

  // the host's ray stream: the board takes rays only within a started batch
  val rays = Mem(s.rayCapacity, UInt(RtAccelTop.RayBits.W))
  loadMemoryFromFileInline(rays, s.raysHex)
  val sent = RegInit(0.U(32.W))
  top.io.rays.valid := sent < io.rayCount
  top.io.rays.bits.tdata := rays(sent)
  top.io.rays.bits.tlast := sent === io.rayCount - 1.U
  when(top.io.rays.fire) { sent := sent + 1.U }

  val hits = Mem(s.rayCapacity, UInt(RtAccelTop.HitBits.W))
  val received = RegInit(0.U(32.W))
  val lfsr = LFSR(16, seed = Some(s.seed & 0xffff | 1))
  val stall = if (s.hostStallPercent == 0) false.B else (lfsr(6, 0) < (s.hostStallPercent * 128 / 100).U)
  top.io.hits.ready := !stall
  val tlasts = RegInit(0.U(32.W)); val tlastAt = RegInit(0.U(32.W))
  when(top.io.hits.fire) {
    when(received < io.rayCount) { hits(received) := top.io.hits.bits.tdata }
    received := received + 1.U
    when(top.io.hits.bits.tlast) { tlasts := tlasts + 1.U; tlastAt := received }
  }
  io.tlasts := tlasts
  io.tlastAt := tlastAt
  io.received := received
  io.sent := sent
  io.readData := hits(io.readIdx)

  io.logCount.foreach(_ := 0.U)
  io.logData.foreach(_ := 0.U)
  io.refetchCount.foreach(_ := 0.U)
  io.refetchData.foreach(_ := 0.U)
  if (s.accessLogCapacity > 0) {
    import chisel3.util.experimental.BoringUtils
    val mcs = top.mcs ++ top.nodeBanks.toSeq.flatMap(_.banks)
    for ((mc, m) <- mcs.zipWithIndex) {
      val count = RegInit(0.U(32.W))
      // as deep as the access log: a refetch is one of the lookups it holds (a sticky error on a line every ray reads
      // makes one per lookup)
      val log = Mem(s.accessLogCapacity, UInt(32.W))
      // each cache path's refetches this cycle (at most one per path), entered in path order
      val events = mc.paths.zipWithIndex.collect { case (c: rtaccel.cache.hw.CachePath, i) =>
        val (fire, forced) = (BoringUtils.bore(c.eFire), BoringUtils.bore(c.eForced))
        val lookups = RegInit(0.U(31.W))
        when(fire) { lookups := lookups + 1.U }
        (fire && forced, Cat(i.U(1.W), lookups))
      }
      var at = count
      for ((ev, word) <- events) {
        when(ev && at < s.accessLogCapacity.U) { log.write(at(log2Ceil(s.accessLogCapacity) - 1, 0), word) }
        at = at + ev.asUInt
      }
      count := at
      io.refetchCount(m) := count
      io.refetchData(m) := log(io.readIdx(log2Ceil(s.accessLogCapacity) - 1, 0))
    }
  }
  // every cluster's log holds ALL accesses (accessLogCapacity, sized for the whole run), not a 1/IUS share: the
  // controller hands a ray to the lowest-numbered free TU, so a cluster can make any share of the accesses (cluster 0
  // all of them when the batch has no more rays than a cluster has TUs) and a share-sized log could overflow.
  // The cost is simulator memory only, IUS x the capacity.
  top.io.tap.foreach(_.zipWithIndex.foreach { case (t, c) =>
    val w = SimSetup.logWords
    val logCount = RegInit(0.U(32.W))
    val log = Mem(s.accessLogCapacity / w, Vec(w, UInt(32.W)))
    when(t.valid) {
      when(logCount < s.accessLogCapacity.U) {
        log.write(logCount >> log2Ceil(w), VecInit(Seq.fill(w)(t.bits)), UIntToOH(logCount(log2Ceil(w) - 1, 0), w).asBools)
      }
      logCount := logCount + 1.U
    }
    io.logCount(c) := logCount
    io.logData(c) := log(io.readIdx).asUInt
  })
}
