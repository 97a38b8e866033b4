package rtaccel.arb

import chisel3._
import chisel3.util._

/** Round-robin arbitration of `n` requesters in a tree of `fanIn`-way round-robin arbiters with a two-entry queue
  * after each (PIPELINE: a 32-way arbiter is about 11 LUT levels; each level of the tree is a few, and the queues
  * register both valid and ready between levels). `chosen` is the winner's index, carried with it through the tree.
  * With fanIn >= n it is one RRArbiter, as before pipelining was a parameter. Every request offered is passed on
  * exactly once; the order among requesters is round robin within each group, and round robin over the groups.
  */
class TreeArbiter[T <: Data](gen: T, val n: Int, val fanIn: Int, withChosen: Boolean = true) extends Module {
  require(n >= 1 && fanIn >= 2, s"a tree arbiter needs requesters (got $n) and a fan-in of 2 or more (got $fanIn)")
  val io = IO(new Bundle {
    val in = Flipped(Vec(n, Decoupled(gen)))
    val out = Decoupled(gen)
    val chosen = if (withChosen) Some(Output(UInt(log2Ceil(n).max(1).W))) else None
  })
  // the index travels only when it is read (withChosen)
  private val idxBits = if (withChosen) log2Ceil(n).max(1) else 0
  private class Tagged extends Bundle {
    val bits = gen.cloneType
    val idx = UInt(idxBits.W)
  }

  /** One level: groups of fanIn inputs, each arbitrated and queued, their winners tagged with their full index. */
  private def level(ins: Seq[DecoupledIO[Tagged]]): Seq[DecoupledIO[Tagged]] = ins.grouped(fanIn).map(g => Queue(arbitrate(g), 2)).toSeq
  private def arbitrate(g: Seq[DecoupledIO[Tagged]]): DecoupledIO[Tagged] = if (g.length == 1) g.head else {
    val a = Module(new RRArbiter(new Tagged, g.length))
    a.io.in.zip(g).foreach { case (x, y) => x <> y }
    a.io.out
  }

  private val leaves = io.in.zipWithIndex.map { case (x, i) =>
    val t = Wire(Decoupled(new Tagged))
    t.valid := x.valid; t.bits.bits := x.bits; t.bits.idx := (if (withChosen) i.U else 0.U); x.ready := t.ready
    t
  }
  /** Levels of queues between an input and the output (0: one flat arbiter). */
  val depth: Int = Iterator.iterate(n)(k => (k + fanIn - 1) / fanIn).takeWhile(_ > fanIn).length
  private val top = {
    var l: Seq[DecoupledIO[Tagged]] = leaves
    for (_ <- 0 until depth) l = level(l)
    arbitrate(l)
  }
  io.out.valid := top.valid
  io.out.bits := top.bits.bits
  io.chosen.foreach(_ := top.bits.idx)
  top.ready := io.out.ready
}

object TreeArbiter {
  /** The fan-in whose round-robin arbiter fits `budget` LUT levels (about 2 per doubling plus one: a 32-way one
    * measured 11 on xc5v, make area), or every requester at once without a budget.
    */
  def fanIn(budget: Option[Int], n: Int): Int = budget.fold(n max 2)(b => 1 << math.max(1, (b - 1) / 2))
}
