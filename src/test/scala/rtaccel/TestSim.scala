package rtaccel

import chiseltest.simulator.VerilatorBackendAnnotation
import firrtl2.annotations.Annotation

/** The simulator of the unit specs: Verilator with no C++ optimisation (VerilatorBuild.quick). Their runs of a few
  * thousand items to a few hundred thousand cycles spend longer building the model than simulating it.
  */
object TestSim {
  val quick: Seq[Annotation] = VerilatorBackendAnnotation +: rtaccel.sim.VerilatorBuild.quick.annotations
  /** `gen` compiled by firtool and driven through its `io` (sim.FirtoolHarness: a third to a half less build time than
    * chiseltest's firrtl2 path); its SystemVerilog in build/sim-test/<folder>/sv, the simulator in <folder>/rtl,
    * where the next test of the same circuit finds it. `module` is the elaborated module.
    */
  final case class Firtool[M, I <: chisel3.Data](module: M, gen: () => rtaccel.sim.FirtoolShell[I], annotations: Seq[Annotation])
  def firtool[M <: chisel3.Module, I <: chisel3.Data](folder: String, build: rtaccel.sim.VerilatorBuild = rtaccel.sim.VerilatorBuild.quick)(gen: => M)(io: M => I): Firtool[M, I] = {
    val s = rtaccel.sim.FirtoolHarness.shell(gen, java.nio.file.Paths.get("build/sim-test", folder, "sv"))(io)
    // one build per folder, reused by the next test of the same circuit (the shell's name is the text's digest)
    Firtool(s.module, s.gen, Seq(VerilatorBackendAnnotation, chiseltest.internal.CachingAnnotation,
      firrtl2.options.TargetDirAnnotation(s"build/sim-test/$folder/rtl")) ++ build.withSources(s.sources))
  }
  /** `quick` with one build per folder (build/sim-test/<folder>) that every test of the same circuit reuses:
    * chiseltest's cache compares the lowered circuit, so another circuit in the folder is rebuilt, never reused.
    */
  def cached(folder: String): Seq[Annotation] =
    quick ++ Seq(chiseltest.internal.CachingAnnotation, firrtl2.options.TargetDirAnnotation(s"build/sim-test/$folder"))
}
