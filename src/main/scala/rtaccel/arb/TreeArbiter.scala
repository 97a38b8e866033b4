package rtaccel.arb

import chisel3._
import chisel3.util._

/** Round-robin arbitration of `n` requesters in a tree of `fanIn`-way round-robin arbiters with a two-entry queue
  * after each (PIPELINE: a 32-way arbiter is about 11 LUT levels; each level of the tree is a few, and the queues
  * register both valid and ready between levels). `chosen` is the winner's index, carried with it through the tree.
  * With fanIn >= n it is one RRArbiter, as before pipelining was a parameter. Every request offered is passed on
  * exactly once; the order among requesters is round robin within each group, and round robin over the groups.
  * `heldInputs`: every requester holds its request until it is taken (as a TU does); the groups at the leaves are
  * then GrantArbiters, whose grant is a register, so that a requester's valid and its ready do not meet in one
  * cycle (a cycle more per request). `grantsEverywhere` (with heldInputs): every level's arbiters are GrantArbiters,
  * since a level's register slices hold their items until taken as well, so no arbiter's choice runs from a slice's
  * valid into the next slice's data in one cycle (the TC's routed critical path on ECP5). A cycle more per level, and
  * a subtree with one busy input passes an item every other cycle: for streams far below one item a cycle (the TUs'
  * results).
  */
class TreeArbiter[T <: Data](gen: T, val n: Int, val fanIn: Int, withChosen: Boolean = true, heldInputs: Boolean = false,
    grantsEverywhere: Boolean = false) extends Module {
  require(n >= 1 && fanIn >= 2, s"a tree arbiter needs requesters (got $n) and a fan-in of 2 or more (got $fanIn)")
  require(!grantsEverywhere || heldInputs, "grants at every level need requesters that hold their requests (heldInputs)")
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

  /** One level: groups of fanIn inputs, each arbitrated and queued, their winners tagged with their full index. The
    * queues are register slices (two entries, valid and ready from registers): a two-entry Queue's valid and ready
    * are its pointers' compare, which chained from level to level into the next queue's RAM write (the TC's routed
    * critical path on ECP5, through five queues of its 32-way result tree).
    */
  private def level(ins: Seq[DecoupledIO[Tagged]], leaves: Boolean): Seq[DecoupledIO[Tagged]] =
    ins.grouped(fanIn).map { g =>
      val s = Module(new RegSlice(new Tagged))
      s.io.enq <> arbitrate(g, leaves)
      s.io.deq
    }.toSeq
  private def arbitrate(g: Seq[DecoupledIO[Tagged]], leaves: Boolean): DecoupledIO[Tagged] =
    if (leaves && heldInputs || grantsEverywhere && g.length > 1) fed(Module(new GrantArbiter(new Tagged, g.length)).io, g)
    else if (g.length == 1) g.head
    else fed(Module(new RRArbiter(new Tagged, g.length)).io, g)
  /** An arbiter's output, its inputs driven by g. */
  private def fed(a: ArbiterIO[Tagged], g: Seq[DecoupledIO[Tagged]]): DecoupledIO[Tagged] = {
    a.in.zip(g).foreach { case (x, y) => x <> y }
    a.out
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
    for (d <- 0 until depth) l = level(l, d == 0)
    arbitrate(l, depth == 0)
  }
  io.out.valid := top.valid
  io.out.bits := top.bits.bits
  io.chosen.foreach(_ := top.bits.idx)
  top.ready := io.out.ready
}

/** Round-robin arbitration of requesters that hold a request until it is taken (`TreeArbiter`'s `heldInputs`): the
  * grant is chosen a cycle ahead from the requests then offered and held in a register until its request is taken,
  * so `in(i).ready` is the grant bit and `out.ready`, and `out.valid` the grant's OR. The requester taken in a cycle
  * is not chosen for the next (whether it offers another then is not known a cycle ahead), so a group of busy
  * requesters passes one request per cycle, and one busy requester alone one every other cycle (a TU waits for its
  * answer between requests).
  */
class GrantArbiter[T <: Data](gen: T, n: Int) extends Module {
  val io = IO(new ArbiterIO(gen, n)) // its `chosen` is left at 0: the tree carries the index with the request
  io.chosen := 0.U
  private val none = VecInit(Seq.fill(n)(false.B))
  private val grant = RegInit(none) // one-hot or none
  private val last = RegInit(0.U(log2Ceil(n).max(1).W)) // the requester granted last: round robin starts after it
  io.out.valid := grant.asUInt.orR
  io.out.bits := Mux1H(grant, io.in.map(_.bits))
  for (i <- 0 until n) {
    io.in(i).ready := grant(i) && io.out.ready
    when(grant(i)) { assert(io.in(i).valid, "GrantArbiter: a granted requester withdrew its request") }
  }
  private val cand = io.in.zip(grant).map { case (x, g) => x.valid && !g } // the granted one is taken or kept
  private val after = (0 until n).map(i => cand(i) && i.U > last)
  private val pick = Mux(after.reduce(_ || _), VecInit(PriorityEncoderOH(after)), VecInit(PriorityEncoderOH(cand)))
  when(!io.out.valid || io.out.ready) { // the grant is free next cycle: choose among the others
    grant := pick
    when(cand.reduce(_ || _)) { last := OHToUInt(pick) }
  }
}

object TreeArbiter {
  /** The fan-in whose round-robin arbiter fits `budget` LUT levels (about 2 per doubling plus one: a 32-way one
    * measured 11 on xc5v, make area), or every requester at once without a budget.
    */
  def fanIn(budget: Option[Int], n: Int): Int = budget.fold(n max 2)(b => 1 << math.max(1, (b - 1) / 2))
}
