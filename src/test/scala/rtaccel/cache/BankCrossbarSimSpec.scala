package rtaccel.cache

import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.formal.{EnvBounds, RandomHarness}

/** The NODE_BANKS crossbar's harness (BankCrossbarHarness: its abstract banks and its monitor's assertions) driven
  * with random free inputs for many cycles. The bounded proof reaches only a few cycles (docs/formal.md), so this
  * is where long traces (many answers interleaved over both banks and both clusters) are checked; each fault of
  * XbarBug must make an assertion fail, so the monitor is known to see it.
  */
class BankCrossbarSimSpec extends AnyFlatSpec with RandomHarness {
  behavior of "BankCrossbar (randomized, against its monitor)"
  val (cycles, seeds) = if (rtaccel.Regress.full) (100000, 1 to 3) else (20000, 1 to 1)

  /** Drives every free input from `seed` for `n` cycles (the fault, if any, fires 1 cycle in 8); returns the
    * beats each cluster received. */
  def run(h: => BankCrossbarHarness, seed: Long, n: Int): Seq[Long] = {
    val beats = Array.fill(2)(0L)
    runRandom(h, seed, n) { (d, rnd) =>
      for (c <- 0 until 2) {
        d.io.reqValid(c).poke(rnd.nextInt(4) != 0)
        d.io.reqRef(c).poke(rnd.nextInt(8))
        d.io.reqTag(c).poke(rnd.nextInt(2))
        d.io.sinkStall(c).poke(rnd.nextInt(3) == 0)
        d.io.bank(c).acceptStall.poke(rnd.nextInt(3) == 0)
        d.io.bank(c).respStall.poke(rnd.nextInt(3) == 0)
        d.io.bank(c).pick.poke(rnd.nextInt(2))
      }
      d.io.bugFire.poke(rnd.nextInt(8) == 0)
    } { d => for (c <- 0 until 2) if (d.io.beatTo(c).peek().litToBoolean) beats(c) += 1 }
    beats.toSeq
  }

  val live = EnvBounds(Some(1), Some(1))
  for ((name, env) <- Seq("stalls of one cycle, every request answered within the bound" -> live,
      "unbounded stalls" -> EnvBounds(None, None)))
    it should s"route every answer whole and once to its cluster and TU over ${seeds.size} x $cycles random cycles: $name" in {
      for (seed <- seeds) {
        val beats = run(new BankCrossbarHarness(env, BankCrossbarSimSpec.answerBound), seed, cycles)
        // each cluster must have received many answers (2 beats each), or the run checked little
        beats.foreach(b => assert(b > cycles / 20, s"beats per cluster $beats over $cycles cycles"))
        info(s"seed $seed: beats to cluster 0 / 1: ${beats.mkString(" / ")}")
      }
    }

  for (bug <- Seq(XbarBug.Spurious, XbarBug.Corrupt, XbarBug.Misroute))
    it should s"fail an assertion on a ${bug.name}" in
      failsAnAssertion(run(new BankCrossbarHarness(live, BankCrossbarSimSpec.answerBound, bug), 100, 2000))
}

object BankCrossbarSimSpec {
  /** cycles from a request's acceptance to its answer's last beat with stalls of one cycle: 1 into the bank's slot,
    * then at most one other answer of the bank ahead of it (the bank's fairness) and its own, each waiting for one
    * whole answer of the other bank to its cluster (4 cycles: 2 beats, a stall before each), a stall of its bank (1)
    * and its 2 beats (4): 1 + 2 x (4 + 1 + 4) = 19, rounded to 20. The random runs have seen 16 (15 was exceeded). */
  val answerBound = 20
}
