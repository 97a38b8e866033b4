// One Scala project: reference model, BVH builder, config, the Chisel generators of the platform and the tools around them.
// Versions are the stack verified to resolve from Maven Central (see docs/toolchain.md).
ThisBuild / scalaVersion := "2.13.15"
ThisBuild / version      := "0.1.0"
ThisBuild / organization := "rtaccel"

val chiselVersion = "6.7.0"

lazy val root = (project in file("."))
  .settings(
    name := "rtaccel",
    libraryDependencies ++= Seq(
      "org.chipsalliance" %% "chisel"     % chiselVersion,
      "edu.berkeley.cs"   %% "chiseltest" % "6.0.0", // also used by the simulate entry point
      "org.scalatest"     %% "scalatest"  % "3.2.19" % Test,
      "com.lihaoyi"       %% "ujson"      % "3.1.0",
      "com.github.scopt"  %% "scopt"      % "4.1.0", // command-line flags of the entry points (cli/Flags)
      "org.apache.commons" % "commons-math3" % "3.6.1" // least squares of the fitted cost model (cli/CostFit)
    ),
    addCompilerPlugin("org.chipsalliance" % "chisel-plugin" % chiselVersion cross CrossVersion.full),
    scalacOptions ++= Seq("-language:reflectiveCalls", "-deprecation", "-feature", "-Xcheckinit", "-Ymacro-annotations"),
    // Tests share the 2-core machine with Verilator builds; keep them in one forked JVM with a big stack.
    Test / fork := true,
    // Two suites at a time in that JVM: a Verilator build is half single-threaded (elaboration, verilation), so
    // the other core compiles or simulates the next suite meanwhile. Suites share no folder (each names its own).
    Test / testForkedParallel := true,
    // The tests' JVM mostly elaborates circuits once each. The C1 compiler alone (no C2) cut the CPU time of a
    // whole-platform test from 82 s to 64 s (the parallel collector alone: 74 s); with both, a simulation-driven IU
    // test ran 29 s -> 21 s and ten million SoftFloat pairs took the same 27 s.
    Test / javaOptions ++= Seq("-Xss16m", "-Xmx6g", "-XX:TieredStopAtLevel=1", "-XX:+UseParallelGC"),
    // Verilator's makefile names g++; a make variable given in MAKEFLAGS overrides it, so every simulator the tests
    // build (chiseltest's own make included) compiles with RTACCEL_CXX, which the Makefile sets (clang when make deps
    // installed it: about 0.6 of g++'s compile time for the same model, docs/platform.md "Test time").
    Test / envVars ++= sys.env.get("RTACCEL_CXX").filter(c => c.nonEmpty && c != "g++").map(c => "MAKEFLAGS" -> s"CXX=$c LINK=$c").toMap,
    Test / testOptions += Tests.Argument(TestFrameworks.ScalaTest, "-oD", "-u", "build/test-reports/scala"),
    Compile / run / fork := true,
    Compile / run / javaOptions ++= Seq("-Xss16m", "-Xmx8g")
  )
