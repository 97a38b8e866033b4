package rtaccel.tc

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.collection.mutable
import scala.util.Random
import rtaccel.TestScenes
import rtaccel.config.PlatformParams
import rtaccel.model.PreparedRay

object TraversalControllerSpec {
  final case class HostRay(id: Long, f: Array[Float])
  final case class Result(id: Long, t: Long, prim: Long, u: Long, v: Long, overflow: Boolean, readError: Boolean)
}

/** The traversal controller alone. The test plays the host (rays in, results out with backpressure) and the
  * TUs (each takes one ray, holds it a random time, offers a result until the TC takes it). Checked:
  * every prepared ray equals the host ray with inv = 1/d bit for bit as the reference model divides
  * (PreparedRay), rays are handed out in arrival order to the lowest-numbered free TU and never held while a
  * TU is free, and every TU result leaves exactly once, unchanged.
  */
class TraversalControllerSpec extends AnyFunSuite with ChiselScalatestTester {
  // Verilator: the three dividers run at ~35 cycles/s in treadle.
  private def folder(p: PlatformParams) = s"TraversalControllerSpec/tus${p.tus}-div${p.divStages}-pipe${p.pipelining.name}"
  /** The TC of `p` built by firtool (TestSim.firtool), one build per circuit shared by the tests that use it. */
  private type Dut = rtaccel.sim.FirtoolShell[Bundle { val in: chisel3.util.DecoupledIO[HostRay]; val out: chisel3.util.DecoupledIO[rtaccel.tu.TuResult]
    val tuRay: Vec[chisel3.util.DecoupledIO[rtaccel.tu.TuRay]]; val tuResult: Vec[chisel3.util.DecoupledIO[rtaccel.tu.TuResult]] }]
  private def tc(p: PlatformParams) = rtaccel.TestSim.firtool(folder(p))(new TraversalController(p))(_.io)
  /** The divider with `div` register levels where the stages spread them (PIPELINE=none). */
  private def fixed(tus: Int, div: Int) = PlatformParams(tus = tus, divStages = div, pipelining = rtaccel.config.Pipelining.Fixed)
  private def bits(f: Float): Long = java.lang.Float.floatToRawIntBits(f).toLong & 0xffffffffL
  private def float(b: Long): Float = java.lang.Float.intBitsToFloat(b.toInt)

  import TraversalControllerSpec._

  private val specials = Array(0f, -0f, Float.MinPositiveValue, -Float.MinPositiveValue, java.lang.Float.MIN_NORMAL,
    -java.lang.Float.MIN_NORMAL, Float.MaxValue, -Float.MaxValue, Float.PositiveInfinity, Float.NegativeInfinity, 1f, -1f,
    3f, 1e-38f, 2.5e38f, 0.1f, float(0x7f7ffffeL), float(0x00400000L), float(0x807fffffL))
  /** A direction component: special values, any non-NaN bit pattern, or an ordinary ray direction. */
  private def component(rnd: Random, ordinary: Float): Float = rnd.nextInt(6) match {
    case 0 => specials(rnd.nextInt(specials.length))
    case 1 => Iterator.continually(float(rnd.nextInt().toLong)).find(!_.isNaN).get
    case _ => ordinary
  }
  private def hostRays(seed: Long, n: Int): Seq[HostRay] = {
    val rnd = new Random(seed)
    val base = TestScenes.rays(seed, n)
    val ids = rnd.shuffle((0 until n).map(i => (i.toLong * 2654435761L + 12345) & 0xffffffffL))
    (0 until n).map { i =>
      val f = Array.tabulate(8)(k => base(i, k))
      for (k <- 3 until 6) f(k) = component(rnd, f(k))
      if (rnd.nextInt(4) == 0) { f(6) = rnd.nextFloat(); f(7) = f(6) + rnd.nextFloat() * 10 }
      HostRay(ids(i), f)
    }
  }

  private def pokeRay(dut: Dut, r: HostRay): Unit = {
    dut.io.in.bits.id.poke(r.id.U)
    for (k <- 0 until 8) dut.io.in.bits.f(k).poke(bits(r.f(k)).U)
  }

  /** The prepared ray on TU port i must be host ray r, with the model's reciprocals. */
  private def checkPrepared(dut: Dut, i: Int, r: HostRay, what: String): Unit = {
    val want = new PreparedRay(r.f(0), r.f(1), r.f(2), r.f(3), r.f(4), r.f(5), r.f(6), r.f(7))
    val t = dut.io.tuRay(i).bits
    def eq(got: BigInt, w: Long, name: String) =
      assert(got == BigInt(w), f"$what: $name = 0x$got%08x, want 0x$w%08x (ray ${r.f.mkString(",")})")
    eq(t.id.peek().litValue, r.id, "id")
    for (k <- 0 until 3) {
      eq(t.ray.o(k).peek().litValue, bits(r.f(k)), s"o$k")
      eq(t.ray.d(k).peek().litValue, bits(r.f(3 + k)), s"d$k")
    }
    eq(t.ray.inv(0).peek().litValue, bits(want.ix), "inv x")
    eq(t.ray.inv(1).peek().litValue, bits(want.iy), "inv y")
    eq(t.ray.inv(2).peek().litValue, bits(want.iz), "inv z")
    eq(t.ray.tmin.peek().litValue, bits(want.tmin), "tmin")
    eq(t.tmax.peek().litValue, bits(want.tmax), "tmax")
  }

  private def peekResult(b: rtaccel.tu.TuResult): Result = Result(b.id.peek().litValue.toLong, b.t.peek().litValue.toLong,
    b.prim.peek().litValue.toLong, b.u.peek().litValue.toLong, b.v.peek().litValue.toLong, b.overflow.peek().litToBoolean,
    b.readError.peek().litToBoolean)
  private def pokeResult(b: rtaccel.tu.TuResult, r: Result): Unit = {
    b.id.poke(r.id.U); b.t.poke(r.t.U); b.prim.poke(r.prim.U); b.u.poke(r.u.U); b.v.poke(r.v.U)
    b.overflow.poke(r.overflow.B); b.readError.poke(r.readError.B)
  }

  /** Random traffic: host rays with random gaps, TUs busy for random times, random backpressure on the
    * results. Returns the cycles taken.
    */
  private def randomRun(p: PlatformParams, n: Int, seed: Long): Long = {
    val rays = hostRays(seed, n)
    val rnd = new Random(seed * 7919 + 1)
    var cycles = 0L
    val built = tc(p)
    test(built.gen()).withAnnotations(built.annotations) { dut =>
      sealed trait TuState
      case class Free(from: Long) extends TuState
      case class Busy(r: HostRay, until: Long) extends TuState
      case class Done(res: Result) extends TuState
      val tus = Array.fill[TuState](p.tus)(Free(0))
      var next = 0 // next host ray to offer
      val accepted = mutable.Queue[(HostRay, Long)]() // accepted, not yet handed to a TU, with the cycle accepted
      val pendingOut = mutable.Map[Long, Result]()   // results offered by TUs, by id
      val inTree = mutable.Map[Long, Result]()       // results taken by a tree arbiter, not yet out
      val out = mutable.Set[Long]()
      var dispatched = 0
      var cycle = 0L
      dut.io.in.valid.poke(false.B); dut.io.out.ready.poke(false.B)
      // Every input is poked before any output is peeked, and only when it changes: each peek after a poke
      // re-evaluates the three dividers, which would dominate the run time.
      val lastReady = Array.fill(p.tus)(false); val lastValid = Array.fill(p.tus)(false)
      for (i <- 0 until p.tus) { dut.io.tuRay(i).ready.poke(false.B); dut.io.tuResult(i).valid.poke(false.B) }
      var lastOffer = false; var lastOutReady = false; var poked = -1
      // the TUs free as the TC sees them: this cycle's, or (PIPELINE) those free readyLag cycles ago and sent no ray
      // since (the last readyLag cycles' free TUs and rays sent, newest last)
      val lag = built.module.readyLag
      val pastFree = mutable.Queue.fill(lag)(Seq.empty[Int]); val pastFired = mutable.Queue.fill(lag)(Seq.empty[Int])
      // the ray a TU got, checked on its port rayBitsLag cycles after the handshake (0 or 1), when the TU reads it
      val bitsLag = built.module.rayBitsLag; var toCheck: Option[(Int, HostRay, String)] = None
      while (out.size < n) {
        assert(cycle < 200L * n + 1000, s"seed $seed: only ${out.size} of $n results after $cycle cycles")
        val what = s"seed $seed cycle $cycle"
        // host side
        val offer = next < n && rnd.nextInt(4) != 0
        if (offer != lastOffer) { dut.io.in.valid.poke(offer.B); lastOffer = offer }
        if (next < n && poked != next) { pokeRay(dut, rays(next)); poked = next }
        val outReady = rnd.nextInt(5) < 3
        if (outReady != lastOutReady) { dut.io.out.ready.poke(outReady.B); lastOutReady = outReady }
        // TU side
        val freeIdx = mutable.ArrayBuffer[Int]()
        for (i <- 0 until p.tus) {
          tus(i) match {
            case Busy(r, until) if cycle >= until =>
              val res = Result(r.id, rnd.nextInt().toLong & 0xffffffffL, rnd.nextInt().toLong & 0xffffffffL,
                rnd.nextInt().toLong & 0xffffffffL, rnd.nextInt().toLong & 0xffffffffL, rnd.nextBoolean(), rnd.nextInt(4) == 0)
              tus(i) = Done(res); pendingOut(res.id) = res
              pokeResult(dut.io.tuResult(i).bits, res)
            case _ =>
          }
          val free = tus(i) match { case Free(from) => cycle >= from; case _ => false }
          if (free) freeIdx += i
          if (free != lastReady(i)) { dut.io.tuRay(i).ready.poke(free.B); lastReady(i) = free }
          val v = tus(i).isInstanceOf[Done]
          if (v != lastValid(i)) { dut.io.tuResult(i).valid.poke(v.B); lastValid(i) = v }
        }
        toCheck.foreach { case (i, r, w) => checkPrepared(dut, i, r, w) }; toCheck = None
        // dispatch: at most one, to the lowest-numbered free TU, the oldest accepted ray
        val offered = (0 until p.tus).filter(i => dut.io.tuRay(i).valid.peek().litToBoolean)
        assert(offered.forall(freeIdx.contains), s"$what: a ray offered to TU ${offered.mkString(",")}, free are ${freeIdx.mkString(",")}")
        val fires = offered
        assert(fires.length <= 1, s"$what: rays handed to TUs ${fires.mkString(",")} at once")
        val seen = if (lag == 0) freeIdx.toSeq else pastFree.head.filterNot(i => pastFired.exists(_.contains(i)))
        if (lag > 0) { pastFree.dequeue(); pastFree.enqueue(freeIdx.toSeq); pastFired.dequeue(); pastFired.enqueue(fires) }
        val readyAt = accepted.headOption.map(_._2 + built.module.dispatchLatency)
        if (seen.nonEmpty && readyAt.exists(_ <= cycle))
          assert(fires.nonEmpty, s"$what: a prepared ray waits while TUs ${seen.mkString(",")} are free")
        for (i <- fires) {
          assert(i == seen.min, s"$what: ray to TU $i, but TU ${seen.min} is free")
          assert(accepted.nonEmpty, s"$what: TU $i got a ray that never came in")
          val (r, _) = accepted.dequeue()
          if (bitsLag == 0) checkPrepared(dut, i, r, s"$what TU $i") else toCheck = Some((i, r, s"$what TU $i, a cycle later"))
          tus(i) = Busy(r, cycle + 1 + (if (rnd.nextInt(3) == 0) rnd.nextInt(60) else rnd.nextInt(6)))
          dispatched += 1
        }
        // results: with one flat arbiter exactly one TU result is taken when one leaves, and it is the one that leaves;
        // with PIPELINE's tree (queues between its levels) a taken result leaves later, unchanged and exactly once
        val outValid = dut.io.out.valid.peek().litToBoolean
        val taken = (0 until p.tus).filter(i => lastValid(i) && dut.io.tuResult(i).ready.peek().litToBoolean)
        val flat = built.module.arb.depth == 0
        for (i <- taken if !flat) { tus(i) match { case Done(r) => inTree(r.id) = r; case _ => }
          tus(i) = Free(cycle + 1 + (if (rnd.nextInt(4) == 0) rnd.nextInt(3) else 0)) }
        if (outValid && outReady) {
          val got = peekResult(dut.io.out.bits)
          assert(!out.contains(got.id), s"$what: ray ${got.id} came out twice")
          if (flat) {
            assert(taken.length == 1, s"$what: a result left but TUs ${taken.mkString(",")} gave theirs")
            assert(pendingOut.get(got.id).contains(got), s"$what: result $got is not the one TU ${taken.head} offered")
            assert(tus(taken.head) == Done(got), s"$what: result of TU ${taken.head} expected")
            tus(taken.head) = Free(cycle + 1 + (if (rnd.nextInt(4) == 0) rnd.nextInt(3) else 0))
          } else {
            assert(inTree.get(got.id).contains(got), s"$what: result $got left but no TU gave it")
            inTree -= got.id
          }
          out += got.id; pendingOut -= got.id
        } else if (flat) assert(taken.isEmpty, s"$what: TU ${taken.mkString(",")} gave a result that did not leave")
        if (flat && pendingOut.nonEmpty) assert(outValid, s"$what: TU results wait but none is offered to the host")
        // host handshake
        if (offer && dut.io.in.ready.peek().litToBoolean) { accepted.enqueue((rays(next), cycle)); next += 1 }
        dut.clock.step(); cycle += 1
      }
      assert(next == n && dispatched == n && accepted.isEmpty && pendingOut.isEmpty && inTree.isEmpty)
      cycles = cycle
    }
    cycles
  }

  // divider stages as given (PIPELINE=none), and the registers PIPELINE=auto places
  for ((tus, div, n, seed) <- Seq((5, Some(6), 3000, 1L), (3, Some(0), 1500, 2L), (1, Some(2), 600, 3L), (5, None, 3000, 4L)))
    test(s"random rays and TUs: 1/d bit-exact, lowest free TU, each result out once (TUs=$tus, divider ${div.fold("PIPELINE=auto")(d => s"stages=$d")}, $n rays, seed $seed)") {
      val c = randomRun(div.fold(PlatformParams(tus = tus))(d => fixed(tus, d)), n, seed)
      info(s"$n rays in $c cycles")
    }

  test("reciprocals of every special direction component, bit-exact (all 19 specials on each axis)") {
    val p = fixed(5, 6)
    val built = tc(p)
    test(built.gen()).withAnnotations(built.annotations) { dut =>
      val rays = specials.indices.map { i =>
        HostRay(i.toLong, Array(1f, 2f, 3f, specials(i), specials((i + 7) % specials.length), specials((i + 13) % specials.length), 0f, 1f))
      }
      dut.io.out.ready.poke(false.B)
      for (i <- 0 until p.tus) { dut.io.tuRay(i).ready.poke((i == 1).B); dut.io.tuResult(i).valid.poke(false.B) }
      var got = 0; var next = 0; var cycle = 0
      while (got < rays.length) {
        assert(cycle < 500)
        dut.io.in.valid.poke((next < rays.length).B)
        if (next < rays.length) pokeRay(dut, rays(next))
        dut.io.tuRay(0).valid.expect(false.B, "TU 0 is not free")
        if (dut.io.tuRay(1).valid.peek().litToBoolean) { checkPrepared(dut, 1, rays(got), s"special ray $got"); got += 1 }
        if (next < rays.length && dut.io.in.ready.peek().litToBoolean) next += 1
        dut.clock.step(); cycle += 1
      }
    }
  }

  test("a ray every third cycle when TUs are free (one divider, three axes): no other stall, always to TU 0, in order") {
    val p = fixed(5, 6)
    val rays = hostRays(11, 64)
    // the divider has divStages cycles (PIPELINE=none), dz enters it two cycles after the ray, and the ray queue is a
    // cycle: a ray accepted at cycle 3k reaches TU 0 at 3k + divStages + 3
    val first = p.divStages + 3
    val built = tc(p)
    test(built.gen()).withAnnotations(built.annotations) { dut =>
      for (i <- 0 until p.tus) { dut.io.tuRay(i).ready.poke(true.B); dut.io.tuResult(i).valid.poke(false.B) }
      dut.io.out.ready.poke(true.B)
      var got = 0
      for (cycle <- 0 until 3 * rays.length + first + 1) {
        val k = cycle / 3
        val offering = k < rays.length
        dut.io.in.valid.poke(offering.B)
        if (offering) {
          pokeRay(dut, rays(k))
          dut.io.in.ready.expect((cycle % 3 == 0).B, s"cycle $cycle: the TC takes a ray at every third cycle and only then")
        }
        for (i <- 1 until p.tus) dut.io.tuRay(i).valid.expect(false.B)
        val out = cycle >= first && (cycle - first) % 3 == 0 && (cycle - first) / 3 < rays.length
        dut.io.tuRay(0).valid.expect(out.B, s"cycle $cycle: a ray at 3k + $first")
        if (out) { checkPrepared(dut, 0, rays(got), s"cycle $cycle"); got += 1 }
        dut.clock.step()
      }
      assert(got == rays.length)
    }
  }

  test("all TUs busy: the TC takes exactly as many rays as its queue holds, loses none, then hands them out in order") {
    val p = fixed(3, 0)
    val rays = hostRays(12, 40)
    val built = tc(p)
    test(built.gen()).withAnnotations(built.annotations) { dut =>
      for (i <- 0 until p.tus) { dut.io.tuRay(i).ready.poke(false.B); dut.io.tuResult(i).valid.poke(false.B) }
      dut.io.out.ready.poke(true.B)
      var next = 0
      for (_ <- 0 until 50) {
        dut.io.in.valid.poke(true.B); pokeRay(dut, rays(next))
        if (dut.io.in.ready.peek().litToBoolean) next += 1
        dut.clock.step()
      }
      // the queue holds the rays the divider can hold at a ray every third cycle and one more: (divStages + 2) / 3 + 2
      val slots = (p.divStages + 2) / 3 + 2
      assert(next == slots, s"took $next rays with every TU busy, want the queue's $slots")
      // free TU 2 only, then TU 1 too: lowest free first
      var got = 0
      dut.io.tuRay(2).ready.poke(true.B)
      for (cycle <- 0 until 200 if got < rays.length) {
        if (cycle == 5) dut.io.tuRay(1).ready.poke(true.B)
        dut.io.in.valid.poke((next < rays.length).B)
        if (next < rays.length) pokeRay(dut, rays(next))
        val v = (0 until p.tus).filter(i => dut.io.tuRay(i).valid.peek().litToBoolean)
        val target = if (cycle < 5) 2 else 1
        dut.io.tuRay(0).valid.expect(false.B)
        if (v.contains(target)) { checkPrepared(dut, target, rays(got), s"cycle $cycle"); got += 1 }
        if (next < rays.length && dut.io.in.ready.peek().litToBoolean) next += 1
        dut.clock.step()
      }
      assert(got == rays.length)
    }
  }
}
