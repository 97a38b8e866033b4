package rtaccel.formal

import chisel3.Module
import chiseltest._
import org.scalatest.TestSuite
import scala.util.Random

/** Runs a formal harness (docs/formal.md: a Module whose inputs are all free, with a monitor of assertions) as a
  * simulation (Verilator without C++ optimisation unless told: treadle took minutes on the cache harnesses), its
  * free inputs drawn at random every cycle. Bounded proofs stop after a few cycles; random runs reach thousands,
  * where liveness bounds ("answered within N cycles") and long interleavings are exercised. A failing assertion of
  * the harness throws chiseltest's ChiselAssertionError.
  */
trait RandomHarness extends ChiselScalatestTester { this: TestSuite =>
  /** `cycles` cycles of `gen` from `seed`: each cycle `drive` pokes every free input, then `observe` peeks.
    * `annos`: the simulator (rtaccel.TestSim.quick unless given). */
  def runRandom[T <: Module](gen: => T, seed: Long, cycles: Int, annos: firrtl2.AnnotationSeq = rtaccel.TestSim.quick)(drive: (T, Random) => Unit)(
      observe: T => Unit = (_: T) => ()): Unit = {
    val rnd = new Random(seed)
    test(gen).withAnnotations(annos) { d =>
      for (_ <- 0 until cycles) { drive(d, rnd); observe(d); d.clock.step() }
    }
  }

  /** The run must fail one of the harness's assertions (an injected fault that the monitor is meant to see). */
  def failsAnAssertion(run: => Unit): Unit = {
    val e = intercept[chiseltest.ChiselAssertionError](run)
    assert(e.getMessage.contains("assertion"), e.toString)
  }
}
