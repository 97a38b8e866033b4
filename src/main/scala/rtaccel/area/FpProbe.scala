package rtaccel.area

import chisel3._
import rtaccel.fp.{Fp, FpDivPipe, FpFormat, Stager, Timed}
import rtaccel.io.InputError

/** One floating-point operation of rtaccel.fp between flip-flops, so that its isolated synthesis (make area-fp)
  * measures the operation's own logic and its LUT levels from input register to result register, as a vendor
  * core's figures are quoted.
  */
class FpProbe(op: FpProbe.Op, f: FpFormat, budget: Option[Int] = None, dsp: rtaccel.fp.DspShape = rtaccel.fp.DspShape.Dsp48) extends Module {
  override def desiredName: String = FpProbe.moduleName(op) + budget.fold("")(b => s"_p$b")
  val io = IO(new Bundle {
    val a = Input(UInt(f.width.W))
    val b = Input(UInt(f.width.W))
    val y = Output(UInt(f.width.W))
  })
  private val pipe = new Stager(budget, dsp)
  private val y = pipe.reg(op.piped(pipe, f, Timed(RegNext(io.a), 1, 0), Timed(RegNext(io.b), 1, 0)))
  /** Cycles from the input registers to the result register. */
  val latency: Int = y.at - 1
  io.y := y.v
}

object FpProbe {
  /** An operation as the pipelines build it: `piped` places registers by its Stager's budget (none: combinational). */
  final case class Op(name: String, about: String, piped: (Stager, FpFormat, Timed[UInt], Timed[UInt]) => Timed[UInt])
  private def sel(fn: (FpFormat, UInt, UInt) => UInt) = (s: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt]) => Fp.selT(s, f, a, b)(fn)

  /** The divider as the pipelines instantiate it (TriPipe, TraversalController: the default divStages). */
  val divStages: Int = rtaccel.config.Presets.paper2017.divStages

  private def divider(s: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt]): Timed[UInt] = {
    val d = Module(new FpDivPipe(f, divStages, s.budget, s.lutInputs))
    val in = s.align(Seq(a, b))
    d.io.in.valid := true.B
    d.io.in.bits.a := in(0).v
    d.io.in.bits.b := in(1).v
    Timed(d.io.out.bits, in(0).at + d.latency, 0)
  }

  /** What the box and triangle pipelines use; sub is add with b's sign flipped and max mirrors min. */
  val ops: Seq[Op] = Seq(
    Op("add", "adder (sub is the same circuit)", Fp.addT),
    Op("mul", "multiplier", Fp.mulT),
    Op("div", s"FpDivPipe ($divStages stages without a budget)", divider),
    Op("lt", "compare a < b (NaN: false)", (s, f, a, b) => Fp.cmpT(s, f, a, b)(Fp.lt).map(0)(_.asUInt)),
    Op("min", "minNum (a NaN operand gives the other)", sel(Fp.minNum)),
    Op("minprop", "minProp (a NaN operand gives NaN)", sel(Fp.minProp)))

  def moduleName(op: Op): String = s"FpProbe_${op.name}"

  def byName(name: String): Op = ops.find(_.name == name).getOrElse(
    throw new InputError(s"unknown fp32 operation '$name' in OPS=; choose from ${ops.map(_.name).mkString(", ")}"))
}
