package rtaccel.iu

import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.formal.{EnvBounds, RandomHarness}

/** The IU routing proof's harness (IuRoutingFormal: two free TUs, the abstract memory, the monitor) run for
  * thousands of random cycles in Verilator (treadle ran 2,000 cycles of it in 3 minutes: the floating-point pipes).
  * Its proof (make regress, depth 10) does not finish in minutes (docs/formal.md), so this is where the routing,
  * the order, the data and the answer bound are exercised; each of its faults must fail an assertion (make regress:
  * a Verilator build each).
  */
class IuRoutingSimSpec extends AnyFlatSpec with RandomHarness {
  behavior of "IntersectionUnit routing (randomized, against the proof's monitor)"
  val cycles = if (rtaccel.Regress.full) 50000 else 5000
  private val verilator = Seq(chiseltest.simulator.VerilatorBackendAnnotation)
  val live = EnvBounds(Some(1), Some(1))
  val bound = IuRoutingFormalSpec.answerBound
  private val refBits = IuRoutingFormal.platform.refs.refBits

  /** Every free input drawn at random (nodes and leaves of 1 or 2 primitives, free rays and memory words);
    * the fault fires 1 cycle in 2. Returns the requests answered. */
  def run(h: => IuRoutingFormal, seed: Long, n: Int): Long = {
    var answers = 0L
    runRandom(h, seed, n, verilator) { (d, rnd) =>
      for (t <- 0 until 2) { d.io.want(t).poke(rnd.nextInt(3) != 0); d.io.cref(t).poke(BigInt(refBits, rnd)) }
      for (k <- 0 until 3) {
        d.io.ray.o(k).poke(BigInt(32, rnd)); d.io.ray.d(k).poke(BigInt(32, rnd)); d.io.ray.inv(k).poke(BigInt(32, rnd))
      }
      d.io.ray.tmin.poke(BigInt(32, rnd))
      d.io.tmax.poke(BigInt(32, rnd))
      d.io.mem.acceptStall.poke(rnd.nextInt(3) == 0)
      d.io.mem.respStall.poke(rnd.nextInt(3) == 0)
      d.io.mem.data.poke(BigInt(256, rnd))
      d.io.mem.err.poke(rnd.nextInt(16) == 0)
      d.io.bugFire.poke(rnd.nextBoolean())
    } { d => if (d.io.answered.peek().litToBoolean) answers += 1 }
    answers
  }

  it should s"answer each TU request once, in order, with the memory's data, within $bound cycles over $cycles random cycles" in {
    val answers = run(new IuRoutingFormal(live, bound), 5, cycles)
    assert(answers > cycles / 40, s"only $answers answers in $cycles cycles")
    info(s"$answers requests answered")
  }
  if (rtaccel.Regress.full) for (bug <- Seq(IuBug.Spurious, IuBug.Retag, IuBug.Corrupt, IuBug.Duplicate, IuBug.Starve))
    it should s"fail an assertion on a ${bug.name}" in failsAnAssertion(run(new IuRoutingFormal(live, bound, bug), 6, 2000))
}
