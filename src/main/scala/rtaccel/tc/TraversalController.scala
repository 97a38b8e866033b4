package rtaccel.tc

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams
import rtaccel.fp.{FpDivPipe, FpFormat}
import rtaccel.tu.{TuRay, TuResult}

/** A ray from the host: id and the rays.npy row (ox, oy, oz, dx, dy, dz, tmin, tmax) as fp32 bits. */
class HostRay extends Bundle {
  val id = UInt(32.W)
  val f = Vec(8, UInt(32.W))
}

/** Traversal controller (paper Section 4): prepares each host ray (1/d of its three axes in turn on one pipelined
  * divider, so a ray every third cycle), hands it to the lowest-numbered free TU, and returns exactly one result per
  * ray.
  */
class TraversalController(p: PlatformParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Decoupled(new HostRay))
    val out = Decoupled(new TuResult)
    val tuRay = Vec(p.tus, Decoupled(new TuRay))
    val tuResult = Flipped(Vec(p.tus, Decoupled(new TuResult)))
  })
  private val f = FpFormat.fp32
  private val one = "h3f800000".U(32.W)

  // Ray preparation: one divider takes dx of a ray in the cycle the ray is accepted and dy, dz in the next two (a
  // divider per axis cost 2 x ~2,000 LUT4 and ~2,300 flip-flops more on ECP5, for a rate of a ray per cycle that
  // no configuration uses: a TU holds a ray for hundreds of cycles). The pipeline cannot stall, so a ray enters only
  // when the queue behind it has room for everything already in flight. `credits` is that room (the queue's size
  // less the rays in the divider and in the queue), kept in a register of its own so `ready` is a compare with zero:
  // summing the queue's count with an in-flight counter put an adder and a compare in front of every input's
  // handshake (the TC's routed critical path on ECP5).
  val div = Module(new FpDivPipe(f, p.divStages, p.stageBudget, p.pipes.lutInputs))
  /** Cycles from a ray's acceptance to its prepared copy (1/dz leaves the divider last). */
  val prepLatency: Int = TraversalController.prepLatency(div.latency)
  private val slots = prepLatency / TraversalController.axes + 2 // rays the divider can hold, and one waiting
  val prepared = Module(new Queue(new TuRay, slots))
  val credits = RegInit(slots.U(log2Ceil(slots + 1).W))
  val inAxis = RegInit(0.U(2.W)) // the axis the divider takes next: 0 = ready for a ray
  // `inIdle` is inAxis === 0 in a register of its own, for the handshake alone, and dy, dz are taken whenever the
  // divider is idle (they are read only after a ray was accepted, which is such a cycle): the acceptance then drives
  // two counters' next states, not 64 enables. The loop inAxis -> ready -> accept -> inAxis ran across the divider's
  // input multiplexers (7.7 ns of wire, the smallest platform's routed critical path on ECP5, docs/timing.md).
  val inIdle = RegInit(true.B)
  val heldD = Reg(Vec(2, UInt(32.W))) // dy, dz of the ray being fed
  io.in.ready := credits =/= 0.U && inIdle
  when(inAxis === 0.U) { heldD := VecInit(io.in.bits.f(4), io.in.bits.f(5)) }
  when(io.in.fire) { inAxis := 1.U; inIdle := false.B }
    .elsewhen(inAxis =/= 0.U) { inAxis := Mux(inAxis === 2.U, 0.U, inAxis + 1.U); inIdle := inAxis === 2.U }
  assert(inIdle === (inAxis === 0.U), "TC: inIdle out of step with the axis counter")
  div.io.in.valid := io.in.fire || inAxis =/= 0.U
  div.io.in.bits.a := one
  div.io.in.bits.b := Mux(inAxis === 0.U, io.in.bits.f(3), heldD(inAxis(1)))
  // the results leave in the same order, three per ray: the axis of each by a counter
  val outAxis = RegInit(0.U(2.W))
  val invXY = Reg(Vec(2, UInt(32.W)))
  when(div.io.out.valid) {
    outAxis := Mux(outAxis === 2.U, 0.U, outAxis + 1.U)
    when(outAxis =/= 2.U) { invXY(outAxis(0)) := div.io.out.bits }
  }
  val rayDelayed = p.pipe.chain(io.in.bits, prepLatency) // in LUT RAM where flip-flops are dear (fp.Stager.chain)
  val outValid = div.io.out.valid && outAxis === 2.U
  credits := credits - io.in.fire.asUInt + prepared.io.deq.fire.asUInt
  prepared.io.enq.valid := outValid
  prepared.io.enq.bits.id := rayDelayed.id
  for (a <- 0 until 3) {
    prepared.io.enq.bits.ray.o(a) := rayDelayed.f(a)
    prepared.io.enq.bits.ray.d(a) := rayDelayed.f(3 + a)
    prepared.io.enq.bits.ray.inv(a) := (if (a < 2) invXY(a) else div.io.out.bits)
  }
  prepared.io.enq.bits.ray.tmin := rayDelayed.f(6)
  prepared.io.enq.bits.tmax := rayDelayed.f(7)
  assert(!outValid || prepared.io.enq.ready, "ray preparation overran its queue")

  /** Cycles from a ray's acceptance to its offer to a free TU: the dividers, the ray queue and the dispatch register. */
  val dispatchLatency: Int = prepLatency + 1 + (if (p.stageBudget.isDefined) 1 else 0)
  // With PIPELINE the TUs' ready is seen two cycles late, less the TUs offered a ray since: a TU leaves idle only
  // by taking a ray, so one seen free is still free (asserted below). The TUs' ready is registered, and the choice
  // of the lowest such TU is made from registers and registered (choosing from registered values is the same), so
  // neither a TU's ready nor the 32-way choice runs into another unit's logic in the same cycle.
  /** Cycles late the TC sees a TU become free (0 or 2). */
  val readyLag: Int = if (p.stageBudget.isDefined) 2 else 0
  private val offered = Wire(Vec(p.tus, Bool()))
  private val rayOut = Wire(Decoupled(new TuRay))
  // one-hot, none when no TU is free: a TU is offered a ray only while it is free
  val target: Seq[Bool] =
    if (readyLag == 0) {
      rayOut <> prepared.io.deq
      PriorityEncoderOH(io.tuRay.map(_.ready))
    } else {
      val none = VecInit(Seq.fill(p.tus)(false.B))
      val wasReady = RegNext(VecInit(io.tuRay.map(_.ready)), none)
      val wasOffered = RegNext(offered, none)
      // free in the next cycle as seen: ready two cycles before it, offered no ray in either cycle since
      val freeNext = (0 until p.tus).map(i => wasReady(i) && !wasOffered(i) && !offered(i))
      // The dispatch register between the ray queue and the TUs. Whether a TU takes its ray in the next cycle is
      // known a cycle ahead (freeNext), so the register's load enable is itself a register: `load` = empty or
      // taken, as the next cycle will see them. Neither the 32-way OR of the choice (the TC's routed critical path
      // on ECP5, into a two-entry slice's enables) nor any other logic sits between a register and the enables
      // of the ray's 385 bits, and the queue's read pointer steps on a register too.
      val anyNext = freeNext.reduce(_ || _)
      val held = Reg(new TuRay)
      val heldValid = RegInit(false.B)
      val load = RegInit(true.B) // = !heldValid || (a TU takes `held` now), from registers of the cycle before
      prepared.io.deq.ready := load
      when(load) { held := prepared.io.deq.bits; heldValid := prepared.io.deq.valid }
      load := !(Mux(load, prepared.io.deq.valid, heldValid)) || anyNext
      rayOut.valid := heldValid
      rayOut.bits := held
      assert(load === (!heldValid || rayOut.ready), "TraversalController: the dispatch register's load disagrees with its handshake")
      RegNext(VecInit(TraversalController.lowest(freeNext)), none)
    }
  rayOut.ready := target.reduce(_ || _)
  /** Cycles after the handshake that the TUs read a ray's bits (TraversalUnit.rayBitsLag): with PIPELINE a TU takes
    * its ray from a register of its own, so the bits are held a cycle more here, once for all TUs.
    */
  val rayBitsLag: Int = rtaccel.tu.TraversalUnit.rayBitsLag(p.stageBudget)
  private val rayBits = if (rayBitsLag == 0) rayOut.bits else RegNext(rayOut.bits)
  for ((t, i) <- io.tuRay.zipWithIndex) {
    t.valid := rayOut.valid && target(i)
    offered(i) := t.valid
    t.bits := rayBits
    when(t.valid) { assert(t.ready, "TraversalController: a ray offered to a TU that is not free") }
  }

  // Results: round-robin over TUs, with host backpressure.
  val arb = Module(new rtaccel.arb.TreeArbiter(new TuResult, p.tus, rtaccel.arb.TreeArbiter.fanIn(p.stageBudget, p.tus), withChosen = false,
    heldInputs = p.stageBudget.isDefined, grantsEverywhere = p.stageBudget.isDefined)) // a TU holds its result until
  // taken, and a result comes every few hundred cycles per TU: registered grants at every level
  arb.io.in <> io.tuResult
  io.out <> arb.io.out
}

object TraversalController {
  /** Pipelined dividers of the ray preparation (the cost model counts them): one, shared by the axes. */
  val dividers: Int = 1
  /** Axes per ray: the divider takes one per cycle. */
  val axes: Int = 3
  /** The lowest set bit of xs, one-hot (none when none is set): each bit against an OR of the bits below it, which
    * synthesis builds as trees (a few levels for 32 TUs) where PriorityEncoderOH is a chain of muxes as long as xs
    * (the TC's routed critical path on ECP5).
    */
  def lowest(xs: Seq[Bool]): Seq[Bool] = xs.indices.map(i => if (i == 0) xs(0) else xs(i) && !VecInit(xs.take(i)).asUInt.orR)
  /** Cycles from a ray's acceptance to its prepared copy, for a divider of `divLatency` cycles. */
  def prepLatency(divLatency: Int): Int = divLatency + axes - 1
}
