package rtaccel.tu

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.collection.mutable
import scala.util.Random
import rtaccel.TestScenes
import rtaccel.bvh.{Mbvh, MemoryImage, RefCodec}
import rtaccel.config.{Fit, PlatformParams}
import rtaccel.model.{AccessSink, MemFaults, PreparedRay, RayBox, RayStats, RayTriangle, Traversal}
import rtaccel.scene.{Hits, Rays, Scene}

object TraversalUnitSpec {
  /** One fetch: kind 0 = node (id), 1 = leaf (first primitive slot, count). */
  final case class Access(kind: Int, id: Int, count: Int) {
    override def toString: String = if (kind == 0) s"node $id" else s"leaf $id+$count"
  }
  /** A hit record as raw bits. */
  final case class Record(id: Long, t: Int, prim: Int, u: Int, v: Int, overflow: Boolean, readError: Boolean, stepLimit: Boolean = false) {
    override def toString: String =
      f"id $id t 0x$t%08x (${java.lang.Float.intBitsToFloat(t)}) prim $prim u 0x$u%08x v 0x$v%08x overflow $overflow readError $readError stepLimit $stepLimit"
  }
  final case class Run(accesses: IndexedSeq[Seq[Access]], records: IndexedSeq[Record], cycles: Long)
  final case class BoxAns(hit: Seq[Boolean], tnear: Seq[Int], cref: Seq[Int], err: Boolean)
  final case class TriAns(hit: Boolean, t: Int, u: Int, v: Int, prim: Int, last: Boolean, err: Boolean)
}

/** The traversal unit alone. The test plays the IU: it takes the TU's requests (random ready), answers a node
  * with the box results and a leaf with one triangle result per primitive, computed from the packed memory
  * image with the reference model's single-box and single-triangle tests (RayBox / RayTriangle) at the
  * request's tmax, after random latencies; results for other TUs are broadcast in between and must be
  * ignored; non-hit lanes carry garbage. The TU's order of requested references and its final hit record are
  * compared bit for bit with the reference traversal (rtaccel.model.Traversal, order recorded by an
  * AccessSink) on the same image.
  */
class TraversalUnitSpec extends AnyFunSuite with ChiselScalatestTester {
  import TraversalUnitSpec._
  private def fbits(f: Float): Int = java.lang.Float.floatToRawIntBits(f)
  private def u32(i: Int): BigInt = BigInt(i & 0xffffffffL)
  private val Inf = Float.PositiveInfinity

  // ---------------------------------------------------------------- reference side

  private def model(img: MemoryImage, faults: MemFaults, rays: Rays, ids: IndexedSeq[Long]): Run = {
    val trav = new Traversal(img, faults)
    val hits = Hits.empty(rays.count)
    val acc = IndexedSeq.fill(rays.count)(mutable.ArrayBuffer[Access]())
    val sink = new AccessSink {
      def node(ray: Int, id: Int, level: Int): Unit = acc(ray) += Access(0, id, 0)
      def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = acc(ray) += Access(1, firstPrim, count)
    }
    val recs = (0 until rays.count).map { i =>
      val st = new RayStats
      trav.trace(i, rays, hits, sink, st)
      Record(ids(i), fbits(hits.t(i)), hits.prim(i), fbits(hits.u(i)), fbits(hits.v(i)), st.overflows > 0, st.readErrors > 0, st.stepLimits > 0)
    }
    Run(acc.map(_.toSeq), recs, 0)
  }

  // ---------------------------------------------------------------- the TU with the test playing the IU

  // Verilator: the TU's float comparators (its tmax culls) are slow in treadle. One build per circuit (the TU
  // depends on M, the stack depth and the reference layout; TestSim.firtool), shared by the tests that use it.
  private def folder(p: PlatformParams) = {
    val r = p.refs
    s"TraversalUnitSpec/m${p.m}-stack${p.stackDepth}-refs${r.nodeIdBits}.${r.primIndexBits}.${r.countBits}.${r.levelBits}-tus${p.tus}-short${p.shortStack}.${p.treeLevels}"
  }

  /** Runs the rays through one TU (its index port = `index`). nodeBad / primBad: the node ids and primitive
    * slots whose results the IU flags err (no child hit / not hit), as it does for a memory read error.
    */
  private def rtl(p: PlatformParams, img: MemoryImage, rays: Rays, ids: IndexedSeq[Long], seed: Long, index: Int,
                  nodeBad: Int => Boolean = _ => false, primBad: Int => Boolean = _ => false): Run = {
    require(p.tus >= 2 && index < p.tus)
    val rnd = new Random(seed)
    val codec = new RefCodec(p.refs)
    val m = p.m
    val acc = IndexedSeq.fill(rays.count)(mutable.ArrayBuffer[Access]())
    val recs = mutable.ArrayBuffer[Record]()
    var cycle = 0L
    def garbage(): Int = rnd.nextInt()
    def fail(what: String): Nothing = throw new AssertionError(s"$what (seed $seed, cycle $cycle, ray ${recs.length})")
    val tu = rtaccel.TestSim.firtool(folder(p))(new TraversalUnit(p.traversal))(_.io)
    test(tu.gen()).withAnnotations(tu.annotations) { dut =>
      dut.clock.setTimeout(0)
      dut.io.index.poke(index.U)
      dut.io.maxSteps.poke(p.stepLimit.U) // the MAX_STEPS register's value after reset
      dut.io.ray.valid.poke(false.B); dut.io.req.ready.poke(false.B); dut.io.result.ready.poke(false.B)
      dut.io.box.valid.poke(false.B); dut.io.tri.valid.poke(false.B)
      var lastReqReady = false; var lastResReady = false; var boxValid = false; var triValid = false
      def pokeBox(tu: Int, a: BoxAns): Unit = {
        val b = dut.io.box.bits
        b.tu.poke(tu.U); b.err.poke(a.err.B)
        for (j <- 0 until m) { b.hit(j).poke(a.hit(j).B); b.tnear(j).poke(u32(a.tnear(j)).U); b.cref(j).poke(u32(a.cref(j)).U) }
        // the ranks the box pipe gives: hit children nearer, or as near in an earlier slot (IEEE compare); garbage
        // for the others
        val near = a.tnear.map(java.lang.Float.intBitsToFloat)
        for (j <- 0 until m) b.rank(j).poke((if (!a.hit(j)) garbage() & (m - 1) else
          (0 until m).count(i => i != j && a.hit(i) && (near(i) < near(j) || (near(i) == near(j) && i < j)))).U)
      }
      def pokeTri(tu: Int, a: TriAns): Unit = {
        val b = dut.io.tri.bits
        b.tu.poke(tu.U); b.hit.poke(a.hit.B); b.t.poke(u32(a.t).U); b.u.poke(u32(a.u).U); b.v.poke(u32(a.v).U)
        b.prim.poke(u32(a.prim).U); b.last.poke(a.last.B); b.err.poke(a.err.B)
      }
      def foreign(): Int = (index + 1 + rnd.nextInt(p.tus - 1)) % p.tus

      var i = 0
      var rayValid = false; var offering = false; var running = false; var gapUntil = 0L
      // The ray port's bits are the ray only in the cycle the TU reads them (rayBitsLag cycles after the handshake:
      // the ray from the first offer on with 0; with 1, the ray in the cycle after the handshake) and garbage else.
      val bitsLag = TraversalUnit.rayBitsLag(p.stageBudget); var realAt = -1L; var scrambleAt = -1L
      def pokeRay(ray: Option[PreparedRay]): Unit = {
        val b = dut.io.ray.bits
        val g = () => u32(garbage())
        def put(x: UInt, v: PreparedRay => Float): Unit = x.poke(ray.fold(g())(q => u32(fbits(v(q)))).U)
        b.id.poke(ray.fold(g())(_ => BigInt(ids(i))).U)
        for (k <- 0 until 3) {
          put(b.ray.o(k), q => Seq(q.ox, q.oy, q.oz)(k)); put(b.ray.d(k), q => Seq(q.dx, q.dy, q.dz)(k))
          put(b.ray.inv(k), q => Seq(q.ix, q.iy, q.iz)(k))
        }
        put(b.ray.tmin, _.tmin); put(b.tmax, _.tmax)
      }
      var r: PreparedRay = null
      var curTmax = 0f // the TU's tmax as the IU sees it: the ray's tmax, lowered by every hit the TU takes
      val schedule = mutable.Queue[(Long, Either[BoxAns, TriAns])]()
      var waiting = false // a request is outstanding
      var rayCycles = 0L
      while (i < rays.count) {
        // ---- drive
        if (!offering && rayValid) { dut.io.ray.valid.poke(false.B); rayValid = false } // taken in the last cycle
        if (cycle == realAt) pokeRay(Some(r))
        if (cycle == scrambleAt) pokeRay(None)
        if (!running && !offering && cycle >= gapUntil) {
          r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
          pokeRay(if (bitsLag == 0) Some(r) else None)
          dut.io.ray.valid.poke(true.B)
          rayValid = true; offering = true; curTmax = r.tmax; rayCycles = 0
        }
        val reqReady = rnd.nextInt(4) != 0
        if (reqReady != lastReqReady) { dut.io.req.ready.poke(reqReady.B); lastReqReady = reqReady }
        val resReady = rnd.nextInt(3) != 0
        if (resReady != lastResReady) { dut.io.result.ready.poke(resReady.B); lastResReady = resReady }
        // results: this TU's when due, else now and then another TU's
        var bv = false; var tv = false
        if (schedule.headOption.exists(_._1 <= cycle)) {
          schedule.dequeue()._2 match {
            case Left(a) => pokeBox(index, a); bv = true
            case Right(a) =>
              pokeTri(index, a); tv = true
              val t = java.lang.Float.intBitsToFloat(a.t)
              if (a.hit && t < curTmax) curTmax = t
          }
          if (schedule.isEmpty) waiting = false
        }
        if (!bv && rnd.nextInt(6) == 0) {
          pokeBox(foreign(), BoxAns(Seq.fill(m)(rnd.nextBoolean()), Seq.fill(m)(garbage()), Seq.fill(m)(garbage()), rnd.nextInt(4) == 0)); bv = true
        }
        if (!tv && rnd.nextInt(6) == 0) {
          pokeTri(foreign(), TriAns(rnd.nextBoolean(), fbits(rnd.nextFloat()), garbage(), garbage(), garbage(), rnd.nextBoolean(), rnd.nextInt(4) == 0)); tv = true
        }
        if (bv != boxValid) { dut.io.box.valid.poke(bv.B); boxValid = bv }
        if (tv != triValid) { dut.io.tri.valid.poke(tv.B); triValid = tv }

        // ---- observe
        if (dut.io.busy.peek().litToBoolean != running) fail(s"busy should be $running")
        val rayReady = dut.io.ray.ready.peek().litToBoolean
        if (rayReady == running) fail(s"ray.ready $rayReady while ${if (running) "busy" else "idle"}")
        val wasRunning = running
        if (offering && rayReady) { offering = false; running = true; if (bitsLag > 0) realAt = cycle + 1; scrambleAt = cycle + 1 + bitsLag }
        if (dut.io.req.valid.peek().litToBoolean) {
          if (!wasRunning || waiting) fail("a request while " + (if (waiting) "one is outstanding" else "idle"))
          if (reqReady) {
            val q = dut.io.req.bits
            if (q.tu.peek().litValue != index) fail(s"request tagged TU ${q.tu.peek().litValue}")
            val want = Seq(r.ox, r.oy, r.oz, r.dx, r.dy, r.dz, r.ix, r.iy, r.iz, r.tmin).map(x => u32(fbits(x)))
            val got = (0 until 3).map(k => q.ray.get.o(k).peek().litValue) ++ (0 until 3).map(k => q.ray.get.d(k).peek().litValue) ++
              (0 until 3).map(k => q.ray.get.inv(k).peek().litValue) :+ q.ray.get.tmin.peek().litValue
            if (got != want) fail(s"request carries ray $got, want $want")
            val tmaxBits = q.tmax.peek().litValue.toInt
            if (tmaxBits != fbits(curTmax)) fail(f"request tmax 0x$tmaxBits%08x, want 0x${fbits(curTmax)}%08x (ray tmax or closest hit so far)")
            val tmax = java.lang.Float.intBitsToFloat(tmaxBits)
            val cref = q.cref.peek().litValue.toInt
            val lat = 1 + (if (rnd.nextInt(4) == 0) rnd.nextInt(30) else rnd.nextInt(6))
            if (!codec.isPrim(cref)) {
              val id = codec.nodeId(cref)
              if (id >= img.numNodes) fail(s"request for node $id of ${img.numNodes}")
              acc(i) += Access(0, id, 0)
              val ans = if (nodeBad(id)) BoxAns(Seq.fill(m)(false), Seq.fill(m)(garbage()), Seq.fill(m)(garbage()), err = true)
              else {
                val res = (0 until m).map { j =>
                  val ref = img.childRef(id, j)
                  def w(k: Int) = java.lang.Float.intBitsToFloat(img.childWord(id, j, k))
                  val tn = if (ref == 0) Float.NaN else RayBox.test(r, tmax, w(0), w(1), w(2), w(3), w(4), w(5))
                  (!tn.isNaN, if (tn.isNaN) garbage() else fbits(tn), ref)
                }
                BoxAns(res.map(_._1), res.map(_._2), res.map(_._3), err = false)
              }
              schedule.enqueue((cycle + lat, Left(ans)))
            } else {
              val first = codec.firstPrim(cref); val n = codec.count(cref)
              if (first + n > img.numPrims) fail(s"request for primitives $first+$n of ${img.numPrims}")
              acc(i) += Access(1, first, n)
              var at = cycle + lat
              for (s <- first until first + n) {
                val o = new RayTriangle.Result
                val ans = if (primBad(s)) TriAns(hit = false, garbage(), garbage(), garbage(), garbage(), s == first + n - 1, err = true)
                else if (RayTriangle.test(r, tmax, k => img.primCoord(s, k), o))
                  TriAns(hit = true, fbits(o.t), fbits(o.u), fbits(o.v), img.primId(s), s == first + n - 1, err = false)
                else TriAns(hit = false, garbage(), garbage(), garbage(), img.primId(s), s == first + n - 1, err = false)
                schedule.enqueue((at, Right(ans)))
                at += 1 + (if (rnd.nextInt(3) == 0) rnd.nextInt(4) else 0)
              }
            }
            waiting = true
          }
        }
        if (dut.io.result.valid.peek().litToBoolean) {
          if (!wasRunning || waiting || schedule.nonEmpty) fail("a result before the traversal ended")
          if (resReady) {
            val b = dut.io.result.bits
            recs += Record(b.id.peek().litValue.toLong, b.t.peek().litValue.toInt, b.prim.peek().litValue.toInt,
              b.u.peek().litValue.toInt, b.v.peek().litValue.toInt, b.overflow.peek().litToBoolean, b.readError.peek().litToBoolean,
              b.stepLimit.peek().litToBoolean)
            running = false; i += 1
            gapUntil = cycle + 1 + (if (rnd.nextBoolean()) 0 else rnd.nextInt(4))
          }
        }
        dut.clock.step(); cycle += 1; rayCycles += 1
        if (rayCycles > 100000) fail("the ray never finished")
      }
    }
    Run(acc.map(_.toSeq), recs.toIndexedSeq, cycle)
  }

  /** RTL == model for every ray: same fetches in the same order, same record bit for bit. */
  private def compare(what: String, seed: Long, got: Run, want: Run, rays: Rays): Unit = {
    assert(got.records.length == want.records.length)
    for (i <- want.records.indices) {
      def ray = (0 until 8).map(rays(i, _)).mkString("(", ", ", ")")
      assert(got.accesses(i) == want.accesses(i),
        s"$what ray $i $ray (seed $seed): TU fetched ${got.accesses(i).mkString(", ")}\n  model fetched ${want.accesses(i).mkString(", ")}")
      assert(got.records(i) == want.records(i), s"$what ray $i $ray (seed $seed): TU record ${got.records(i)}\n  model record ${want.records(i)}")
    }
  }

  private def ids(n: Int, seed: Long): IndexedSeq[Long] = {
    val rnd = new Random(seed); IndexedSeq.fill(n)(rnd.nextInt().toLong & 0xffffffffL)
  }

  /** Soup rays plus some with a tmin > 0 or a finite tmax. */
  private def soupRays(seed: Long, n: Int): Rays = {
    val rnd = new Random(seed)
    val d = TestScenes.rays(seed, n).data.clone()
    for (i <- 0 until n) rnd.nextInt(5) match {
      case 0 => d(8 * i + 7) = rnd.nextFloat() * 1.5f
      case 1 => d(8 * i + 6) = rnd.nextFloat() * 0.5f; d(8 * i + 7) = d(8 * i + 6) + rnd.nextFloat()
      case _ =>
    }
    Rays(d)
  }

  /** A soup of overlapping triangles; the paper's fixed 32-bit reference layout and a 32-entry stack (so
    * that few TU circuits serve every test), or with `fit` the fields and the stack fitted to the tree.
    */
  private def soupImage(seed: Long, tris: Int, p0: PlatformParams, stack: Option[Int] = None, fit: Boolean = false): MemoryImage = {
    val s = TestScenes.soup(seed, tris, size = 3f)
    val bvh = Mbvh.build(s, p0)
    val need = Fit.needs(bvh).stackDepth
    val p = if (fit) Fit.fitTo(p0, bvh) else { require(need <= 32, s"the soup tree needs a $need-entry stack"); p0.copy(stackDepth = 32) }
    MemoryImage.pack(bvh, s, stack.fold(p)(d => p.copy(stackDepth = d)))
  }

  // ---------------------------------------------------------------- random soups

  // make regress adds M=2 (PlatformSpec's 4-TU case runs M=2 in make test) and three more short-stack rings
  for ((m, mppl, n, seed, fit) <- Seq((4, 4, 400, 1L, false), (8, 8, 300, 3L, false), (4, 2, 400, 4L, true)) ++
      (if (rtaccel.Regress.full) Seq((2, 1, 300, 2L, false)) else Nil))
    test(s"random soup, M=$m MPPL=$mppl${if (fit) ", fitted reference fields and stack" else ""}: fetch order and hit records equal the model bit for bit ($n rays, seed $seed)") {
      val img = soupImage(seed, 200, PlatformParams(tus = 4, m = m, mppl = mppl), fit = fit)
      if (fit) assert(img.p.refs.refBits < 32, "a fitted layout has its leaf flag below bit 31")
      val rays = soupRays(seed + 10, n); val id = ids(n, seed)
      val want = model(img, MemFaults.none, rays, id)
      val got = rtl(img.p, img, rays, id, seed, index = (seed % 4).toInt)
      compare(s"M=$m", seed, got, want, rays)
      val hits = want.records.count(_.prim >= 0)
      info(s"$n rays, ${want.accesses.map(_.length).sum} fetches, $hits hits, ${got.cycles} cycles")
      assert(hits > n / 5 && hits < n, "the soup rays must both hit and miss")
      assert(want.records.forall(r => !r.overflow && !r.readError), "a fitted stack never overflows")
      assert(want.records.forall(!_.stepLimit), s"the default step limit (${img.p.stepLimit}) flags no ray of an uncorrupted image")
    }

  test("a stack of depth 2 overflows: record prim -3, t = +inf, u = v = 0, overflow flag, same fetches as the model") {
    val seed = 5L; val n = 300
    val img = soupImage(seed, 200, PlatformParams(tus = 4, m = 8, mppl = 1), stack = Some(2))
    assert(img.p.stackDepth == 2)
    val rays = soupRays(seed + 10, n); val id = ids(n, seed)
    val want = model(img, MemFaults.none, rays, id)
    val got = rtl(img.p, img, rays, id, seed, index = 3)
    compare("stack 2", seed, got, want, rays)
    val over = want.records.filter(_.overflow)
    info(s"${over.length} of $n rays overflowed")
    assert(over.nonEmpty && over.length < n, "some rays must overflow, not all")
    assert(over.forall(r => r.prim == Hits.Overflow && r.prim == -3 && r.t == fbits(Inf) && r.u == 0 && r.v == 0 && !r.readError))
  }

  // Short stack with restart: the same fetches (restart revisits included) and records as model.traceShort,
  // which TraversalSpec holds bit-identical to the full stack.
  for ((m, mppl, ring, seed) <- Seq((4, 4, 1, 7L)) ++ (if (rtaccel.Regress.full) Seq((4, 2, 2, 8L), (8, 1, 3, 9L), (2, 1, 4, 10L)) else Nil))
    test(s"short stack with restart, M=$m MPPL=$mppl ring $ring: fetches and records equal the model, restarts included") {
      val n = 250
      val img0 = soupImage(seed, 300, PlatformParams(tus = 4, m = m, mppl = mppl), fit = true)
      val img = img0.copy(p = img0.p.copy(shortStack = ring))
      val rays = soupRays(seed + 10, n); val id = ids(n, seed)
      val want = model(img, MemFaults.none, rays, id)
      val got = rtl(img.p, img, rays, id, seed, index = 2)
      compare(s"ring $ring", seed, got, want, rays)
      val full = model(img0, MemFaults.none, rays, id)
      assert(want.records == full.records, "the short stack's records must equal the full stack's")
      val extra = want.accesses.map(_.length).sum - full.accesses.map(_.length).sum
      info(s"$n rays, ${full.accesses.map(_.length).sum} fetches with the full stack, $extra more after restarts, ${got.cycles} cycles")
      assert(extra > 0, s"a ring of $ring entries on this soup must restart")
      assert(want.records.forall(!_.overflow))
    }

  test("memory read errors (poisoned nodes and primitives, MemFaults): records and fetches equal the model's with the same faults") {
    val seed = 6L; val n = 300
    val img0 = soupImage(seed, 200, PlatformParams(tus = 4, m = 4, mppl = 4))
    val primBase = 4096L * ((img0.numNodes.toLong * img0.p.nodeStrideBytes + 4095) / 4096)
    // a fault seed that spares the root (a poisoned root fails every ray) and poisons something
    val faults = (1 to 1000).iterator.map(s => MemFaults(MemFaults.threshold(0.003), s, 32, img0.p.nodeStrideBytes, primBase, 64))
      .find(f => !f.nodeBad(0) && (0 until img0.numNodes).exists(f.nodeBad) && (0 until img0.numPrims).exists(f.primBad)).get
    for ((stack, ring, what) <- Seq((img0.p.stackDepth, 0, "32-entry stack"), (2, 0, "stack 2: overflow and read error together"),
        (img0.p.stackDepth, 2, "short stack of 2 with restart"))) {
      val img = img0.copy(p = img0.p.copy(stackDepth = stack, shortStack = ring))
      val rays = soupRays(seed + 10, n); val id = ids(n, seed)
      val want = model(img, faults, rays, id)
      val got = rtl(img.p, img, rays, id, seed + stack + ring, index = 1, faults.nodeBad, faults.primBad)
      compare(what, seed, got, want, rays)
      val bad = want.records.filter(_.readError)
      info(s"$what: ${bad.length} of $n rays read a poisoned node or primitive (fault seed ${faults.seed})")
      assert(bad.nonEmpty && bad.length < n, "some rays must read an error, not all")
      assert(bad.forall(r => r.prim == Hits.ReadError && r.prim == -2 && r.t == fbits(Inf) && r.u == 0 && r.v == 0))
      if (stack == 2) assert(want.records.exists(r => r.readError && r.overflow), "a ray with both flags: the read error wins")
    }
  }

  // ---------------------------------------------------------------- directed cases on hand-made images

  private val hp = PlatformParams(tus = 4, m = 4, mppl = 4, stackDepth = 32)
  private val hc = new RefCodec(hp.refs)
  /** A leaf box along the x axis from a to b (the rays below run along +x at y = z = 0.25). */
  private def xbox(a: Float, b: Float): Array[Float] = Array(a, -1f, -1f, b, 2f, 2f)
  /** A triangle in the plane x = c that the axis rays hit (at t = c) or, off = true, miss. */
  private def xtri(c: Float, off: Boolean = false): Array[Float] = {
    val y = if (off) 10f else 0f
    Array(c, -1f + y, -1f, c, 2f + y, -1f, c, -1f + y, 2f)
  }
  private def image(p: PlatformParams, nodes: Seq[Seq[(Array[Float], Int)]], tris: Seq[Array[Float]]): MemoryImage = {
    val nw = p.nodeStrideBytes / 4; val pw = p.primStrideBytes / 4
    val na = new Array[Int](nodes.length * nw)
    for ((ch, n) <- nodes.zipWithIndex; ((box, ref), j) <- ch.zipWithIndex) {
      for (k <- 0 until 6) na(n * nw + 7 * j + k) = fbits(box(k))
      na(n * nw + 7 * j + 6) = ref
    }
    val pa = new Array[Int](tris.length * pw)
    for ((t, s) <- tris.zipWithIndex) { for (k <- 0 until 9) pa(s * pw + k) = fbits(t(k)); pa(s * pw + 9) = 100 + s }
    MemoryImage(p, na, pa)
  }
  private def axisRay(tmin: Float = 0f, tmax: Float = Inf): Array[Float] = Array(0f, 0.25f, 0.25f, 1f, 0f, 0f, tmin, tmax)
  private def leaf(s: Int) = Access(1, s, 1)
  private val root = Access(0, 0, 0)

  /** Runs the rays on the image through model and TU; returns the model's run (equal to the TU's). */
  private def directed(what: String, img: MemoryImage, rayRows: Seq[Array[Float]], seed: Long,
                       nodeBad: Int => Boolean = _ => false, primBad: Int => Boolean = _ => false,
                       check: Boolean = true): (Run, Run) = {
    val rays = Rays(rayRows.flatten.toArray); val id = ids(rays.count, seed)
    val got = rtl(img.p, img, rays, id, seed, index = 2, nodeBad, primBad)
    val want = model(img, MemFaults.none, rays, id)
    if (check) compare(what, seed, got, want, rays)
    (got, want)
  }

  test("a ray that misses the root: one fetch, the miss record (prim -1, t = +inf, u = v = 0)") {
    val img = soupImage(7, 100, PlatformParams(tus = 4, m = 4, mppl = 4))
    val away = Seq(Array(-5f, -5f, -5f, -1f, -1f, -1f, 0f, Inf), Array(20f, 5f, 5f, 1f, 0.01f, 0f, 0f, Inf),
      Array(-5f, 5f, 5f, 1f, 0f, 0f, 0f, 1f)) // towards the soup, but tmax ends before it
    val (got, _) = directed("miss", img, away, 7)
    for (i <- away.indices) {
      assert(got.accesses(i) == Seq(root))
      assert(got.records(i).prim == -1 && got.records(i).t == fbits(Inf) && got.records(i).u == 0 && got.records(i).v == 0)
    }
  }

  test("a leaf-only tree (root with one leaf child): root, then the leaf; hit and miss") {
    // built by the tree builder from one triangle
    val seed = 9L
    val one = TestScenes.soup(seed, 1)
    val p0 = PlatformParams(tus = 4, m = 4, mppl = 4)
    val bvh = Mbvh.build(one, p0)
    assert(bvh.numNodes == 1 && bvh.nodes(0).children.length == 1 && bvh.nodes(0).children(0).isLeaf, "one leaf under the root")
    val img = MemoryImage.pack(bvh, one, p0.copy(stackDepth = 32))
    val c = (0 until 3).map(k => (0 until 3).map(v => one.v(0, v, k)).sum / 3)
    val rows = Seq(Array(-5f, -5f, -5f, -1f, -1f, -1f, 0f, Inf), Array(c(0) - 5f, c(1) - 4f, c(2) - 3f, 5f, 4f, 3f, 0f, Inf)) ++
      TestScenes.rays(seed, 30).data.grouped(8).toSeq
    val (_, w) = directed("leaf-only", img, rows, seed)
    assert(w.accesses.forall(a => a == Seq(root) || a == Seq(root, Access(1, 0, 1))))
    assert(w.accesses(0) == Seq(root) && w.records(0).prim == -1)
    assert(w.accesses(1) == Seq(root, Access(1, 0, 1)) && w.records(1).prim == 0, "the ray at the centroid hits")
    // a hand-made root whose only child is a leaf of three primitives
    val three = image(hp, Seq(Seq((xbox(1, 9), hc.leaf(0, 3)))), Seq(xtri(4f), xtri(2f, off = true), xtri(3f)))
    val (_, w3) = directed("leaf of 3", three, Seq(axisRay(), axisRay(tmin = 3.5f), Array(0f, 5f, 0.25f, 1f, 0f, 0f, 0f, Inf)), seed + 1)
    assert(w3.accesses.take(2).forall(_ == Seq(root, Access(1, 0, 3))) && w3.records(0).prim == 102 && w3.records(1).prim == 100)
    assert(w3.accesses(2) == Seq(root) && w3.records(2).prim == -1, "outside the box")
  }

  test("equal entry distances keep slot order (stable), nearer ones first, pushed far-first") {
    val same = image(hp, Seq((0 until 4).map(j => (xbox(1, 2), hc.leaf(j, 1)))), (0 until 4).map(_ => xtri(1.5f, off = true)))
    val (_, w1) = directed("all equal", same, Seq(axisRay()), 11)
    assert(w1.accesses(0) == Seq(root, leaf(0), leaf(1), leaf(2), leaf(3)))
    val mixed = image(hp, Seq(Seq(xbox(3, 4), xbox(1, 2), xbox(3, 4), xbox(1, 2)).zipWithIndex.map { case (b, j) => (b, hc.leaf(j, 1)) }),
      (0 until 4).map(_ => xtri(1.5f, off = true)))
    val (_, w2) = directed("pairs equal", mixed, Seq(axisRay()), 12)
    assert(w2.accesses(0) == Seq(root, leaf(1), leaf(3), leaf(0), leaf(2)))
    // two levels: equal inner nodes, then their leaves
    val two = image(hp, Seq(Seq((xbox(1, 4), hc.node(1, 1)), (xbox(1, 4), hc.node(2, 1))),
      Seq((xbox(2, 3), hc.leaf(0, 1)), (xbox(1, 2), hc.leaf(1, 1))), Seq((xbox(1, 2), hc.leaf(2, 1)), (xbox(1, 2), hc.leaf(3, 1)))),
      (0 until 4).map(_ => xtri(1.5f, off = true)))
    val (_, w3) = directed("two levels", two, Seq(axisRay()), 13)
    assert(w3.accesses(0) == Seq(root, Access(0, 1, 0), leaf(1), leaf(0), Access(0, 2, 0), leaf(2), leaf(3)))
  }

  // leaves at x = 5, 1, 3, 7 (slots 0..3); triangles in them at 5.5 (hit), 1.5 (miss), 3.5 (hit), 7.5 (hit)
  private val row = image(hp, Seq(Seq(xbox(5, 6), xbox(1, 2), xbox(3, 4), xbox(7, 8)).zipWithIndex.map { case (b, j) => (b, hc.leaf(j, 1)) }),
    Seq(xtri(5.5f), xtri(1.5f, off = true), xtri(3.5f), xtri(7.5f)))

  test("tmax cuts the traversal: a hit discards farther entries at pop; the ray's own tmax leaves far boxes unhit") {
    val (_, w) = directed("tmax", row, Seq(axisRay(), axisRay(tmax = 2.5f), axisRay(tmin = 4.5f)), 14)
    assert(w.accesses(0) == Seq(root, leaf(1), leaf(2)), "after the hit at 3.5 the entries at 5 and 7 are discarded")
    assert(w.records(0).prim == 102 && w.records(0).t == fbits(3.5f))
    assert(w.accesses(1) == Seq(root, leaf(1)) && w.records(1).prim == -1, "tmax 2.5: only the box at 1 is hit")
    assert(w.accesses(2) == Seq(root, leaf(0)) && w.records(2).prim == 100, "tmin 4.5: the boxes at 1 and 3 lie before it")
    // an entry exactly at tmax is still fetched (it is discarded only when beyond tmax)
    val edge = image(hp, Seq(Seq((xbox(5, 6), hc.leaf(0, 1)), (xbox(1, 2), hc.leaf(1, 1)), (xbox(3, 5), hc.leaf(2, 1)), (xbox(7, 8), hc.leaf(3, 1)))),
      Seq(xtri(5.5f), xtri(1.5f, off = true), xtri(5f), xtri(7.5f)))
    val (_, we) = directed("entry at tmax", edge, Seq(axisRay()), 15)
    assert(we.records(0).t == fbits(5f), "the test needs a hit at exactly t = 5")
    assert(we.accesses(0) == Seq(root, leaf(1), leaf(2), leaf(0)) && we.records(0).prim == 102)
  }

  test("a leaf of several primitives: closest of them, the earlier one on an exact tie") {
    val img = image(hp, Seq(Seq((xbox(1, 9), hc.leaf(0, 4)))), Seq(xtri(6f), xtri(3f), xtri(3f), xtri(2f, off = true)))
    val (_, w) = directed("ties", img, Seq(axisRay(), axisRay(tmin = 4f)), 16)
    assert(w.accesses(0) == Seq(root, Access(1, 0, 4)) && w.records(0).prim == 101 && w.records(0).t == fbits(3f))
    assert(w.records(1).prim == 100)
  }

  test("directed overflow: four children hit, stack of 2, the third push is dropped; record prim -3 and the model's fetches") {
    val p2 = hp.copy(stackDepth = 2)
    val img = image(p2, Seq(Seq(xbox(5, 6), xbox(1, 2), xbox(3, 4), xbox(7, 8)).zipWithIndex.map { case (b, j) => (b, hc.leaf(j, 1)) }),
      (0 until 4).map(_ => xtri(0f, off = true)))
    val (got, w) = directed("overflow", img, Seq(axisRay(), axisRay(tmax = 4.5f)), 17)
    // sorted: slots 1, 2, 0, 3; pushes 3 (slot 3), 0 (slot 0), then slot 2 is dropped
    assert(w.accesses(0) == Seq(root, leaf(1), leaf(0), leaf(3)))
    assert(got.records(0) == Record(got.records(0).id, fbits(Inf), -3, 0, 0, overflow = true, readError = false))
    assert(w.accesses(1) == Seq(root, leaf(1), leaf(2)) && !got.records(1).overflow && got.records(1).prim == -1, "two pushes fit")
  }

  test("err = true on a triangle result: not hit, traversal continues, record prim -2 with the readError flag") {
    val (clean, _) = directed("clean", row, Seq(axisRay()), 18)
    assert(clean.accesses(0) == Seq(root, leaf(1), leaf(2)) && clean.records(0).prim == 102)
    val (got, _) = directed("bad prim", row, Seq(axisRay()), 18, primBad = _ == 2, check = false)
    // the hit at 3.5 is lost, so the entry at 5 is fetched (hit 5.5), the one at 7 discarded
    assert(got.accesses(0) == Seq(root, leaf(1), leaf(2), leaf(0)), s"fetched ${got.accesses(0)}")
    assert(got.records(0) == Record(clean.records(0).id, fbits(Inf), -2, 0, 0, overflow = false, readError = true), got.records(0).toString)
    // an error in a primitive the ray misses flags the ray just the same
    val (g2, _) = directed("bad missed prim", row, Seq(axisRay()), 19, primBad = _ == 1, check = false)
    assert(g2.accesses(0) == Seq(root, leaf(1), leaf(2)) && g2.records(0).prim == -2 && g2.records(0).readError)
  }

  test("err = true on a box result: no child is hit, traversal continues elsewhere, record prim -2") {
    val (g1, _) = directed("bad root", row, Seq(axisRay()), 20, nodeBad = _ == 0, check = false)
    assert(g1.accesses(0) == Seq(root))
    assert(g1.records(0).prim == -2 && g1.records(0).t == fbits(Inf) && g1.records(0).u == 0 && g1.records(0).v == 0 && g1.records(0).readError)
    // two subtrees: the near one (node 1) is poisoned, the far one (node 2) is still traversed and holds a hit
    val two = image(hp, Seq(Seq((xbox(4, 6), hc.node(2, 1)), (xbox(1, 3), hc.node(1, 1))),
      Seq((xbox(1, 2), hc.leaf(0, 1)), (xbox(2, 3), hc.leaf(1, 1))), Seq((xbox(4, 5), hc.leaf(2, 1)), (xbox(5, 6), hc.leaf(3, 1)))),
      Seq(xtri(1.5f), xtri(2.5f), xtri(4.5f), xtri(5.5f)))
    val (clean, _) = directed("two subtrees", two, Seq(axisRay()), 21)
    assert(clean.accesses(0) == Seq(root, Access(0, 1, 0), leaf(0)) && clean.records(0).prim == 100)
    val (g2, _) = directed("bad inner node", two, Seq(axisRay()), 21, nodeBad = _ == 1, check = false)
    assert(g2.accesses(0) == Seq(root, Access(0, 1, 0), Access(0, 2, 0), leaf(2)), s"fetched ${g2.accesses(0)}")
    assert(g2.records(0).prim == -2 && g2.records(0).readError && !g2.records(0).overflow)
  }

  // ---------------------------------------------------------------- step limit (MAX_STEPS): images that loop

  test("step limit, directed: a node that points to itself or to its parent; the ray ends after MAX_STEPS fetches, prim -4") {
    // (with the paper's layout a reference cannot name the root: ref 0 is an empty slot, so the loops start at node 1)
    val limit = 12
    val p = hp.copy(maxSteps = Some(limit))
    val leafTri = Seq(xtri(2.5f, off = true))
    // node 1: a leaf and, nearer, itself: root, then node 1 over and over, a push each time
    val self = image(p, Seq(Seq((xbox(1, 9), hc.node(1, 1))), Seq((xbox(2, 3), hc.leaf(0, 1)), (xbox(1, 9), hc.node(1, 2)))), leafTri)
    // node 2 points back to node 1, its parent: root, 1, 2, 1, 2, ...
    val ancestor = image(p, Seq(Seq((xbox(1, 9), hc.node(1, 1))), Seq((xbox(1, 9), hc.node(2, 2))),
      Seq((xbox(1, 9), hc.node(1, 3)), (xbox(5, 6), hc.leaf(0, 1)))), leafTri)
    val n1 = Access(0, 1, 0); val n2 = Access(0, 2, 0)
    for ((what, img, loop) <- Seq(("itself", self, Seq.fill(limit - 1)(n1)), ("its parent", ancestor, Seq.tabulate(limit - 1)(k => if (k % 2 == 0) n1 else n2)))) {
      // the second ray ends before the loop's boxes (tmax), so it never enters the loop
      val (got, w) = directed(s"loop to $what", img, Seq(axisRay(), axisRay(tmax = 0.5f)), 30)
      assert(w.accesses(0) == root +: loop, s"$what: fetched ${w.accesses(0)}")
      assert(got.records(0) == Record(got.records(0).id, fbits(Inf), Hits.StepLimit, 0, 0, overflow = false, readError = false, stepLimit = true),
        got.records(0).toString)
      assert(Hits.StepLimit == -4 && w.accesses(1) == Seq(root) && w.records(1).prim == Hits.Miss && !w.records(1).stepLimit)
    }
    // the loop in node 1 pushes its leaf each pass: at 40 steps the 32-entry stack has overflowed; the step limit wins
    val (g40, w40) = directed("loop past the stack", self.copy(p = hp.copy(maxSteps = Some(40))), Seq(axisRay()), 31)
    assert(w40.accesses(0).length == 40 && g40.records(0).overflow && g40.records(0).stepLimit && g40.records(0).prim == -4)
    // a read error in the loop wins over the step limit: the leaf nearer than node 1 is fetched on every pass
    val leafFirst = image(p, Seq(Seq((xbox(1, 9), hc.node(1, 1))), Seq((xbox(1, 3), hc.leaf(0, 1)), (xbox(2, 9), hc.node(1, 2)))), leafTri)
    val (gre, _) = directed("read error in the loop", leafFirst, Seq(axisRay()), 32, primBad = _ == 0, check = false)
    assert(gre.accesses(0) == root +: Seq.tabulate(limit - 1)(k => if (k % 2 == 0) n1 else leaf(0)), s"fetched ${gre.accesses(0)}")
    assert(gre.records(0).readError && gre.records(0).stepLimit && gre.records(0).prim == Hits.ReadError)
    // MAX_STEPS = 0: no limit; a loop-free tree ends as before, with as many fetches as it needs
    val (g0, _) = directed("no limit", row.copy(p = hp.copy(maxSteps = Some(0))), Seq(axisRay()), 33)
    assert(g0.accesses(0) == Seq(root, leaf(1), leaf(2)) && g0.records(0).prim == 102)
    // exactly as many steps as the ray needs: not flagged; one fewer: flagged before its last fetch
    val (g3, _) = directed("limit = need", row.copy(p = hp.copy(maxSteps = Some(3))), Seq(axisRay()), 34)
    assert(g3.records(0).prim == 102 && !g3.records(0).stepLimit)
    val (g2, _) = directed("limit = need - 1", row.copy(p = hp.copy(maxSteps = Some(2))), Seq(axisRay()), 35)
    assert(g2.accesses(0) == Seq(root, leaf(1)) && g2.records(0).prim == -4 && g2.records(0).stepLimit)
  }

  /** The image after `flips` silent bit flips (TestScenes.flipBits), padded so that every reference a flip can make
    * names words the model and the test's IU both read: node ids over the whole id field, primitive slots over the
    * whole first field plus a leaf's largest count, zero beyond the packed image. The model traverses this image, not
    * the tree it was packed from (the platform's test reads memory the same way: host.ImageFile.asRead).
    */
  private def corrupted(img: MemoryImage, seed: Long, flips: Int): MemoryImage = {
    val p = img.p
    require(p.refs.nodeIdBits <= 16 && p.refs.primIndexBits <= 16, "a fitted layout: the padded copy names every id")
    val f = TestScenes.flipBits(img, seed, flips)
    MemoryImage(p, java.util.Arrays.copyOf(f.nodes, (1 << p.refs.nodeIdBits) * img.nodeWords),
      java.util.Arrays.copyOf(f.prims, ((1 << p.refs.primIndexBits) + p.refs.maxLeafPrims) * img.primWords))
  }

  // the fitted soup of the random-soup test above (seed 4, M=4, MPPL=2): the same TU circuit, built once
  private def fittedSoup = soupImage(4, 200, PlatformParams(tus = 4, m = 4, mppl = 2), fit = true)

  test("step limit at its default (fitted scene): a node made to point to itself flags the rays that loop after exactly stepBound fetches; the others keep their records") {
    val clean = fittedSoup
    val p = clean.p
    val codec = new RefCodec(p.refs)
    // the first inner node with an inner child: that child's reference now names the node itself
    val (n, j) = (1 until clean.numNodes).iterator.flatMap(n => (0 until p.m).map(n -> _))
      .find { case (n, j) => val r = clean.childRef(n, j); r != 0 && !codec.isPrim(r) }.get
    val nodes = clean.nodes.clone()
    nodes(n * clean.nodeWords + 7 * j + 6) = codec.node(n, codec.level(clean.childRef(n, j)))
    val img = clean.copy(nodes = nodes)
    val rays = soupRays(40, 200); val id = ids(200, 40)
    val want = model(img, MemFaults.none, rays, id)
    val got = rtl(p, img, rays, id, 40, index = 3)
    compare("self loop at the default limit", 40, got, want, rays)
    val before = model(clean, MemFaults.none, rays, id)
    val flagged = want.records.indices.filter(want.records(_).stepLimit)
    info(s"node $n slot $j names node $n: ${flagged.length} of ${rays.count} rays looped, ended after ${p.stepLimit} fetches " +
      s"(${clean.numNodes} nodes, ${clean.numPrims} primitives; the longest clean ray made ${before.accesses.map(_.length).max})")
    assert(flagged.nonEmpty && flagged.length < rays.count, "some rays must enter the loop, not all")
    for (i <- flagged) assert(want.accesses(i).length == p.stepLimit && want.records(i).prim == Hits.StepLimit)
    // a ray that went round the loop and left it (its tmax culled the looping child) keeps its record, unless the
    // passes filled the fitted stack
    for (i <- want.records.indices if !flagged.contains(i))
      assert(want.records(i) == before.records(i) || want.records(i).prim == Hits.Overflow, s"ray $i left the loop with another record")
  }

  // make test: one corrupted image (loops, overflows and memory read errors together), 3 s; make regress: 60, some
  // 6,000 flips in all, half of them over a loop made on purpose
  for (run <- if (rtaccel.Regress.full) 0 until 60 else Seq(2))
    test(s"step limit, random silent bit flips in the image (seeded, run $run): every ray ends once, fetches and records (flags included) equal the model's") {
      val seed = 100L + run
      val clean = fittedSoup
      // odd runs: a loop for certain (a reference made to name its node or an ancestor) under the random flips
      val img = corrupted(if (run % 2 == 1) TestScenes.withLoop(clean, seed) else clean, seed, flips = 60 + 30 * (run % 4))
      val faults = if (run % 3 != 2) MemFaults.none else {
        val primBase = 4096L * ((img.numNodes.toLong * img.p.nodeStrideBytes + 4095) / 4096)
        MemFaults(MemFaults.threshold(0.003), seed.toInt, 32, img.p.nodeStrideBytes, primBase, 64)
      }
      val n = 200
      val rays = soupRays(seed, n); val id = ids(n, seed)
      val want = model(img, faults, rays, id)
      val got = rtl(img.p, img, rays, id, seed, index = run % 4, faults.nodeBad, faults.primBad)
      assert(got.records.map(_.id) == id, "each ray returns once, in turn")
      compare(s"flips run $run", seed, got, want, rays)
      val r = want.records
      info(s"${r.count(_.stepLimit)} step limits (limit ${img.p.stepLimit}), ${r.count(_.overflow)} overflows, ${r.count(_.readError)} read errors, " +
        s"${r.count(_.prim >= 0)} hits of $n rays; ${want.accesses.map(_.length).sum} fetches, ${got.cycles} cycles")
      // a flagged ray's record names its first flag; an unflagged one keeps the id word as memory holds it, which a
      // flip may have made negative (RTL and model alike)
      assert(r.forall(x => !(x.overflow || x.readError || x.stepLimit) ||
        (x.t == fbits(Inf) && x.prim == (if (x.readError) Hits.ReadError else if (x.stepLimit) Hits.StepLimit else Hits.Overflow))))
      if (!rtaccel.Regress.full) assert(r.exists(_.stepLimit), "make test's seeds make a loop some rays enter")
    }

  // the short stack with restart over corrupted images: make test on the short-stack test's circuit (ring 1), one image;
  // make regress 10 more there and 20 with a ring of 2 on the fitted soup of the random-flip test
  private def shortSoup = { val i = soupImage(7, 300, PlatformParams(tus = 4, m = 4, mppl = 4), fit = true); i.copy(p = i.p.copy(shortStack = 1)) }
  for ((ring, images) <- Seq(1 -> (if (rtaccel.Regress.full) 11 else 1)) ++ (if (rtaccel.Regress.full) Seq(2 -> 20) else Nil))
    test(s"step limit with SHORT_STACK=$ring, a loop and random silent bit flips ($images seeded image(s)): fetches and records (flags included) equal the model's") {
      val clean = if (ring == 1) shortSoup else { val i = fittedSoup; i.copy(p = i.p.copy(shortStack = ring)) }
      var limited = 0
      for (run <- 0 until images) {
        val seed = 500L + run
        val img = corrupted(if (run % 2 == 0) TestScenes.withLoop(clean, seed) else clean, seed, flips = 60 + 30 * (run % 4))
        val rays = soupRays(seed, 150); val id = ids(150, seed)
        val want = model(img, MemFaults.none, rays, id)
        val got = rtl(img.p, img, rays, id, seed, index = run % 4)
        compare(s"ring $ring flips run $run", seed, got, want, rays)
        limited += want.records.count(_.stepLimit)
      }
      info(s"$limited rays ended at the step limit (${clean.p.stepLimit} fetches, or a node below the trail's ${clean.p.treeLevels} levels)")
      assert(limited > 0)
    }
}
