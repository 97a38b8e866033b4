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

/** Traversal controller (paper Section 4): prepares each host ray (1/d with three pipelined dividers,
  * one ray per cycle), hands it to the lowest-numbered free TU, and returns exactly one result per ray.
  */
class TraversalController(p: PlatformParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Decoupled(new HostRay))
    val out = Decoupled(new TuResult)
    val tuRay = Vec(p.tus, Decoupled(new TuRay(p)))
    val tuResult = Flipped(Vec(p.tus, Decoupled(new TuResult)))
  })
  private val f = FpFormat.fp32
  private val one = "h3f800000".U(32.W)

  // Ray preparation: the pipeline cannot stall, so a ray enters only when the queue behind it has room
  // for everything already in flight. `credits` is that room (the queue's size less the rays in the dividers and
  // in the queue), kept in a register of its own so `ready` is a compare with zero: summing the queue's count with
  // an in-flight counter put an adder and a compare in front of every input's handshake (the TC's routed critical
  // path on ECP5).
  val divs = Seq.fill(TraversalController.dividers)(Module(new FpDivPipe(f, p.divStages, p.stageBudget)))
  private val lat = divs.head.latency
  val prepared = Module(new Queue(new TuRay(p), lat + 2))
  val credits = RegInit((lat + 2).U(log2Ceil(lat + 3).W))
  io.in.ready := credits =/= 0.U
  for (a <- 0 until 3) {
    divs(a).io.in.valid := io.in.fire
    divs(a).io.in.bits.a := one
    divs(a).io.in.bits.b := io.in.bits.f(3 + a)
  }
  val rayDelayed = p.pipe.chain(io.in.bits, lat) // in LUT RAM where flip-flops are dear (fp.Stager.chain)
  val outValid = divs.map(_.io.out.valid).reduce(_ && _) // the three run in lockstep
  credits := credits - io.in.fire.asUInt + prepared.io.deq.fire.asUInt
  prepared.io.enq.valid := outValid
  prepared.io.enq.bits.id := rayDelayed.id
  for (a <- 0 until 3) {
    prepared.io.enq.bits.ray.o(a) := rayDelayed.f(a)
    prepared.io.enq.bits.ray.d(a) := rayDelayed.f(3 + a)
    prepared.io.enq.bits.ray.inv(a) := divs(a).io.out.bits
  }
  prepared.io.enq.bits.ray.tmin := rayDelayed.f(6)
  prepared.io.enq.bits.tmax := rayDelayed.f(7)
  assert(!outValid || prepared.io.enq.ready, "ray preparation overran its queue")

  // Dispatch to the first free TU. With PIPELINE, a small queue between the ray queue and the TUs registers
  // the handshake: otherwise the TUs' ready, ORed over all of them, reaches the ray queue's read pointer and its
  // RAM's read address in the same cycle (the TC's routed critical path on ECP5 once the credits were in).
  private val ready = rtaccel.arb.Slice(p, prepared.io.deq)
  /** Cycles from a ray's acceptance to its offer to a free TU: the dividers, the ray queue and the dispatch queue. */
  val dispatchLatency: Int = lat + 1 + (if (p.stageBudget.isDefined) 1 else 0)
  // With PIPELINE the TUs' ready is seen two cycles late, less the TUs offered a ray since: a TU leaves idle only
  // by taking a ray, so one seen free is still free (asserted below). The TUs' ready is registered, and the choice
  // of the lowest such TU is made from registers and registered (choosing from registered values is the same), so
  // neither a TU's ready nor the 32-way choice runs into another unit's logic in the same cycle.
  /** Cycles late the TC sees a TU become free (0 or 2). */
  val readyLag: Int = if (p.stageBudget.isDefined) 2 else 0
  private val offered = Wire(Vec(p.tus, Bool()))
  // one-hot, none when no TU is free: a TU is offered a ray only while it is free
  val target: Seq[Bool] =
    if (readyLag == 0) PriorityEncoderOH(io.tuRay.map(_.ready))
    else {
      val none = VecInit(Seq.fill(p.tus)(false.B))
      val wasReady = RegNext(VecInit(io.tuRay.map(_.ready)), none)
      val wasOffered = RegNext(offered, none)
      // free in the next cycle as seen: ready two cycles before it, offered no ray in either cycle since
      val freeNext = (0 until p.tus).map(i => wasReady(i) && !wasOffered(i) && !offered(i))
      RegNext(VecInit(PriorityEncoderOH(freeNext)), none)
    }
  ready.ready := target.reduce(_ || _)
  for ((t, i) <- io.tuRay.zipWithIndex) {
    t.valid := ready.valid && target(i)
    offered(i) := t.valid
    t.bits := ready.bits
    when(t.valid) { assert(t.ready, "TraversalController: a ray offered to a TU that is not free") }
  }

  // Results: round-robin over TUs, with host backpressure.
  val arb = Module(new rtaccel.arb.TreeArbiter(new TuResult, p.tus, rtaccel.arb.TreeArbiter.fanIn(p.stageBudget, p.tus), withChosen = false))
  arb.io.in <> io.tuResult
  io.out <> arb.io.out
}

object TraversalController {
  /** 1/d per axis, one pipelined divider each (the cost model counts them). */
  val dividers: Int = 3
}
