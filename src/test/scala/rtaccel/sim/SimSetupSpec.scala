package rtaccel.sim

import java.nio.file.Paths
import org.scalatest.funsuite.AnyFunSuite

/** The simulator's input files: Verilator 5.006 overruns a stack buffer on a `$readmemh` file name longer than 256
  * characters (a checkout at /check/work/main loaded a wrong image into make test's NODE_BANKS platform, where
  * /work/main did not), so the names are kept short and a longer one is refused. */
class SimSetupSpec extends AnyFunSuite {
  private val dram = DramConfig(40, 4, 1)
  private def setup(name: String) = SimSetup(1 << 17, name, name, 1 << 16, dram)

  test("a $readmemh file name of 256 characters is taken, one of 257 refused with what to change") {
    val ok = "/" + "a" * (SimSetup.maxFileNameChars - 1)
    assert(setup(ok).imageHex == ok)
    val e = intercept[rtaccel.io.InputError](setup(ok + "b"))
    assert(e.getMessage.contains("257 characters") && e.getMessage.contains("shorter path"), e.getMessage)
  }

  test("a build's input folder is short whatever its key's length, one per key") {
    val work = Paths.get("build/sim-test/SimSetupSpec")
    val long = "tus4-ius2-ch2.4096-m4-refs27.27.4.4-stack64-axi256-div6-rays131072-words2097152-lat40-bw4000-jit41-stall25-seed4-" +
      "err197-short1.64-rtagged-raystore-tagfwd-banks2-o0-c64.2.lrp-c32.1.dm-mppl4-log2097152-p4fb7d1e43f"
    val d = SimSetup.inputDir(work, long)
    assert(d.startsWith(work) && d.toString.length - work.toString.length <= 20, d.toString)
    assert(SimSetup.inputDir(work, long) == d)
    assert(SimSetup.inputDir(work, long + "x") != d)
  }
}
