package rtaccel.sim

import chisel3._
import chisel3.util._
import chisel3.util.experimental.loadMemoryFromFileInline
import rtaccel.config.PlatformParams
import rtaccel.mc.{AxiAr, AxiParams, AxiReadMaster}

/** Timing of the simulated DRAM.
  * latencyCycles: cycles from the AR handshake to the first R beat of an isolated request (>= 1).
  * bytesPerCycleNum / bytesPerCycleDen: sustained bandwidth, an exact rational number of bytes per cycle.
  * randomExtraLatency: each request waits a further pseudo-random 0..randomExtraLatency cycles (LFSR, seed).
  * errorThreshold (of 65536) / errorSeed: poisoned beats (rtaccel.model.MemFaults): a poisoned beat is
  * answered with SLVERR and inverted data, so that a platform that ignored RRESP would compute wrong hits. Whether
  * the error stays is the model's input `sticky` (MEM_ERROR_MODE), so one simulator build runs either mode.
  */
final case class DramConfig(latencyCycles: Int, bytesPerCycleNum: Int, bytesPerCycleDen: Int,
                            randomExtraLatency: Int = 0, seed: Int = 1, errorThreshold: Int = 0, errorSeed: Int = 1) {
  require(errorThreshold >= 0 && errorThreshold <= rtaccel.model.MemFaults.One, s"error threshold must be 0..65536 (got $errorThreshold)")
  require(latencyCycles >= 1, s"DRAM latency must be at least 1 cycle (got $latencyCycles)")
  require(bytesPerCycleNum >= 1 && bytesPerCycleDen >= 1, s"bandwidth must be a positive fraction (got $bytesPerCycleNum/$bytesPerCycleDen)")
  require(randomExtraLatency >= 0 && randomExtraLatency < (1 << 16), "random extra latency must be in 0..65535")
  require(seed != 0 && (seed & 0xffff) != 0, "the LFSR seed must be non-zero in its low 16 bits")
  def bytesPerCycle: Double = bytesPerCycleNum.toDouble / bytesPerCycleDen
}

object DramConfig {
  /** Paper platform: 1.2 GB/s peak x 50% sustained at 150 MHz = 4 B/cycle, ~40 cycles latency. */
  val paper: DramConfig = DramConfig(latencyCycles = 40, bytesPerCycleNum = 4, bytesPerCycleDen = 1)

  /** From a PlatformParams' memory model, as a rational with denominator 1000. */
  def from(p: PlatformParams, randomExtraLatency: Int = 0, seed: Int = 1): DramConfig = {
    val den = 1000
    val num = math.max(1L, math.round(p.memBytesPerCycle * den)).toInt
    val g = BigInt(num).gcd(BigInt(den)).toInt
    DramConfig(p.memory.latencyCycles max 1, num / g, den / g, randomExtraLatency, seed)
  }
}

/** Simulation-only AXI4 read slave (INCR bursts of full-width beats, in order, any ID echoed back).
  *
  * Memory: `words` entries of dataBits, initialised from a `$readmemh` file (see rtaccel.host.ImageFile), read
  * combinationally so that a beat held under R backpressure stays stable.
  * Requests: an AR queue of `queueDepth` entries; an entry accepted in cycle t is stamped
  * readyAt = t + latencyCycles + extra (extra = LFSR value mod (randomExtraLatency + 1)); the head request
  * starts emitting beats once the cycle counter reaches readyAt. Requests are served strictly in order, so a
  * request never overtakes an earlier one, even if its own readyAt is earlier.
  * Bandwidth: a credit counter in units of 1/den byte gains num every cycle and a beat costs beatBytes * den.
  * R valid needs credit >= one beat. The counter saturates at cap = one beat + one cycle's gain, so an idle
  * bus cannot bank more than one beat; in a saturated run (num <= beatBytes * den) the cap is never hit and
  * the delivered rate is exactly num/den bytes per cycle. Once R valid rises it stays until the handshake
  * (credit only grows while waiting), as AXI requires.
  * Addresses: beat index = addr / beatBytes (low bits ignored); beats beyond `words` return 0 with DECERR.
  */
class DramModel(axi: AxiParams, words: Int, hexFile: String, cfg: DramConfig, queueDepth: Int = 16) extends Module {
  require(words >= 1, "the DRAM needs at least one word")
  require(queueDepth >= 1, "the request queue needs at least one entry")
  private val ap = axi
  val io = IO(new Bundle {
    /** The slave side of the AXI4 read channels (connect with `dram.io.axi <> master.io.axi`). */
    val axi = Flipped(new AxiReadMaster(ap))
    /** Free-running cycle counter (for tests and traces). */
    val cycle = Output(UInt(64.W))
    /** MEM_ERROR_MODE=sticky: a poisoned beat fails every read, like a bad cell; transient (false): it fails its
      * first read only, like a soft error the read corrects, and every later read of it is clean. */
    val sticky = Input(Bool())
  })

  // with errors, each word carries one bit more (0 as loaded from the file): its transient error was spent
  private val spentBit = if (cfg.errorThreshold > 0) 1 else 0
  val mem = Mem(words, UInt((axi.dataBits + spentBit).W))
  if (hexFile.nonEmpty) loadMemoryFromFileInline(mem, hexFile)

  val cycle = RegInit(0.U(64.W))
  cycle := cycle + 1.U
  io.cycle := cycle

  // ---- request queue with ready times
  class Entry extends Bundle {
    val ar = new AxiAr(axi)
    val readyAt = UInt(64.W)
  }
  val ar = io.axi.ar
  val r = io.axi.r
  val q = Module(new Queue(new Entry, queueDepth))
  val lfsr = random.LFSR(16, ar.fire, Some(BigInt(cfg.seed & 0xffff)))
  val extra: UInt =
    if (cfg.randomExtraLatency == 0) 0.U
    else if (isPow2(cfg.randomExtraLatency + 1)) lfsr(log2Ceil(cfg.randomExtraLatency + 1) - 1, 0)
    else lfsr % (cfg.randomExtraLatency + 1).U
  q.io.enq.valid := ar.valid
  q.io.enq.bits.ar := ar.bits
  q.io.enq.bits.readyAt := cycle + cfg.latencyCycles.U + extra
  ar.ready := q.io.enq.ready

  // ---- bandwidth credits, units of 1/den byte
  val beatCost = BigInt(axi.beatBytes) * cfg.bytesPerCycleDen
  val cap = beatCost + cfg.bytesPerCycleNum
  val credit = RegInit(cap.U(log2Ceil(cap + 1).W))
  val haveCredit = credit >= beatCost.U

  // ---- beat generation for the head request
  val beat = RegInit(0.U(9.W))
  val head = q.io.deq.bits.ar
  val wordIdx = (head.addr >> log2Ceil(axi.beatBytes)) +& beat
  val inRange = wordIdx < words.U
  val started = q.io.deq.valid && cycle >= q.io.deq.bits.readyAt
  val isLast = beat === head.len

  r.valid := started && haveCredit
  r.bits.id := head.id
  val memIdx = wordIdx(math.max(log2Ceil(words), 1) - 1, 0)
  val stored = mem(memIdx)
  val word = stored(axi.dataBits - 1, 0)
  // the same hash as rtaccel.model.MemFaults.hash16, so the model knows which beats are poisoned
  val bad: Bool = if (cfg.errorThreshold == 0) false.B else {
    import rtaccel.model.MemFaults
    val x = wordIdx.pad(32)(31, 0) ^ (cfg.errorSeed.toLong & 0xffffffffL).U(32.W)
    val m1 = (x * MemFaults.Mul1.U(32.W))(31, 0)
    val h1 = m1 ^ (m1 >> 15)
    val m2 = (h1 * MemFaults.Mul2.U(32.W))(31, 0)
    (m2 ^ (m2 >> 13))(15, 0) < cfg.errorThreshold.U(17.W)
  }
  val poisoned: Bool = if (spentBit == 0) false.B else bad && (io.sticky || !stored(axi.dataBits))
  // a transient error is spent by the read that reports it
  if (spentBit > 0) when(r.fire && inRange && poisoned && !io.sticky) { mem.write(memIdx, Cat(1.U(1.W), word)) }
  r.bits.data := Mux(inRange, Mux(poisoned, ~word, word), 0.U)
  r.bits.resp := Mux(!inRange, 3.U, Mux(poisoned, 2.U, 0.U)) // DECERR, SLVERR, OKAY
  r.bits.last := isLast
  q.io.deq.ready := r.fire && isLast

  when(r.fire) { beat := Mux(isLast, 0.U, beat + 1.U) }
  val gained = credit +& cfg.bytesPerCycleNum.U
  val spent = Mux(r.fire, gained - beatCost.U, gained)
  credit := Mux(spent > cap.U, cap.U, spent)

  when(q.io.deq.valid) {
    assert(head.burst === 1.U, "DramModel: only INCR bursts are modelled")
    assert(head.size === log2Ceil(axi.beatBytes).U, "DramModel: only full-width beats are modelled")
  }
}
