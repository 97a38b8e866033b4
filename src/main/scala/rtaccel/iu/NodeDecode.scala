package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.bvh.QNodeLayout
import rtaccel.fp.{Fp, FpFormat, Timed}

/** What shapes a node's way into the box pipe (NodeJob, NodeDecode): the pipes' view, NODE_FORMAT's bits (0: the
  * full layout, no decoder) and the stored node's slot (`PlatformParams.nodes`). */
final case class NodeParams(pipes: PipeParams, quantBits: Int, slotBytes: Int) {
  def m: Int = pipes.m
}

/** A node as the IU collects it from memory: the words of one slotBytes slot. */
class NodeJob(p: NodeParams) extends Bundle {
  val tu = UInt(p.pipes.tuBits.W)
  val ray = new RayData
  val tmax = UInt(32.W)
  val words = Vec(p.slotBytes / 4, UInt(32.W))
  val err = Bool()
}

/** NODE_FORMAT=q<k>: turns the quantized node of bvh.QNodeLayout into the full-layout words BoxPipe takes,
  * in the model's order (QNodeLayout.plane), one node per cycle, no stalls:
  *   1: per child and plane q * 2^e of its axis (exact: Fp.fromUIntScaled)   2: origin + that, fp32 nearest even.
  * Without PIPELINE, a register after each (`latency` 2); with it, the Stager places registers at the budget inside
  * both (an unpipelined decode of M=4 was 22 LUT levels on xc5v, the deepest path of a q8 platform) and one on the
  * output. Empty slots decode like the others (ref 0 keeps them from hitting in BoxPipe).
  */
class NodeDecode(p: NodeParams) extends Module {
  require(p.quantBits > 0, "NodeDecode is the quantized node format's stage")
  val io = IO(new Bundle {
    val in = Flipped(Valid(new NodeJob(p)))
    val out = Valid(new BoxJob(p.pipes))
  })
  private val f = FpFormat.fp32
  private val lay = new QNodeLayout(p.m, p.quantBits)
  private val in = io.in.bits
  private val stream = Cat(in.words.slice(lay.streamWord0, lay.usedWords).reverse)
  private def field(bit: Int, width: Int): UInt = stream(bit + width - 1, bit)
  // the fixed stages are two registers: one after the scaling, one after the sum
  private val pipe = p.pipes.pipe
  private def fixed[T <: Data](x: Timed[T]): Timed[T] = if (pipe.budget.isEmpty) Timed(RegNext(x.v), x.at + 1, 0) else x

  private val scaled = Seq.tabulate(p.m, 6) { (c, k) =>
    fixed(Fp.fromUIntScaledT(pipe, f, Timed(field(lay.planeBit(c, k), lay.bits), 0, 0), Timed(field(lay.expBit(k % 3), 8).asSInt, 0, 0)))
  }
  private val sums = Seq.tabulate(p.m, 6)((c, k) => fixed(Fp.addT(pipe, f, Timed(in.words(k % 3), 0, 0), scaled(c)(k))))
  /** Cycles from a node in to its box job out. */
  val latency: Int = sums.flatten.map(_.at).max + (if (pipe.budget.isEmpty) 0 else 1)
  private val last = latency - (if (pipe.budget.isEmpty) 0 else 1)

  val out = Wire(new BoxJob(p.pipes))
  private def late[T <: Data](x: T): T = pipe.delayTo(Timed(x, 0, 0), last).v
  out.tu := late(in.tu); out.ray := late(in.ray); out.tmax := late(in.tmax); out.err := late(in.err)
  for (c <- 0 until p.m) {
    for (k <- 0 until 6) out.words(7 * c + k) := pipe.delayTo(sums(c)(k), last).v
    out.words(7 * c + 6) := late(in.words(lay.refWord0 + c))
  }
  io.out.valid := ShiftRegister(io.in.valid, latency, false.B, true.B)
  io.out.bits := (if (pipe.budget.isEmpty) out else RegNext(out))
}

object NodeDecode {
  /** The fixed stages' latency (PIPELINE=none): a register after the scaling, one after the sum. */
  val FixedLatency = 2
  private val memo = scala.collection.concurrent.TrieMap[NodeParams, Int]()
  /** Cycles NodeDecode takes at `p` (from an elaboration of it alone, memoized): what the throughput model adds to a
    * quantized node's test beyond the fixed stages. */
  def latencyOf(p: NodeParams): Int = memo.getOrElseUpdate(p, {
    val annos = new chisel3.stage.ChiselGeneratorAnnotation(() => new NodeDecode(p)).elaborate
    annos.collectFirst { case d: chisel3.stage.DesignAnnotation[_] => d.design.asInstanceOf[NodeDecode].latency }.get
  })

  /** The box job of a node collected as `job`: its words as they are for full nodes, through NodeDecode for q<k>. */
  def toBoxJob(p: NodeParams, valid: Bool, job: NodeJob): Valid[BoxJob] = {
    val out = Wire(Valid(new BoxJob(p.pipes)))
    if (p.quantBits == 0) {
      out.valid := valid
      out.bits.tu := job.tu; out.bits.ray := job.ray; out.bits.tmax := job.tmax; out.bits.err := job.err
      out.bits.words := VecInit(job.words.take(7 * p.m))
    } else {
      val d = Module(new NodeDecode(p))
      d.io.in.valid := valid; d.io.in.bits := job
      out := d.io.out
    }
    out
  }
}
