package rtaccel.tu

import chisel3._
import chisel3.util._

/** The full traversal stack inside a TU: `depth` entries in LUT RAM (Mem `stack`), one push or pop per cycle; the
  * TU checks `full` before a push (a push onto a full stack is dropped and flagged) and `empty` before a pop.
  * `topInRegister` (PIPELINE): the newest entry is kept in a register and the RAM holds the ones below it, so a
  * pop's entry comes from a register (the compare with tmax and the TU's next state no longer follow a RAM read),
  * and the entry below it goes from the RAM straight into that register, read at an address that is a register too
  * (no subtract in front of the RAM). The same entries come out in the same cycles either way.
  */
class FullStack[T <: Data](entry: T, depth: Int, topInRegister: Boolean) {
  require(depth >= 1, s"a stack needs an entry (got $depth)")
  private val mem = Mem(depth, entry).suggestName("stack")
  private val n = RegInit(0.U(log2Ceil(depth + 1).W)) // entries held
  def empty: Bool = n === 0.U
  def full: Bool = n === depth.U

  private val addrBits = log2Ceil(depth).max(1)
  // topInRegister: `top` is entry n-1; the RAM holds entries 0..n-2 at their index. `at` = n-1 (where the top goes
  // when pushed under) and `below` = n-2 (the entry that becomes the top on a pop), kept as registers so that no
  // adder sits in front of the RAM (both wrap below zero, where nothing reads them)
  private val top = if (topInRegister) Some(Reg(entry)) else None
  private val emptyAt = ((1 << addrBits) - 1).U(addrBits.W) // n - 1 and n - 2 at n = 0
  private val emptyBelow = ((1 << addrBits) - 2).U(addrBits.W)
  private val at = if (topInRegister) RegInit(emptyAt) else emptyAt
  private val below = if (topInRegister) RegInit(emptyBelow) else emptyBelow

  def clear(): Unit = { n := 0.U; if (topInRegister) { at := emptyAt; below := emptyBelow } }

  /** Pushes `e` (call only when !full). */
  def push(e: T): Unit = {
    top match {
      case Some(t) =>
        when(!empty) { mem(at) := t }
        t := e
        at := at + 1.U; below := at
      case None => mem(n) := e
    }
    n := n + 1.U
  }

  /** Takes the newest entry (call only when !empty). */
  def pop(): T = {
    n := n - 1.U
    top match {
      case Some(t) =>
        t := mem(below) // entry n-2, the new top (unused when this pop empties the stack)
        at := below; below := below - 1.U
        t
      case None => mem(n - 1.U)
    }
  }
}
