package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.bvh.QNodeLayout
import rtaccel.fp.{Fp, FpFormat}

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
  * in the model's order (QNodeLayout.plane), two register levels, one node per cycle, no stalls:
  *   1: per child and plane q * 2^e of its axis (exact: Fp.fromUIntScaled)   2: origin + that, fp32 nearest even.
  * Empty slots decode like the others (ref 0 keeps them from hitting in BoxPipe).
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

  val scaled = RegNext(VecInit(Seq.tabulate(p.m, 6) { (c, k) =>
    Fp.fromUIntScaled(f, field(lay.planeBit(c, k), lay.bits), field(lay.expBit(k % 3), 8).asSInt)
  }.flatten))
  val origin1 = RegNext(VecInit(Seq.tabulate(3)(in.words(_))))
  val refs1 = RegNext(VecInit(Seq.tabulate(p.m)(c => in.words(lay.refWord0 + c))))
  val j1 = RegNext(in)
  val v1 = RegNext(io.in.valid, false.B)

  val out = Wire(new BoxJob(p.pipes))
  out.tu := j1.tu; out.ray := j1.ray; out.tmax := j1.tmax; out.err := j1.err
  for (c <- 0 until p.m) {
    for (k <- 0 until 6) out.words(7 * c + k) := Fp.add(f, origin1(k % 3), scaled(6 * c + k))
    out.words(7 * c + 6) := refs1(c)
  }
  io.out.valid := RegNext(v1, false.B)
  io.out.bits := RegNext(out)
}

object NodeDecode {
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
