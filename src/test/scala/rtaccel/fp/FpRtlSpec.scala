package rtaccel.fp

import chiseltest._
import chiseltest.simulator.VerilatorBackendAnnotation
import org.scalatest.flatspec.AnyFlatSpec
import org.scalatest.matchers.should.Matchers

/** RTL (Verilator) against Java float for fp32: all edge pairs, constructed ties and range edges, and
  * 1M random pairs through every op (each pair goes through all 13 functions in parallel, 4 lanes per poke/peek).
  */
class FpRtlSpec extends AnyFlatSpec with ChiselScalatestTester with Matchers {
  private val fp32 = FpFormat.fp32
  private val lanes = 4
  // make test: the edge, tie and range-edge pairs in full and a quarter of make regress's random pairs (the run is
  // chiseltest's peek and poke, about 40,000 pairs/s: 1e6 pairs took 25 s); SoftFloatSpec checks millions at the model
  private val nRandom = if (rtaccel.Regress.full) 1000000 else 250000

  "Fp (fp32 RTL, Verilator)" should s"equal Java float on edge pairs, ties, range edges and $nRandom random pairs per op" in {
    test(new FpOpsHarness(Seq((fp32, lanes)))).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
      val p = dut.io(0)
      val g = new FpTestGen(fp32, 7)
      val cov = new FpCoverage32 // edge classes hit by all streams below, judged independently with float64
      def covered(it: Iterator[(Long, Long)]) = it.map { ab => (0 until 4).foreach(op => cov.add(op, ab._1, ab._2)); ab }

      val edge = new FpCheck("rtl32-edges")
      val nEdge = FpHarnessDriver.run(p, covered(g.edgePairs.iterator), FpRef.java32, edge)
      info(s"$nEdge edge pairs; " + edge.report)

      val constructed = (Iterator.fill(30000)(g.addTie()) ++ Iterator.fill(30000)(g.mulTie()) ++
        Iterator.fill(30000)(g.rangeEdge()) ++ Iterator.fill(10000)(g.cancel()))
      val cons = new FpCheck("rtl32-constructed")
      val nCons = FpHarnessDriver.run(p, covered(constructed), FpRef.java32, cons)
      info(s"$nCons constructed pairs; " + cons.report)

      val rnd = new FpCheck("rtl32-random")
      val t0 = System.nanoTime()
      val nRnd = FpHarnessDriver.run(p, covered(Iterator.fill(nRandom)(g.mixed())), FpRef.java32, rnd)
      val secs = (System.nanoTime() - t0) / 1e9
      info(s"$nRnd random pairs; " + rnd.report)
      info(f"RTL fp32: ${nRnd / secs}%.0f operand pairs/s (${nRnd * FpOps.n / secs}%.0f checked ops/s incl. Java reference), $secs%.1f s")

      info("edge-class coverage of all pairs:\n" + cov.report)
      edge.totalFailed shouldBe 0
      cons.totalFailed shouldBe 0
      rnd.totalFailed shouldBe 0
      edge.minChecked should be >= 5000L
      rnd.minChecked shouldBe nRandom.toLong
      cov.missing shouldBe empty
    }
  }
}
