package rtaccel

import chiseltest.simulator.VerilatorBackendAnnotation
import firrtl2.annotations.Annotation

/** The simulator of the unit specs: Verilator with no C++ optimisation (VerilatorBuild.quick). Their runs of a few
  * thousand items to a few hundred thousand cycles spend longer building the model than simulating it.
  */
object TestSim {
  val quick: Seq[Annotation] = VerilatorBackendAnnotation +: rtaccel.sim.VerilatorBuild.quick.annotations
}
