package rtaccel.tu

import chisel3._
import chisel3.util._
import rtaccel.fp.{Fp, FpFormat}
import rtaccel.iu.{BoxResult, IuReq, PipeParams, RayData, TriResult}

/** What shapes a traversal unit (TraversalUnit and its stacks; `PlatformParams.traversal`): the pipes' view (M, the
  * TU tag's width and the register budget, and the answers' bundles it receives), the width of a child reference's
  * address, the stacks (depth, SHORT_STACK's ring and the levels its trail tracks), the step counter's width and
  * whether a request carries the ray (RAY_STORE=0) or the IU's ray store has it. The TU's index is a port, so the TUs
  * of a platform are one module.
  */
final case class TuParams(pipes: PipeParams, refBits: Int, stackDepth: Int, shortStack: Int, treeLevels: Int, stepBits: Int,
                          rayStore: Boolean) {
  def m: Int = pipes.m
  def tuBits: Int = pipes.tuBits
  def stageBudget: Option[Int] = pipes.stageBudget
}

/** A ray handed to a TU: its id, the prepared ray (with 1/d) and tmax. */
class TuRay extends Bundle {
  val id = UInt(32.W)
  val ray = new RayData
  val tmax = UInt(32.W)
}

/** Closest hit of one ray; prim = -1 and t = +inf on a miss; overflow = the stack was too shallow. */
class TuResult extends Bundle {
  val id = UInt(32.W)
  val t = UInt(32.W)
  val prim = UInt(32.W)
  val u = UInt(32.W)
  val v = UInt(32.W)
  val overflow = Bool()
  val readError = Bool() // a node or primitive of this ray came with a memory error
  val stepLimit = Bool() // the ray needed more fetches than MAX_STEPS and ended there
}

/** Traversal unit (paper Section 4): control flow and the traversal stack of one ray, in exactly the order
  * of rtaccel.model.Traversal (docs/architecture.md, "Traversal order"):
  * issue the current ref to the IU; for a node, rank the hit children by entry distance (stable by slot),
  * descend into the nearest and push the others far-first; for a leaf, keep the closest hit (t < tmax);
  * then pop, discarding entries whose entry distance is beyond tmax.
  * A push onto a full stack is dropped, the ray is flagged `overflow` and traversal carries on (the same
  * accesses as the model); its result is the overflow record (prim -3, t = +inf, u = v = 0), never a
  * plausible wrong hit.
  * With `p.shortStack` > 0 the stack is the short stack with restart (ShortStack, model.Traversal.traceShort):
  * a node skips the hit children its trail says are finished, pushes never fail, and when the ring runs dry
  * after a drop the TU restarts at the root; same fetches in the same order as the model.
  * Step limit: each request to the IU (a node or a leaf) is a step; a ray takes `maxSteps` from the MAX_STEPS register
  * when it starts (0: no limit), and when it has made that many and needs another it ends without it, flagged
  * `stepLimit` (prim -4): a loop through a corrupted image cannot hold the TU (model.Traversal counts alike). With
  * the short stack a node deeper than the trail's levels ends the ray the same way.
  */
class TraversalUnit(p: TuParams) extends Module {
  val io = IO(new Bundle {
    val ray = Flipped(Decoupled(new TuRay))
    val req = Decoupled(new IuReq(p.tuBits, p.rayStore))
    val box = Flipped(Valid(new BoxResult(p.pipes)))
    val tri = Flipped(Valid(new TriResult(p.pipes)))
    val result = Decoupled(new TuResult)
    val busy = Output(Bool())
    val index = Input(UInt(p.tuBits.W)) // a port, not a parameter, so that every TU is one module
    val maxSteps = Input(UInt(p.stepBits.W)) // the MAX_STEPS register (0: no limit), read as a ray starts
  })
  private val index = io.index
  // with PIPELINE this TU's answers from the IU pass a register here: the compares of the TU's own tmax with an
  // answer, and the state enables they drive, then sit in the TU and not beside the IU's pipes across the chip (the
  // smallest platform's routed critical path on ECP5, docs/timing.md; a cycle more per answer:
  // PlatformParams.accessSliceCycles)
  private def mine[T <: Data](v: Valid[T], tu: T => UInt): Valid[T] = {
    val w = Wire(Valid(chiselTypeOf(v.bits))); w.valid := v.valid && tu(v.bits) === index; w.bits := v.bits
    rtaccel.arb.Slice.late(p.stageBudget, w)
  }
  private val boxIn = mine[BoxResult](io.box, _.tu)
  private val triIn = mine[TriResult](io.tri, _.tu)
  private val f = FpFormat.fp32
  private val inf = "h7f800000".U(32.W)

  object S extends ChiselEnum { val idle, issue, waitBox, push, waitTri, pop, done = Value }
  // The state is one-hot: a flip-flop per state, so that testing a state reads one flip-flop and each flip-flop's next
  // value is an OR of the transitions into it, not a decode of an encoded state (three bits: the state's next value
  // was 6 LUT levels from the step limit's flag through the request's handshake, the smallest platform's routed
  // critical path on ECP5, docs/timing.md twenty-first round).
  private val hot = RegInit(VecInit(S.all.map(x => (x.litValue == S.idle.litValue).B)))
  private def is(s: S.Type): Bool = hot(s.litValue.toInt)
  private def goto(s: S.Type): Unit = hot := VecInit(S.all.map(x => s === x))
  S.all.zipWithIndex.foreach { case (x, i) => require(x.litValue == i, "the states are numbered 0, 1, ...") }
  assert(PopCount(hot) === 1.U, "TraversalUnit: not in exactly one state")
  val r = Reg(new TuRay)
  val cur = Reg(UInt(32.W))
  val tmax = Reg(UInt(32.W))
  val best = Reg(new TuResult)
  val overflow = Reg(Bool())
  val readError = Reg(Bool())
  val stepLimit = Reg(Bool())
  // fetches the ray may still make, counted down from MAX_STEPS as the ray starts (so the register across the chip
  // is read once per ray), whether it has a limit at all, and whether it has made them all: a register set as the
  // last allowed request leaves, so the request's valid waits on no compare
  val stepsLeft = Reg(UInt(p.stepBits.W))
  val limited = Reg(Bool())
  val outOfSteps = Reg(Bool())
  class Entry extends Bundle { val cref = UInt(TraversalUnit.refBits.W); val t = UInt(TraversalUnit.distBits.W) }
  private val short = p.shortStack > 0
  // with PIPELINE the full stack's top entry is a register (FullStack): a pop's compare does not follow a RAM read
  val stack = if (short) None else Some(new FullStack(new Entry, p.stackDepth, topInRegister = p.stageBudget.isDefined))
  val ss = if (short) Some(new ShortStack(p)) else None
  val sorted = Reg(Vec(p.m, new Entry))
  val pushIdx = Reg(UInt(log2Ceil(p.m).W))
  // the push state ends after sorted(lastPush): sorted(1) with the full stack, sorted(skip + 1) with the short one
  val lastPush = if (short) Reg(UInt(log2Ceil(p.m).W)) else WireDefault(1.U(log2Ceil(p.m).W))

  // With PIPELINE a ray is taken in the cycle after its handshake, from the bits the TC drives in that cycle
  // (TraversalUnit.rayBitsLag): the load enables of the ray's registers are then `take`, a register of this TU,
  // and not the TC's offer ANDed with this TU's state across the chip (the smallest platform's routed critical
  // path on ECP5: TU state -> the TC's choice -> this TU's enables, docs/timing.md). Not ready in that cycle.
  private val lateRay = TraversalUnit.rayBitsLag(p.stageBudget) == 1
  private val take = if (lateRay) RegNext(io.ray.fire, false.B) else io.ray.fire
  io.ray.ready := is(S.idle) && (if (lateRay) !take else true.B)
  io.busy := !is(S.idle) || (if (lateRay) take else false.B)
  when(take) {
    r := io.ray.bits; cur := 0.U; tmax := io.ray.bits.tmax; overflow := false.B; readError := false.B
    stepLimit := false.B; stepsLeft := io.maxSteps; limited := io.maxSteps =/= 0.U; outOfSteps := false.B
    best.id := io.ray.bits.id; best.t := inf; best.prim := "hffffffff".U; best.u := 0.U; best.v := 0.U
    stack.foreach(_.clear()); ss.foreach(_.start())
    goto(S.issue)
  }

  // with the short stack, a node below the trail's treeLevels levels ends the ray alike: no tree that fits the trail
  // (Fit.checkTrail) has one, only a loop through a corrupted image makes it, and the trail could not track it
  private val tooDeep = ss.fold(false.B)(s => !cur(p.refBits - 1) && s.level >= p.treeLevels.U)
  io.req.valid := is(S.issue) && !outOfSteps && !tooDeep
  when(is(S.issue) && (outOfSteps || tooDeep)) { stepLimit := true.B; goto(S.done) } // the fetch is not made
  io.req.bits.tu := index
  io.req.bits.cref := cur
  io.req.bits.tmax := tmax
  io.req.bits.ray.foreach(_ := r.ray) // RAY_STORE=1: the IU's ray store has it, and r.ray is never read
  when(io.req.fire) {
    goto(Mux(cur(p.refBits - 1), S.waitTri, S.waitBox))
    stepsLeft := stepsLeft - 1.U; outOfSteps := limited && stepsLeft === 1.U
  }

  // Node: the hit children in the order of their ranks (the box pipe's: nearer first, an equal one in an earlier
  // slot first).
  when(is(S.waitBox) && boxIn.valid) {
    val b = boxIn.bits
    when(b.err) { readError := true.B } // b.hit is all false then: the ray pops on
    val ranks = b.rank
    for (j <- 0 until p.m) when(b.hit(j)) {
      sorted(ranks(j)).cref := b.cref(j); sorted(ranks(j)).t := b.tnear(j)
    }
    val k = PopCount(b.hit)
    // the first unfinished hit child: rank 0 with the full stack, rank trail(level) with the short one
    val skip = ss.fold(0.U)(_.skip)
    when(k <= skip) { goto(S.pop) } // no hit child left: this node is done
      .otherwise {
        cur := Mux1H(Seq.tabulate(p.m)(j => (b.hit(j) && ranks(j) === skip) -> b.cref(j))) // exactly one hit child has that rank
        ss.foreach(s => s.level := s.level + 1.U)
        pushIdx := k - 1.U; if (short) lastPush := skip + 1.U
        goto(Mux(k === skip + 1.U, S.issue, S.push))
      }
  }
  when(is(S.push)) { // far first: sorted(k-1) down to sorted(skip+1)
    ss match {
      case Some(s) => s.push(sorted(pushIdx).cref, sorted(pushIdx).t)
      case None =>
        when(stack.get.full) { overflow := true.B }
          .otherwise { stack.get.push(sorted(pushIdx)) }
    }
    pushIdx := pushIdx - 1.U
    when(pushIdx === lastPush) { goto(S.issue) }
  }

  // Leaf: results arrive in slot order; an earlier equal t is kept.
  // With PIPELINE a result is applied a cycle after it arrives, with its compare against tmax registered: the compare
  // then drives one flip-flop, not the enables of tmax and the best record (160 flip-flops; the path after the pop's
  // on the smallest platform, docs/timing.md). A result compares with the tmax the one before it leaves: that one's
  // t when it is taken, so back-to-back results keep the order's closest hit (a cycle more per leaf:
  // PlatformParams.tuLeafCycles).
  private val (triAt, takeAt) = p.stageBudget match {
    case None => (triIn, triIn.bits.hit && Fp.lt(f, triIn.bits.t, tmax))
    case Some(_) =>
      val b = Wire(Valid(new TriResult(p.pipes)))
      b.valid := RegNext(triIn.valid, false.B); b.bits := RegNext(triIn.bits)
      val take = Reg(Bool())
      take := triIn.bits.hit && Mux(b.valid && take, Fp.lt(f, triIn.bits.t, b.bits.t), Fp.lt(f, triIn.bits.t, tmax))
      (b, take)
  }
  when(is(S.waitTri) && triAt.valid) {
    val t = triAt.bits
    when(t.err) { readError := true.B }
    when(takeAt) {
      tmax := t.t; best.t := t.t; best.prim := t.prim; best.u := t.u; best.v := t.v
    }
    when(t.last) { goto(S.pop) }
  }

  // A pop loads `cur` whatever its entry's distance: an entry beyond tmax leaves the TU in the pop state, where `cur`
  // is not read, and the next pop or the end overwrites it. So the distance compare drives only the next state, not
  // the enable of 32 flip-flops (the smallest platform's routed critical path on ECP5 ended at `cur`, docs/timing.md)
  when(is(S.pop)) {
    ss match {
      case Some(s) =>
        when(!s.empty) {
          val top = s.pop()
          cur := top.cref
          when(!Fp.gt(f, top.t, tmax)) { goto(S.issue) }
        }.elsewhen(s.anyDropped && s.level =/= 0.U) { s.restart(); cur := 0.U; goto(S.issue) } // from the root again
          .otherwise { goto(S.done) } // nothing pending and nothing dropped, or the root itself is finished
      case None =>
        when(stack.get.empty) { goto(S.done) }
          .otherwise {
            val top = stack.get.pop()
            cur := top.cref
            when(!Fp.gt(f, top.t, tmax)) { goto(S.issue) }
          }
    }
  }

  io.result.valid := is(S.done)
  io.result.bits := best
  io.result.bits.overflow := overflow
  io.result.bits.readError := readError
  io.result.bits.stepLimit := stepLimit
  private def code(c: Int) = (c & 0xffffffffL).U(32.W)
  when(overflow || readError || stepLimit) { // read error, then step limit, then overflow, as in the model
    import rtaccel.scene.Hits
    io.result.bits.t := inf
    io.result.bits.prim := Mux(readError, code(Hits.ReadError), Mux(stepLimit, code(Hits.StepLimit), code(Hits.Overflow)))
    io.result.bits.u := 0.U; io.result.bits.v := 0.U
  }
  when(io.result.fire) { goto(S.idle) }
}

object TraversalUnit {
  /** A stack entry: a child reference and its entry distance (fp32); the cost model sizes the stacks by it. */
  val refBits: Int = 32
  val distBits: Int = 32
  val entryBits: Int = refBits + distBits
  /** Cycles after its handshake that a ray's bits are read (the TC drives them that late): 1 with PIPELINE. */
  def rayBitsLag(stageBudget: Option[Int]): Int = if (stageBudget.isDefined) 1 else 0
}
