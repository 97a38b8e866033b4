package rtaccel.sim

import chiseltest.simulator.{VerilatorCFlags, VerilatorFlags}
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.io.InputError

/** The build profiles of make simulate (their runs are checked bit for bit in SimulateSpec and PlatformSpec). */
class VerilatorBuildSpec extends AnyFunSuite {
  test("o1 is exactly the build make simulate always had; fast adds Verilator's -O3 and nothing else") {
    assert(VerilatorBuild.legacy.annotations == Seq(VerilatorCFlags(Seq("-O1"))))
    assert(VerilatorBuild.fast.annotations == Seq(VerilatorCFlags(Seq("-O1")), VerilatorFlags(Seq("-O3"))))
  }

  test("a C++ level for the hot code goes to make through Verilator's own build (the makefile puts OPT_FAST last)") {
    val os2 = VerilatorBuild.named("os2").annotations.collect { case VerilatorFlags(f) => f }
    val cxx = VerilatorBuild.compiler.fold("")(c => s" CXX=$c LINK=$c")
    assert(os2 == Seq(Seq("--build", "-j", "2", "-MAKEFLAGS", s"OPT_FAST=-O2 OPT_GLOBAL=-O2$cxx")))
    // make deps installs clang-14: the profiles Verilator builds itself compile with it
    assume(sys.env.get("RTACCEL_CXX").forall(_.isEmpty), "RTACCEL_CXX chooses the compiler")
    assert(VerilatorBuild.compiler.forall(_.startsWith("clang")), VerilatorBuild.compiler)
  }

  test("names are unique, valid in a folder name, and an unknown one is one input error listing them") {
    val names = VerilatorBuild.all.map(_.name)
    assert(names.distinct == names && names.forall(_.matches("[a-z0-9]+")))
    val e = intercept[InputError](VerilatorBuild.named("O1"))
    assert(e.getMessage.startsWith("SIM_BUILD must be one of o1, fast,") && e.getMessage.contains("(got 'O1')"))
    assert(intercept[IllegalArgumentException](VerilatorBuild("a-b", Nil, Nil, None)).getMessage.contains("a-b"))
  }

  test("without SIM_BUILD the quick build serves short runs and -O3 the long ones, from 2^18 rays on") {
    assert(VerilatorBuild.auto(1) == VerilatorBuild.legacy && VerilatorBuild.auto((1 << 18) - 1) == VerilatorBuild.legacy)
    assert(VerilatorBuild.auto(1 << 18) == VerilatorBuild.fast && VerilatorBuild.auto(1000000) == VerilatorBuild.fast)
  }
}
