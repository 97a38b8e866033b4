package rtaccel.sim

import chiseltest.simulator.{VerilatorCFlags, VerilatorFlags}
import firrtl2.annotations.Annotation

/** How a simulator is compiled: Verilator's own options, the C++ compiler's flags and the optimisation level
  * of the model's hot code (make's OPT_FAST, which the generated makefile puts last and so wins over any
  * -CFLAGS level). chiseltest runs Verilator and then `make`; with `--build` Verilator compiles the model
  * itself, with our make variables, and chiseltest's own make then finds it up to date. Its name is part of
  * the build folder (Simulate's key), so a build of another profile is never reused.
  */
final case class VerilatorBuild(name: String, verilatorFlags: Seq[String], cFlags: Seq[String], optFast: Option[String],
                                jobs: Int = 2) {
  require(name.matches("[a-z0-9]+"), s"a build profile name is lower-case letters and digits (got '$name')")
  /** The chiseltest annotations of this profile. `sources`: more Verilog files for Verilator (chiseltest keeps one
    * VerilatorFlags annotation, so they go into this profile's).
    */
  def annotations: Seq[Annotation] = withSources(Nil)
  def withSources(sources: Seq[String]): Seq[Annotation] = {
    // with Verilator's own build the compiler is ours to choose: clang when make deps installed it
    val cxx = VerilatorBuild.compiler.fold("")(c => s" CXX=$c LINK=$c")
    val build = optFast.toSeq.flatMap(o => Seq("--build", "-j", jobs.toString, "-MAKEFLAGS", s"OPT_FAST=$o OPT_GLOBAL=$o$cxx"))
    val flags = verilatorFlags ++ build ++ sources
    Seq(VerilatorCFlags(cFlags)) ++ (if (flags.isEmpty) Nil else Seq(VerilatorFlags(flags)))
  }
}

object VerilatorBuild {
  /** What make simulate used until the profiles existed: -CFLAGS -O1 (the hot code stays at Verilator's -Os,
    * OPT_FAST, which the generated makefile puts after -CFLAGS). Quickest to build.
    */
  val legacy: VerilatorBuild = VerilatorBuild("o1", Nil, Seq("-O1"), None)
  /** Verilator's -O3 (its slow optimisations: every module inlined, `--inline-mult -1`): the quickest model
    * measured (docs/platform.md, "Simulation speed"), at a longer build.
    */
  val fast: VerilatorBuild = VerilatorBuild("fast", Seq("-O3"), Seq("-O1"), None)
  /** No C++ optimisation at all: a third less build time than `legacy` for a model about 4× slower per cycle
    * (cornell, 4 TUs: 60 s against 88 s to build, 2.2e4 against 8.1e4 cycles/s). The test suites' runs of a few
    * hundred rays spend far longer building than simulating, so they use it.
    */
  val quick: VerilatorBuild = VerilatorBuild("o0", Nil, Seq("-O0"), Some("-O0"))
  /** The C++ compiler of the profiles Verilator builds itself (`optFast`): RTACCEL_CXX, which the Makefile sets
    * (clang when make deps installed it), else Verilator's default g++. At -O0 clang compiles a platform's model in
    * about 0.63 of g++'s time (the 8-TU all-formats circuit of PlatformSpec: 19.9 s against 31.5 s, one core), and
    * the test suites' builds are mostly that compile.
    */
  lazy val compiler: Option[String] = sys.env.get("RTACCEL_CXX").filter(c => c.nonEmpty && c != "g++")

  /** Tried and measured (docs/platform.md), kept so that the comparison can be rerun with SIM_BUILD=<name>. */
  private val tried: Seq[VerilatorBuild] = Seq(
    VerilatorBuild("xfast", Seq("--x-assign", "fast", "--x-initial", "fast"), Seq("-O1"), None),
    VerilatorBuild("os2", Nil, Seq("-O1"), Some("-O2")),
    VerilatorBuild("os3", Nil, Seq("-O1"), Some("-O3")),
    VerilatorBuild("split", Seq("--output-split", "5000", "--output-split-cfuncs", "5000"), Seq("-O1"), None),
    VerilatorBuild("thr2", Seq("--threads", "2"), Seq("-O1"), None))
  val all: Seq[VerilatorBuild] = Seq(legacy, fast, quick) ++ tried

  /** Runs with at least this many rays build `fast`: only a long run wins back -O3's longer build (the test
    * suites' runs, a few hundred rays each, keep the quick build).
    */
  val fastFromRays: Int = 1 << 18

  /** The profile of a run of `rays` rays when SIM_BUILD is not given. */
  def auto(rays: Int): VerilatorBuild = if (rays >= fastFromRays) fast else legacy

  def named(n: String): VerilatorBuild = all.find(_.name == n).getOrElse(
    throw new rtaccel.io.InputError(s"SIM_BUILD must be one of ${all.map(_.name).mkString(", ")} (got '$n')"))
}
