package rtaccel.fp

import chisel3._
import chisel3.util._

/** Fully pipelined divider: accepts one a/b per cycle, result `stages` cycles later (0 = combinational),
  * bit-identical to [[Fp.div]]. The divider is Fp.divPre, divSteps(f) restoring recurrence steps and
  * Fp.divPost (round/pack); the `stages` register levels are spread over that chain by estimated delay.
  */
class FpDivPipe(val f: FpFormat, val stages: Int) extends Module {
  require(stages >= 0, "stages must be >= 0")
  val io = IO(new Bundle {
    val in = Flipped(Valid(new Bundle {
      val a = UInt(f.width.W)
      val b = UInt(f.width.W)
    }))
    val out = Valid(UInt(f.width.W))
  })

  /** How many register levels follow each unit of the chain (pre, steps..., post). */
  val regsAfter: Seq[Int] = FpDivPipe.placement(f, stages)

  private def delay[T <: Data](x: T, v: Bool, n: Int): (T, Bool) =
    (0 until n).foldLeft((x, v)) { case ((d, vv), _) => (RegEnable(d, vv), RegNext(vv, false.B)) }

  private val steps = Fp.divSteps(f)
  var (st, vld) = delay(Fp.divPre(f, io.in.bits.a, io.in.bits.b), io.in.valid, regsAfter(0))
  for (i <- 1 to steps) {
    val d = delay(Fp.divStep(f, st), vld, regsAfter(i))
    st = d._1; vld = d._2
  }
  private val (res, resValid) = delay(Fp.divPost(f, st), vld, regsAfter(steps + 1))
  io.out.valid := resValid
  io.out.bits := res
}

object FpDivPipe {
  /** Relative delay estimates (in recurrence steps) of pre-normalisation and round/pack. */
  private val preWeight = 2.0
  private val postWeight = 4.0

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
