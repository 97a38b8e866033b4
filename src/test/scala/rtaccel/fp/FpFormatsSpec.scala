package rtaccel.fp

import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.flatspec.AnyFlatSpec
import org.scalatest.matchers.should.Matchers

/** RTL against SoftFloat for other formats: exhaustive for 8-bit and 6-bit formats, edge pairs plus large
  * random runs for half precision FpFormat(5, 10) and FpFormat(8, 15); fp64 (FpFormat.fp64) against Java
  * double. One Verilator build holds all formats.
  */
class FpFormatsSpec extends AnyFlatSpec with ChiselScalatestTester with Matchers {
  private val half = FpFormat(5, 10)
  private val f815 = FpFormat(8, 15)
  private val f43 = FpFormat(4, 3)
  private val f32s = FpFormat(3, 2)
  private val fp64 = FpFormat.fp64
  private val fmts = Seq((half, 4), (f815, 2), (f43, 4), (f32s, 2), (fp64, 1))
  // make test: every edge pair and a quarter of make regress's random pairs (the exhaustive formats stay exhaustive):
  // the run is chiseltest's peek and poke, about 40,000 pairs/s, 41 s at make regress's counts
  private val full = rtaccel.Regress.full
  private val n64 = if (full) 200000 else 50000
  private val nHalf = if (full) 1000000 else 250000
  private val n815 = if (full) 300000 else 75000

  "Fp (RTL, Verilator)" should s"equal SoftFloat: exhaustive (4,3) and (3,2), half $nHalf random, (8,15) $n815 random, edge pairs; fp64 $n64 random == Java double" in {
    test(new FpOpsHarness(fmts)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
      val checks = scala.collection.mutable.ArrayBuffer[(FpCheck, Long)]()
      val t0 = System.nanoTime()
      for (((f, _), idx) <- fmts.zipWithIndex) {
        val p = dut.io(idx)
        val sf = new SoftFloat(f)
        val g = new FpTestGen(f, 11 + idx)
        val label = s"(${f.expBits},${f.manBits})"
        val n = 1L << f.width
        val (pairs, expected) =
          if (f.width <= 8) ((for (a <- 0L until n; b <- 0L until n) yield (a, b)).iterator, n * n)
          else {
            val nr = if (f == half) nHalf else if (f == fp64) n64 else n815
            (g.edgePairs.iterator ++ Iterator.fill(20000)(g.addTie()) ++ Iterator.fill(20000)(g.mulTie()) ++
              Iterator.fill(20000)(g.rangeEdge()) ++ Iterator.fill(nr)(g.mixed()), g.edgePairs.length + 60000L + nr)
          }
        val chk = new FpCheck(s"rtl$label")
        // fp64 is checked directly against Java double; the others against SoftFloat
        val ref: (Int, Long, Long) => Long = if (f == fp64) FpRef.java64 else FpRef.soft(sf)
        val ran = FpHarnessDriver.run(p, pairs, ref, chk)
        info(s"$ran pairs; " + chk.report)
        checks += ((chk, expected))
      }
      info(f"formats: ${(System.nanoTime() - t0) / 1e9}%.1f s")
      for ((chk, expected) <- checks) {
        chk.totalFailed shouldBe 0
        chk.minChecked shouldBe expected
      }
    }
  }
}
