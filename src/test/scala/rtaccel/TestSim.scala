package rtaccel

import chiseltest.simulator.VerilatorBackendAnnotation
import firrtl2.annotations.Annotation

/** The simulator of the unit specs: Verilator with no C++ optimisation (VerilatorBuild.quick). Their runs of a few
  * thousand items to a few hundred thousand cycles spend longer building the model than simulating it.
  */
object TestSim {
  val quick: Seq[Annotation] = VerilatorBackendAnnotation +: rtaccel.sim.VerilatorBuild.quick.annotations
  /** `quick` with one build per folder (build/sim-test/<folder>) that every test of the same circuit reuses:
    * chiseltest's cache compares the lowered circuit, so another circuit in the folder is rebuilt, never reused.
    */
  def cached(folder: String): Seq[Annotation] =
    quick ++ Seq(chiseltest.internal.CachingAnnotation, firrtl2.options.TargetDirAnnotation(s"build/sim-test/$folder"))
}
