package rtaccel.formal

import chisel3.Module
import chiseltest.ChiselScalatestTester
import chiseltest.formal.{BoundedCheck, DoNotModelUndef, FailedBoundedCheckException, Formal}
import org.scalatest.Informing
import org.scalatest.flatspec.AnyFlatSpecLike

/** How the formal specs run a check (docs/formal.md): Yices 2 (`yices-smt2`, from PyPI into the venv with the
  * rest of requirements.txt) on the harness's properties up to `depth` cycles after reset, each check's wall time
  * reported. RTACCEL_FORMAL_ENGINE=z3|cvc4 runs the same checks on z3 or CVC4 (from apt, `make z3`) to compare:
  * Yices proved make test's checks in 92 s where z3 and CVC4 took 148 s, and it returns memories in a form
  * chiseltest reads back, so a counterexample comes with its cycle. DoNotModelUndef: Chisel's undefined values
  * (e.g. a SyncReadMem read in the cycle its address is written) get one fixed value instead of a free one;
  * modelling them freely made z3 take minutes for a depth-2 check of CachePath.
  */
trait FormalChecks extends ChiselScalatestTester with Formal { this: AnyFlatSpecLike with Informing =>
  /** The engine of every check: RTACCEL_FORMAL_ENGINE (yices, the default; z3; cvc4). */
  val engine: Seq[firrtl2.annotations.Annotation] = sys.env.getOrElse("RTACCEL_FORMAL_ENGINE", "yices") match {
    case "yices" => Seq(chiseltest.formal.backends.Engines.yices2)
    case "z3" => Seq(chiseltest.formal.backends.Z3EngineAnnotation)
    case "cvc4" => Seq(chiseltest.formal.backends.CVC4EngineAnnotation)
    case other => throw new IllegalArgumentException(s"RTACCEL_FORMAL_ENGINE must be yices, z3 or cvc4 (got '$other')")
  }
  /** make regress (RTACCEL_REGRESS=full) runs the deeper bounds */
  val regress: Boolean = rtaccel.Regress.full

  private def run[T <: Module](gen: => T, depth: Int): Double = {
    val t0 = System.nanoTime()
    verify(gen, Seq(BoundedCheck(depth), DoNotModelUndef) ++ engine)
    (System.nanoTime() - t0) / 1e9
  }

  /** Every assertion of the harness holds in every trace of up to `depth` cycles. */
  def prove[T <: Module](gen: => T, depth: Int): Unit = {
    val s = run(gen, depth)
    info(f"bound $depth cycles: proved in $s%.1f s")
  }

  /** The checker finds a counterexample within `depth` cycles (a deliberately broken harness). After the solver
    * answers sat, chiseltest 6 reads the trace back; z3 4.8 gives a memory's contents as a lambda, which chiseltest's
    * response parser does not implement (NotImplementedError in SMTModelChecker.getWitness): with z3 the
    * counterexample was found, only its VCD is not written.
    */
  def refute[T <: Module](gen: => T, depth: Int): Unit = {
    val t0 = System.nanoTime()
    val e = intercept[Throwable](run(gen, depth))
    val s = (System.nanoTime() - t0) / 1e9
    e match {
      case f: FailedBoundedCheckException => info(f"counterexample at cycle ${f.failAt} found in $s%.1f s")
      case n: NotImplementedError if n.getStackTrace.exists(f => f.getClassName.endsWith("SMTModelChecker") && f.getMethodName == "getWitness") =>
        info(f"counterexample found in $s%.1f s (not written as VCD: ${n.getMessage})")
      case other => throw other
    }
  }
}
