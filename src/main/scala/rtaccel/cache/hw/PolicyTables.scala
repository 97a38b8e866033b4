package rtaccel.cache.hw

import chisel3._
import chisel3.util._
import rtaccel.cache.policy.{LevelPolicy, ReplacementPolicy}

/** The pure policy functions of rtaccel.cache.policy, tabulated at elaboration time so the RTL and the trace
  * model cannot disagree on a rule: the circuit only indexes tables the Scala functions filled in.
  */
object PolicyTables {
  /** Refuses a policy whose state needs more than `maxStateBits` (HwLimits.policyStateBits; rows = 2^stateBits). */
  def check(pol: ReplacementPolicy, maxStateBits: Int): Unit =
    require(pol.stateBits <= maxStateBits,
      s"the RTL tabulates replacement state of up to $maxStateBits bits; ${pol.ways}-way ${pol.getClass.getSimpleName} " +
        s"needs ${pol.stateBits}: use fewer ways (true LRU up to 4, tree PLRU up to 8)")

  /** Rows for states the policy can reach; other rows are never indexed and hold 0. */
  private def rows[T](pol: ReplacementPolicy)(f: Int => Int): Seq[Int] = {
    val reach = pol.states.toSet
    (0 until (1 << pol.stateBits)).map(s => if (reach(s)) f(s) else 0)
  }

  /** next state after touching `way` in `state` */
  def touch(pol: ReplacementPolicy, state: UInt, way: UInt): UInt =
    if (pol.stateBits == 0) 0.U(1.W)
    else {
      val t = VecInit(Seq.tabulate(pol.ways)(w => VecInit(rows(pol)(s => pol.touch(s, w)).map(_.U(pol.stateBits.W)))))
      t(way)(state(pol.stateBits - 1, 0))
    }

  /** the way the policy evicts from a full set */
  def victim(pol: ReplacementPolicy, state: UInt): UInt =
    if (pol.stateBits == 0 || pol.ways == 1) 0.U
    else VecInit(rows(pol)(pol.victim).map(_.U(log2Ceil(pol.ways).W)))(state(pol.stateBits - 1, 0))

  /** LevelPolicy.allocate(victimLevel, incomingLevel, maxLevel) for level codes as wide as the inputs and a
    * runtime MAX_LEVEL: the class of every (MAX_LEVEL, level) pair, tabulated.
    */
  def allocate(victimLevel: UInt, incomingLevel: UInt, maxLevel: UInt): Bool = {
    val bits = incomingLevel.getWidth
    require(victimLevel.getWidth == bits && maxLevel.getWidth == bits, "levels and MAX_LEVEL must share the level code width")
    val code = LevelPolicy.Code(bits)
    val n = 1 << bits
    val t = VecInit(Seq.tabulate(n)(ml => VecInit(Seq.tabulate(n)(l => code.cls(l, ml).U((bits + 1).W)))))
    t(maxLevel)(incomingLevel) <= t(maxLevel)(victimLevel)
  }
}
