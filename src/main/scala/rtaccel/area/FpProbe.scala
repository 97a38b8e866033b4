package rtaccel.area

import chisel3._
import rtaccel.fp.{Fp, FpDivPipe, FpFormat}
import rtaccel.io.InputError

/** One floating-point operation of rtaccel.fp between flip-flops, so that its isolated synthesis (make area-fp)
  * measures the operation's own logic and its LUT levels from input register to result register, as a vendor
  * core's figures are quoted.
  */
class FpProbe(op: FpProbe.Op, f: FpFormat) extends Module {
  override def desiredName: String = FpProbe.moduleName(op)
  val io = IO(new Bundle {
    val a = Input(UInt(f.width.W))
    val b = Input(UInt(f.width.W))
    val y = Output(UInt(f.width.W))
  })
  io.y := RegNext(op.build(f, RegNext(io.a), RegNext(io.b)))
}

object FpProbe {
  final case class Op(name: String, about: String, build: (FpFormat, UInt, UInt) => UInt)

  /** The divider as the pipelines instantiate it (TriPipe, TraversalController: the default divStages). */
  val divStages: Int = rtaccel.config.Presets.paper2017.divStages

  private def divider(f: FpFormat, a: UInt, b: UInt): UInt = {
    val d = Module(new FpDivPipe(f, divStages))
    d.io.in.valid := true.B
    d.io.in.bits.a := a
    d.io.in.bits.b := b
    d.io.out.bits
  }

  /** What the box and triangle pipelines use; sub is add with b's sign flipped and max mirrors min. */
  val ops: Seq[Op] = Seq(
    Op("add", "adder (sub is the same circuit)", Fp.add),
    Op("mul", "multiplier", Fp.mul),
    Op("div", s"FpDivPipe, $divStages stages", divider),
    Op("lt", "compare a < b (NaN: false)", (f, a, b) => Fp.lt(f, a, b).asUInt),
    Op("min", "minNum (a NaN operand gives the other)", Fp.minNum),
    Op("minprop", "minProp (a NaN operand gives NaN)", Fp.minProp))

  def moduleName(op: Op): String = s"FpProbe_${op.name}"

  def byName(name: String): Op = ops.find(_.name == name).getOrElse(
    throw new InputError(s"unknown fp32 operation '$name' in OPS=; choose from ${ops.map(_.name).mkString(", ")}"))
}
