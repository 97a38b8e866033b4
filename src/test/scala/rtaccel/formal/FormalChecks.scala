package rtaccel.formal

import chisel3.Module
import chiseltest.ChiselScalatestTester
import chiseltest.formal.{BoundedCheck, DoNotModelUndef, FailedBoundedCheckException, Formal}
import org.scalatest.Informing
import org.scalatest.flatspec.AnyFlatSpecLike

/** How the formal specs run a check (docs/formal.md): z3 (the default engine, from apt) on the harness's
  * properties up to `depth` cycles after reset, each check's wall time reported. DoNotModelUndef: Chisel's
  * undefined values (e.g. a SyncReadMem read in the cycle its address is written) get one fixed value instead
  * of a free one; modelling them freely made z3 take minutes for a depth-2 check of CachePath.
  */
trait FormalChecks extends ChiselScalatestTester with Formal { this: AnyFlatSpecLike with Informing =>
  /** CVC4 (from apt, `make z3` installs it too) instead of z3: the tagged cache path's checks, where z3 did not
    * finish depth 4 in 4 minutes (docs/formal.md) */
  val cvc4: Seq[firrtl2.annotations.Annotation] = Seq(chiseltest.formal.backends.CVC4EngineAnnotation)
  /** make regress (RTACCEL_REGRESS=full) runs the deeper bounds */
  val regress: Boolean = rtaccel.Regress.full

  private def run[T <: Module](gen: => T, depth: Int, engine: Seq[firrtl2.annotations.Annotation]): Double = {
    val t0 = System.nanoTime()
    verify(gen, Seq(BoundedCheck(depth), DoNotModelUndef) ++ engine)
    (System.nanoTime() - t0) / 1e9
  }

  /** Every assertion of the harness holds in every trace of up to `depth` cycles. */
  def prove[T <: Module](gen: => T, depth: Int, engine: Seq[firrtl2.annotations.Annotation] = Nil): Unit = {
    val s = run(gen, depth, engine)
    info(f"bound $depth cycles: proved in $s%.1f s")
  }

  /** The checker finds a counterexample within `depth` cycles (a deliberately broken harness). After z3 answers
    * sat, chiseltest 6 reads the trace back; z3 4.8 gives a memory's contents as a lambda, which chiseltest's
    * response parser does not implement (NotImplementedError in SMTModelChecker.getWitness): the counterexample was
    * found, only its VCD is not written.
    */
  def refute[T <: Module](gen: => T, depth: Int, engine: Seq[firrtl2.annotations.Annotation] = Nil): Unit = {
    val t0 = System.nanoTime()
    val e = intercept[Throwable](run(gen, depth, engine))
    val s = (System.nanoTime() - t0) / 1e9
    e match {
      case f: FailedBoundedCheckException => info(f"counterexample at cycle ${f.failAt} found in $s%.1f s")
      case n: NotImplementedError if n.getStackTrace.exists(f => f.getClassName.endsWith("SMTModelChecker") && f.getMethodName == "getWitness") =>
        info(f"counterexample found in $s%.1f s (not written as VCD: ${n.getMessage})")
      case other => throw other
    }
  }
}
