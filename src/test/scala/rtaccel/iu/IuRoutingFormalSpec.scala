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

  // make regress only: at depth 10 z3 needs minutes (docs/formal.md)
  if (regress) it should s"answer each TU request once, tagged and in order, with the memory's data, within $answerBound cycles" in
    prove(new IuRoutingFormal(live, answerBound), depth)
  if (regress) for (bug <- Seq(IuBug.Spurious, IuBug.Retag, IuBug.Corrupt, IuBug.Duplicate))
    it should s"find a counterexample to a ${bug.name}" in refute(new IuRoutingFormal(live, answerBound, bug), depth)
}

object IuRoutingFormalSpec {
  val answerBound = 24
  val depth = 10
}
