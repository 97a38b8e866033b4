package rtaccel.tu

import chisel3._
import chisel3.util._

/** The state of the short stack with restart inside a TU (model.Traversal.traceShort, docs/architecture.md):
  * a ring of `p.shortStack` entries that overwrites its oldest entry when full (and remembers that it did),
  * and a trail of finished hit children per node level. Built in the TU's clock domain; the TU calls these
  * methods from its states, one push or pop per cycle, as it does with the full stack.
  */
class ShortStack(p: TuParams) {
  private val cap = p.shortStack
  require(cap >= 1)
  class Entry extends Bundle {
    val cref = UInt(TraversalUnit.refBits.W); val t = UInt(TraversalUnit.distBits.W); val level = UInt(ShortStack.levelBits(p).W)
  }
  // at least 2 rows so the address has a bit; only rows 0..cap-1 are used
  private val ring = Mem(math.max(2, cap), new Entry)
  private val n = RegInit(0.U(log2Ceil(cap + 1).W))
  private val head = RegInit(0.U(math.max(1, log2Ceil(cap)).W)) // the row of the next push
  private val dropped = RegInit(false.B)
  // one row per level a reference can have (0..treeLevels), so any level indexes a real row
  private val trail = Reg(Vec(p.treeLevels + 1, UInt(log2Ceil(p.m + 1).W)))
  /** Level of the current reference (the root is level 0). */
  val level = Reg(UInt(ShortStack.levelBits(p).W))

  private def wrapInc(x: UInt) = Mux(x === (cap - 1).U, 0.U, x + 1.U)
  private def wrapDec(x: UInt) = Mux(x === 0.U, (cap - 1).U, x - 1.U)

  def start(): Unit = { n := 0.U; head := 0.U; dropped := false.B; trail.foreach(_ := 0.U); level := 0.U }
  /** Hit children of the current node finished on earlier passes (0 on a first visit). */
  def skip: UInt = trail(level)
  def empty: Bool = n === 0.U
  def anyDropped: Bool = dropped

  /** Pushes a pending child of the current node (whose level was already advanced to the child's). */
  def push(cref: UInt, t: UInt): Unit = {
    val e = Wire(new Entry); e.cref := cref; e.t := t; e.level := level
    ring(head) := e
    head := wrapInc(head)
    when(n === cap.U) { dropped := true.B }.otherwise { n := n + 1.U }
  }

  /** Takes the newest entry (call only when !empty): the path's node at its level is finished. */
  def pop(): Entry = {
    val at = wrapDec(head)
    val e = ring(at)
    head := at; n := n - 1.U
    finished(e.level); level := e.level
    e
  }

  /** Ring empty after a drop: the subtree at `level` is finished; restart from the root. */
  def restart(): Unit = { finished(level); dropped := false.B; level := 0.U }

  /** The path's node at `lvl` is done: its parent has one more finished child, and deeper counts restart. */
  private def finished(lvl: UInt): Unit =
    for (l <- 0 to p.treeLevels) {
      when(lvl === (l + 1).U) { trail(l) := trail(l) + 1.U }
      when(lvl <= l.U) { trail(l) := 0.U }
    }
}

object ShortStack {
  /** Levels run 0..treeLevels (a leaf sits one below the deepest node). */
  def levelBits(p: TuParams): Int = log2Ceil(p.treeLevels + 1)
}
