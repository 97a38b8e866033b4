package rtaccel.iu

import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.formal.{EnvBounds, FormalChecks}

/** Bounded proofs of the IU's request/result routing (IuRoutingFormal, docs/formal.md): two TUs with free child
  * references (nodes 0..7, leaves of 1 or 2 primitives), free rays, memory stalls of up to one cycle.
  */
class IuRoutingFormalSpec extends AnyFlatSpec with FormalChecks {
  behavior of "IntersectionUnit routing (bounded proof)"
  val answerBound = IuRoutingFormalSpec.answerBound
  val live = EnvBounds(Some(1), Some(1))
  val depth = IuRoutingFormalSpec.depth

  // depth 10: Yices proves it in 13 s, each fault refuted in 12-15 s (z3 did not finish in minutes: docs/formal.md);
  // make test refutes the wrong tag, make regress every fault
  it should s"answer each TU request once, tagged and in order, with the memory's data, within $answerBound cycles" in
    prove(new IuRoutingFormal(live, answerBound), depth)
  for (bug <- Seq(IuBug.Retag) ++ (if (regress) Seq(IuBug.Spurious, IuBug.Corrupt, IuBug.Duplicate) else Nil))
    it should s"find a counterexample to a ${bug.name}" in refute(new IuRoutingFormal(live, answerBound, bug), depth)
}

object IuRoutingFormalSpec {
  val answerBound = 24
  val depth = 10
}
