package rtaccel.cache

import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.config.{CacheParams, CachePolicy}
import rtaccel.formal.{EnvBounds, RandomHarness}

/** The cache path's proof harness (CachePathFormal: abstract memory, free requests and stalls, the monitor) run for
  * thousands of random cycles. The proofs stop at 8–14 cycles, short of their answer bound (16 cycles
  * from acceptance), so "answered within the bound" and the faults that need long traces (a lost `last`, a starved
  * output) are exercised here (docs/formal.md, "Random runs of the harnesses").
  */
class CachePathSimSpec extends AnyFlatSpec with RandomHarness {
  behavior of "CachePath (randomized, against the proof's monitor)"
  val cycles = if (rtaccel.Regress.full) 100000 else 10000
  val live = EnvBounds(Some(1), Some(1))
  val bound = CachePathFormalSpec.answerBound
  val dm = CacheParams(4, 1, CachePolicy.Dm)
  val lru = CacheParams(8, 2, CachePolicy.Lru)

  /** Every free input drawn at random (16 lines over 4 sets: hits, misses, conflicts); the fault fires 1 cycle in
    * 8. Returns the answers the monitor saw. */
  def run(h: => CachePathFormal, seed: Long, n: Int): Long = {
    var answers = 0L
    runRandom(h, seed, n) { (d, rnd) =>
      d.io.reqValid.poke(rnd.nextInt(3) != 0)
      d.io.reqLine.poke(rnd.nextInt(16))
      d.io.reqLevel.poke(rnd.nextInt(4))
      d.io.reqTag.poke(rnd.nextInt(2))
      d.io.maxLevel.poke(3)
      d.io.sinkStall.poke(rnd.nextInt(3) == 0)
      d.io.mem.acceptStall.poke(rnd.nextInt(3) == 0)
      d.io.mem.respStall.poke(rnd.nextInt(3) == 0)
      d.io.mem.data.poke(BigInt(32, rnd))
      d.io.mem.err.poke(rnd.nextInt(16) == 0)
      d.io.bugFire.poke(rnd.nextInt(8) == 0)
    } { d => if (d.io.answered.peek().litToBoolean) answers += 1 }
    answers
  }

  // (name, harness, in make test: the in-order and the tagged DM paths; make regress runs all five, longer)
  val configs = Seq(
    ("direct-mapped, in order", () => new CachePathFormal(dm, live, bound), true),
    ("2-way LRU, in order", () => new CachePathFormal(lru, live, bound), false),
    ("direct-mapped, one lookup per cycle (TAG_FORWARD=1)", () => new CachePathFormal(dm, live, bound, forward = true), false),
    ("direct-mapped, tagged answers (2 requesters)", () => new CachePathFormal(dm, live, CachePathFormalSpec.taggedBound, tagged = true), true),
    ("2-way LRU, tagged answers", () => new CachePathFormal(lru, live, CachePathFormalSpec.taggedBound, tagged = true), false))
  for ((name, h, quick) <- configs if rtaccel.Regress.full || quick)
    it should s"answer each request once, with the memory's data, within $bound cycles over $cycles random cycles: $name" in {
      val answers = run(h(), 7, cycles)
      assert(answers > cycles / 20, s"only $answers answers in $cycles cycles")
      info(s"$answers answers")
    }

  val faults = Seq(PathBug.Spurious, PathBug.Corrupt, PathBug.NoLast, PathBug.Starve)
  for (bug <- faults)
    it should s"fail an assertion on a ${bug.name}" in failsAnAssertion(run(new CachePathFormal(dm, live, bound, bug), 8, 3000))
  // TAG_FORWARD=1 without forwarding (PathBug.NoForward) was not seen in 3,000 random cycles, with requests spread
  // or confined to one set: its hazard needs one exact back-to-back sequence on the line the monitor checks. Its
  // bounded proof finds it (CachePathFormalSpec, make regress).
}
