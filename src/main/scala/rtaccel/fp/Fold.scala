package rtaccel.fp

import chisel3._
import chisel3.util._

/** Operators shared across the cycles of a job, for a datapath that takes a job every `k` cycles at most (TRI_II,
  * BOX_II).
  *
  * Invariant: every value of such a datapath stays the same for k cycles from its `at` (its input is a register
  * loaded on the job's valid; every other value is a function, a delay or a [[batch]] of such values). So one
  * operator can do k operations of a job, one per cycle: operation s reads its operands at cycle `at + s`, and its
  * result is caught in a register; the batch's results leave together from registers that hold them k cycles.
  * Sharing changes no result, only latencies (the operations are the same, in the same rounding): bit-exact at every
  * k. With k = 1 a batch is its operations side by side, the circuit of before.
  *
  * `valid`: the job's valid at the datapath's input (cycle 0); a job's cycle t is marked by its valid delayed t
  * cycles (flip-flops without reset: before the first job they select operands nobody reads).
  */
final class Fold(pipe: Stager, val k: Int, valid: Bool) {
  require(k >= 1, s"an initiation interval is at least 1 cycle (got $k)")
  private val marks = scala.collection.mutable.ArrayBuffer[Bool](valid)
  /** True in the cycle a job is at its cycle t (jobs at least k cycles apart). */
  def at(t: Int): Bool = {
    while (marks.size <= t) marks += pipe.beside(marks.last, 1)
    marks(t)
  }

  /** The pipe's input: as it comes with k = 1 (`depth` levels of the driver's logic in front of it), else a register
    * loaded on valid (cycle 1), which holds the job until the next one. */
  def input[T <: Data](x: T, depth: Int): Timed[T] = if (k == 1) pipe.in(x, depth) else Timed(pipe.hold(x, valid), 1, 0)

  /** An assertion that no job comes within k cycles of the one before (`what` names the pipe and its knob). */
  def assertSpacing(what: String): Unit = if (k > 1) {
    val recent = (1 until k).map(at).reduce(_ || _)
    when(valid) { assert(!recent, s"$what: jobs closer than $k cycles") }
  }

  /** LUT levels of the selection in front of a shared operator: a 2:1 mux, else a priority mux of k inputs. */
  val selectLevels: Int = if (k == 2) 1 else 2

  /** `ops` (each its operands) done by `fn` on ceil(n / k) operators: operator i does operations i*k .. i*k+k-1 on
    * consecutive cycles. `fn` must end in a register (a [[Stager.reg]]) and treat its operands alike (one operator
    * built per group). The results are registers, valid together the cycle after the last operation's result (`k`
    * cycles after the first's), for k cycles.
    */
  def batch(ops: Seq[Seq[Timed[UInt]]])(fn: Seq[Timed[UInt]] => Timed[UInt]): Seq[Timed[UInt]] =
    if (k == 1) ops.map(fn) else {
      val arity = ops.head.size
      require(ops.forall(_.size == arity), "a batch's operations take the same operands")
      val aligned = pipe.align(ops.flatten).grouped(arity).toSeq
      val (t0, d0) = pipe.join(aligned.flatten: _*)
      val groups = aligned.grouped(k).toSeq.map { group =>
        // the group's operands side by side, operation s's selected in the cycle it is read (`t`: after any cut)
        val all = Timed(VecInit(group.flatten.map(_.v)), t0, d0)
        val sel = pipe.stepAt(all, selectLevels) { (v, t) =>
          val byOp = v.grouped(arity).toSeq
          VecInit((0 until arity).map(j => (1 until byOp.size).foldLeft(byOp.head(j)) { (acc, s) => Mux(at(t + s), byOp(s)(j), acc) }))
        }
        val r = fn((0 until arity).map(j => sel.map(0)(_(j))))
        require(r.depth == 0, "a batch's operation ends in a register")
        // operation s's result is there in cycle r.at + s: caught then, and all of them held from r.at + k on
        val caught = group.indices.map(s => if (s == k - 1) r.v else pipe.hold(r.v, at(r.at + s)))
        (r.at, caught.map(c => pipe.hold(c, at(r.at + k - 1))))
      }
      require(groups.map(_._1).distinct.size == 1, "a batch's operators take the same cycles")
      groups.flatMap(_._2).map(v => Timed(v, groups.head._1 + k, 0))
    }
}
