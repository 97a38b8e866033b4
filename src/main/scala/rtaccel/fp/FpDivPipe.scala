package rtaccel.fp

import chisel3._
import chisel3.util._

/** Fully pipelined divider: accepts one a/b per cycle, result `latency` cycles later, bit-identical to [[Fp.div]].
  * The divider is Fp.divPre, divSteps(f) non-restoring recurrence steps and Fp.divPost (round/pack).
  * `lutInputs`: the family's LUT size (PipeParams.lutInputs), which a budget's placement and the rounding follow.
  * With a budget (PIPELINE=auto or <levels>), registers go wherever a path would pass `budget` LUT levels and the
  * result leaves from a register (a consumer in another module starts its own path there); without one, `stages`
  * register levels are spread over the chain by estimated delay (0 = combinational), the depths of before
  * pipelining was a parameter.
  */
class FpDivPipe(val f: FpFormat, val stages: Int, val budget: Option[Int] = None, lutInputs: Int = Depth.LutInputs) extends Module {
  require(stages >= 0, "stages must be >= 0")
  val io = IO(new Bundle {
    val in = Flipped(Valid(new Bundle {
      val a = UInt(f.width.W)
      val b = UInt(f.width.W)
    }))
    val out = Valid(UInt(f.width.W))
  })

  private val steps = Fp.divSteps(f)
  private val pipe = new Stager(budget, lutInputs = lutInputs)
  private val (res, resValid, lat) = budget match {
    case Some(_) =>
      // the counts beside the exponent difference (two adders in a row, measured 7 levels for fp32 on xc5v)
      val counted = pipe.step(pipe.in(io.in.bits, FpDivPipe.inputDepth),
        (Depth.lzc(f.manBits + 1) max (2 * Depth.carry(f.expBits + 2) + 3)) + 1)(x => Fp.divPreCount(f, x.a, x.b))
      var st = pipe.step(counted, Depth.shift(f.manBits + 1) + 1)(Fp.divPreShift(f, _))
      for (_ <- 1 to steps) st = pipe.step(st, FpDivPipe.stepLevels(f, pipe))(s => Fp.divStep(f, s))
      val out = pipe.reg(Fp.divPostT(pipe, f, st))
      (out.v, pipe.valid(io.in.valid, out.at), out.at)
    case None =>
      val regsAfter = FpDivPipe.placement(f, stages)
      def delay[T <: Data](x: T, v: Bool, n: Int): (T, Bool) =
        (0 until n).foldLeft((x, v)) { case ((d, vv), _) => (RegEnable(d, vv), RegNext(vv, false.B)) }
      var (st, vld) = delay(Fp.divPre(f, io.in.bits.a, io.in.bits.b), io.in.valid, regsAfter(0))
      for (i <- 1 to steps) {
        val d = delay(Fp.divStep(f, st), vld, regsAfter(i))
        st = d._1; vld = d._2
      }
      val (r, v) = delay(Fp.divPost(f, st), vld, regsAfter(steps + 1))
      (r, v, stages)
  }
  /** The pipeline registers (the state between steps: a census for the cost model). */
  val census: Stager.Census = if (budget.isDefined) pipe.census else Stager.Census(stages.toLong * (new Fp.DivState(f)).getWidth)
  /** Cycles from an input to its result. */
  val latency: Int = lat
  io.out.valid := resValid
  io.out.bits := res
}

object FpDivPipe {
  /** Relative delay estimates (in recurrence steps) of pre-normalisation and round/pack. */
  private val preWeight = 2.0
  private val postWeight = 4.0
  /** LUT levels assumed in front of the divider's inputs (a selection in the caller's stage). */
  val inputDepth: Int = 1
  /** One non-restoring step: an add or subtract on one carry chain, its choice in the chain's LUTs (the restoring
    * step it replaced, a compare, a subtract and a mux, was estimated 3 and measured about 4 levels for fp32 on xc5v,
    * docs/timing.md).
    */
  private[fp] def stepLevels(f: FpFormat): Int = Depth.carry(f.manBits + 3)
  /** The same where LUTs have 4 inputs (ECP5), at most two steps a cycle: there a step's carry chain and the nets
    * into and out of it took about 3 ns, and three steps at 7 levels (125 MHz) were the smallest platform's routed
    * critical path (TriPipe's divider, 9.0 ns; docs/timing.md twenty-first round).
    */
  private[fp] def stepLevels(f: FpFormat, pipe: Stager): Int =
    if (pipe.smallLuts) pipe.budget.fold(stepLevels(f))(b => stepLevels(f) max (b / 2)) else stepLevels(f)

  /** Register levels after each of the divSteps(f)+2 chain units; sums to `stages`. Cut j (1..stages) goes
    * after the unit whose cumulative delay is nearest to j/(stages+1) of the total, so the stages are balanced.
    */
  def placement(f: FpFormat, stages: Int): Seq[Int] = {
    val weights = Seq(preWeight) ++ Seq.fill(Fp.divSteps(f))(1.0) ++ Seq(postWeight)
    val cum = weights.scanLeft(0.0)(_ + _).tail // delay at the end of each unit
    val total = cum.last
    val counts = Array.fill(weights.length)(0)
    for (j <- 1 to stages) {
      val target = total * j / (stages + 1)
      val idx = cum.indices.minBy(i => math.abs(cum(i) - target))
      counts(idx) += 1
    }
    counts.toSeq
  }
}
