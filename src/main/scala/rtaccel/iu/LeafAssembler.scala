package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.config.{Numerics, TriTest}
import rtaccel.mc.FetchBeat

/** What shapes the packed leaves' assembly (LeafAssembler and its beats): the pipes' view and the width of a leaf's
  * primitive count (`PlatformParams.leaves`). */
final case class LeafParams(pipes: PipeParams, countBits: Int) {
  def tuBits: Int = pipes.tuBits
  def maxLeafPrims: Int = 1 << countBits
}

/** The job a leaf's primitives are tested for: which TU asked, its ray and its current tmax. */
class LeafCtx(p: LeafParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val ray = new RayData
  val tmax = UInt(32.W)
}

/** One memory beat of a leaf, with the leaf's primitive count - 1 and its job (both constant over the leaf's beats). */
class LeafBeat(p: LeafParams, beatBits: Int) extends Bundle {
  val beat = new FetchBeat(beatBits)
  val lastPrim = UInt(math.max(1, p.countBits).W)
  val ctx = new LeafCtx(p)
}

/** PRIM_FORMAT=packed: cuts a leaf's 10-word records (9 coordinates + triangle id, Numerics.packedPrimBytes) out of
  * its beats, where a record may span two beats (8 words per 256-bit beat) or a beat hold more than one record
  * (512-bit). A leaf reads ceil(count x 10 / beatWords) beats (mc.LeafFetch); the words past its last record in its
  * final beat are padding and are dropped, so that the next leaf's first beat starts a record.
  *
  * The record words wait in a buffer of beatWords + 9 words (the most that can be short of a record, plus a beat),
  * each with the error bit of the beat it came from and a flag on the leaf's final word. A record leaves as soon
  * as its 10 words are in, one per cycle, with err = any of its beats had an error and last = it ends its leaf.
  * The leaf's job is queued on its first beat and leaves with its last record, so that a leaf's beats may be
  * taken while earlier leaves still drain. `in` is refused only while the buffer lacks room for a whole beat;
  * the output never waits (the triangle pipes never stall).
  *
  * TRI_II=k: the triangle pipe takes a record every k cycles at most, so a record leaves at least k cycles after the
  * one before it. Records may complete closer together than that (a 256-bit beat holds 0.8 of one: two can complete
  * in consecutive cycles), so the buffer holds them and refuses beats while full: a record in `cap` slots always
  * leaves within k cycles, and the buffer always takes a beat while it holds less than a record.
  */
class LeafAssembler(p: LeafParams, beatBits: Int) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Decoupled(new LeafBeat(p, beatBits)))
    val out = Valid(new TriJob(p.pipes))
    val leafTaken = Output(Bool()) // `in` took the final beat of a leaf
  })
  private val rec = Numerics.packedPrimBytes / 4
  private val bw = beatBits / 32
  require(bw >= 2 && isPow2(bw), s"a beat of $beatBits bits must be a power of two of at least 64 bits")
  private val cap = bw + rec - 1
  private val nBits = log2Ceil(cap + 1)
  // jobs: a leaf's words never take more than `cap` slots, so at most this many leaves have words buffered
  private val jobDepth = (cap - 2) / rec + 3

  val words = Reg(Vec(cap, UInt(32.W)))
  val errs = Reg(Vec(cap, Bool()))
  val ends = Reg(Vec(cap, Bool()))
  val n = RegInit(0.U(nBits.W))
  // the queued job keeps what the triangle test reads: Möller–Trumbore takes no reciprocal direction
  private val keepInv = p.pipes.triTest == TriTest.Watertight
  class Stored extends Bundle {
    val tu = UInt(p.tuBits.W); val tmax = UInt(32.W); val o = Vec(3, UInt(32.W)); val d = Vec(3, UInt(32.W))
    val tmin = UInt(32.W); val inv = if (keepInv) Some(Vec(3, UInt(32.W))) else None
  }
  val jobs = Module(new Queue(new Stored, jobDepth))

  // ---- input side: the beat index within the current leaf and how many of its words are record words
  val in = io.in.bits
  val beatIdx = RegInit(0.U(log2Ceil(p.maxLeafPrims * rec / bw + 2).W))
  // by count: the leaf's beats - 1 and the record words of its final beat (the rest of that beat is padding)
  private val counts = 1 to p.maxLeafPrims
  val lastBeat = VecInit(counts.map(c => ((rec * c + bw - 1) / bw - 1).U(beatIdx.getWidth.W)))(in.lastPrim)
  val finalWords = VecInit(counts.map(c => (rec * c - ((rec * c + bw - 1) / bw - 1) * bw).U(log2Ceil(bw + 1).W)))(in.lastPrim)
  val finalBeat = beatIdx === lastBeat
  val valid = Mux(finalBeat, finalWords, bw.U)

  // ---- output side: a whole record at the front of the buffer, at least `ii` cycles after the one before it
  private val ii = p.pipes.triInterval
  val spaced = if (ii == 1) true.B else {
    val wait = RegInit(0.U(log2Ceil(ii).W)) // cycles still to wait before the next record may leave
    when(n >= rec.U && wait === 0.U) { wait := (ii - 1).U }.elsewhen(wait =/= 0.U) { wait := wait - 1.U }
    wait === 0.U
  }
  val outFire = n >= rec.U && spaced
  val nAfter = Mux(outFire, n - rec.U, n)
  val firstBeat = beatIdx === 0.U
  io.in.ready := nAfter +& bw.U <= cap.U && (!firstBeat || jobs.io.enq.ready)
  val inFire = io.in.fire
  jobs.io.enq.valid := io.in.valid && firstBeat && nAfter +& bw.U <= cap.U
  val st = jobs.io.enq.bits
  st.tu := in.ctx.tu; st.tmax := in.ctx.tmax; st.o := in.ctx.ray.o; st.d := in.ctx.ray.d; st.tmin := in.ctx.ray.tmin
  st.inv.foreach(_ := in.ctx.ray.inv)
  when(inFire) { beatIdx := Mux(finalBeat, 0.U, beatIdx + 1.U) }
  io.leafTaken := inFire && finalBeat

  val out = io.out.bits
  io.out.valid := outFire
  val job = jobs.io.deq.bits
  out.tu := job.tu; out.tmax := job.tmax; out.ray.o := job.o; out.ray.d := job.d; out.ray.tmin := job.tmin
  out.ray.inv := job.inv.getOrElse(VecInit(Seq.fill(3)(0.U(32.W))))
  out.words := VecInit(words.take(rec))
  out.err := errs.take(rec).reduce(_ || _)
  out.last := ends(rec - 1)
  jobs.io.deq.ready := outFire && ends(rec - 1)
  when(outFire) { assert(jobs.io.deq.valid, "LeafAssembler: a record without its leaf's job") }

  // ---- buffer: drop the record that leaves, then append this beat's record words behind what stays
  for (i <- 0 until cap) {
    def kept[T <: Data](v: Vec[T]): T = if (i + rec < cap) Mux(outFire, v(i + rec), v(i)) else v(i)
    val slot = i.U -& nAfter // the beat word that lands in slot i (valid when below `valid`)
    val lands = inFire && i.U >= nAfter && slot < valid
    val w = VecInit.tabulate(bw)(k => in.beat.data(32 * k + 31, 32 * k))
    words(i) := Mux(lands, w(slot(log2Ceil(bw) - 1, 0)), kept(words))
    errs(i) := Mux(lands, in.beat.err, kept(errs))
    ends(i) := Mux(lands, finalBeat && slot === valid - 1.U, kept(ends))
  }
  n := nAfter + Mux(inFire, valid, 0.U)
}
