package rtaccel.iu

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.collection.mutable
import scala.util.Random
import rtaccel.TestScenes
import rtaccel.bvh.{Mbvh, MemoryImage, RefCodec}
import rtaccel.config.RespOrder
import rtaccel.config.{Fit, PlatformParams}
import rtaccel.model.{PreparedRay, RayBox, RayTriangle}

object IntersectionUnitSpec {
  /** Expected box result: hit per slot, tnear where hit, the child refs; on err only err and no hit count. */
  final case class BoxExp(tu: Int, hit: Seq[Boolean], tnear: Seq[Int], cref: Seq[Int], err: Boolean, what: String)
  final case class TriExp(tu: Int, hit: Boolean, t: Int, u: Int, v: Int, prim: Int, last: Boolean, err: Boolean, what: String)
  final case class Req(cref: Int, tmax: Float, r: PreparedRay)
  final case class Stats(requests: Int, nodes: Int, prims: Int, boxHits: Int, triHits: Int, badNodes: Int, badPrims: Int,
                         mixedLeaves: Int, maxOutstanding: Int, cycles: Long, overtakes: Int = 0)
}

/** The intersection unit top with several TU request ports and the memory side played by the test: each
  * TU port issues requests (random ray, tmax and node or leaf reference from a packed soup image) one at a
  * time, waiting for its results as a TU does; the memory answers each FetchReq with the image's beats, in
  * order, after random delays, and poisons random beats (err = true, inverted data). Every box and triangle
  * result must equal the reference model's RayBox / RayTriangle on the same node / primitive bit for bit,
  * tagged with the requesting TU; a poisoned beat makes its node's hits all false / its primitive not hit,
  * with err set.
  */
class IntersectionUnitSpec extends AnyFunSuite with ChiselScalatestTester {
  import IntersectionUnitSpec._
  private def fbits(f: Float): Int = java.lang.Float.floatToRawIntBits(f)
  private def u32(i: Int): BigInt = BigInt(i & 0xffffffffL)
  // Verilator (firtool-built): M box tests and a Möller–Trumbore pipeline with a divider are far too slow in treadle.
  private def folder(p: PlatformParams, beatBits: Int) = {
    val r = p.refs
    s"IntersectionUnitSpec/tus${p.tus}-m${p.m}-beat$beatBits-refs${r.nodeIdBits}.${r.primIndexBits}.${r.countBits}.${r.levelBits}-div${p.divStages}${if (p.nodeQuantBits > 0) s"-q${p.nodeQuantBits}" else ""}${if (p.respByPath) s"-r${p.respOrder}" else ""}${if (p.rayStore) "-store" else ""}"
  }

  private def soupImage(seed: Long, p0: PlatformParams, fit: Boolean): MemoryImage = {
    val s = TestScenes.soup(seed, 300, size = 3f)
    val bvh = Mbvh.build(s, p0)
    MemoryImage.pack(bvh, s, if (fit) Fit.fitTo(p0, bvh) else p0)
  }

  /** Random traffic on the IU; `errPercent` of the memory beats come back with err. respByPath (RESP_ORDER=path):
    * node beats and leaf beats come on their own ports, each in its own request order, the leaves' slower, so that
    * node beats are taken ahead of older leaves' (counted in Stats.overtakes). RESP_ORDER=tagged: the two ports,
    * and each port answers in any order: a new answer goes in at a random answer boundary of its port's queue (not
    * into the answer under way), its beats tagged with the TU; a result is expected once its answer's first beat is
    * taken (Stats.overtakes: answers placed ahead of an older one). rayStore (RAY_STORE=1): a TU's request carries
    * no ray; the test writes the TU's ray into the IU's ray store as it presents the request (one write per cycle,
    * as the TC hands out rays), and the results must still be those of that ray. */
  private def run(img: MemoryImage, beatBits: Int, requests: Int, seed: Long, errPercent: Int, order: String = RespOrder.Request,
      rayStore: Boolean = false): Stats = {
    val respByPath = order != RespOrder.Request; val tagged = order == RespOrder.Tagged
    // PIPELINE=none: the monitor below pairs each memory request with the TU port taken in the same cycle, which holds
    // for the flat arbiter; the tree of PIPELINE's budget (queues between its levels) is checked by TreeArbiterSpec
    // and end to end by PlatformSpec, the pipes at every depth by IuPipesSpec
    val p = img.p.copy(respByPath = respByPath, respTagged = tagged, rayStore = rayStore, pipelining = rtaccel.config.Pipelining.Fixed)
    val rnd = new Random(seed)
    val codec = new RefCodec(p.refs)
    val m = p.m
    val beatWords = beatBits / 32
    val nodeWords = p.nodeSlotBytes / 4; val primWords = p.primStrideBytes / 4
    val nodeRefs = 0 +: (0 until img.numNodes).flatMap(n => (0 until m).map(img.childRef(n, _))).filter(r => r != 0 && !codec.isPrim(r))
    val leafRefs = (0 until img.numNodes).flatMap(n => (0 until m).map(img.childRef(n, _))).filter(codec.isPrim)
    assert(leafRefs.exists(codec.count(_) > 1), "the image needs leaves of several primitives")
    val rays = TestScenes.rays(seed, 512)
    var st = Stats(0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
    val iu = rtaccel.TestSim.firtool(folder(p, beatBits))(new IntersectionUnit(p, beatBits, p.tus))(_.io)
    test(iu.gen()).withAnnotations(iu.annotations) { dut =>
      dut.clock.setTimeout(0)
      var cycle = 0L
      def fail(what: String): Nothing = throw new AssertionError(s"$what (seed $seed, cycle $cycle)")
      val tuReq = Array.fill[Option[Req]](p.tus)(None)      // presented on the port
      val tuWait = Array.fill(p.tus)(0)                     // results still owed to the TU
      val tuNext = Array.fill(p.tus)(0L)                    // earliest cycle of its next request
      val boxQ = mutable.Queue[BoxExp](); val triQ = mutable.Queue[TriExp]()
      // per response port (RESP_ORDER=path: 0 nodes, 1 leaves): beats owed, cycle of the next, one shown
      val ports = dut.io.mem.resp +: dut.io.mem.primResp.toSeq
      val beatQs = ports.map(_ => mutable.ArrayBuffer[(BigInt, Boolean, Boolean, Int, Int)]()) // data, last, err, request number, tag
      // tagged: the results each request's answer will bring, expected when its first beat is taken
      val deferred = mutable.Map[Int, mutable.ArrayBuffer[() => Unit]]()
      def expect(req: Int)(e: => Unit): Unit = if (tagged) deferred.getOrElseUpdate(req, mutable.ArrayBuffer()) += (() => e) else e
      val beatAt = Array.fill(ports.length)(0L); val beatShown = Array.fill(ports.length)(false)
      var issued = 0
      var lastProgress = 0L // cycle of the last result
      for (i <- 0 until p.tus) dut.io.req(i).valid.poke(false.B)
      dut.io.mem.req.ready.poke(false.B); for (port <- ports) port.valid.poke(false.B)
      var lastMemReady = false
      while (issued < requests || tuWait.exists(_ > 0) || tuReq.exists(_.nonEmpty)) {
        if (cycle > lastProgress + 5000) fail(s"stuck: ${boxQ.length} box and ${triQ.length} triangle results owed, ${beatQs.map(_.length).sum} beats " +
          s"unsent (shown: ${beatShown.mkString(",")}, taken: ${ports.map(_.ready.peek().litToBoolean).mkString(",")}), TUs owed ${tuWait.mkString(",")}, " +
          s"presenting ${tuReq.map(_.nonEmpty).mkString(",")}")
        // ---- TU ports: a new request when idle, held until taken (RAY_STORE=1: one TU a cycle writes its ray)
        var storeFree = true
        for (w <- dut.io.rays) w.valid.poke(false.B)
        for (i <- 0 until p.tus) if (tuReq(i).isEmpty && tuWait(i) == 0 && cycle >= tuNext(i) && issued < requests && storeFree) {
          val k = rnd.nextInt(rays.count)
          val tmax = rnd.nextInt(5) match { case 0 => rnd.nextFloat() * 8; case 1 => 0f; case _ => Float.PositiveInfinity }
          val tmin = if (rnd.nextInt(5) == 0) rnd.nextFloat() * 2 else 0f
          val cref = if (rnd.nextBoolean()) nodeRefs(rnd.nextInt(nodeRefs.length)) else leafRefs(rnd.nextInt(leafRefs.length))
          // mostly aimed at a point of the node's child boxes or of one of the leaf's triangles, so that many hit
          val o = Array(rays(k, 0), rays(k, 1), rays(k, 2))
          val d = if (rnd.nextInt(4) == 0) Array(rays(k, 3), rays(k, 4), rays(k, 5)) else {
            val target = if (!codec.isPrim(cref)) {
              val j = rnd.nextInt(m); val id = codec.nodeId(cref)
              Array.tabulate(3)(a => { val lo = img.childWord(id, j, a); val hi = img.childWord(id, j, 3 + a)
                val l = java.lang.Float.intBitsToFloat(lo); val h = java.lang.Float.intBitsToFloat(hi); l + (h - l) * rnd.nextFloat() })
            } else {
              val s = codec.firstPrim(cref) + rnd.nextInt(codec.count(cref))
              val b1 = rnd.nextFloat(); val b2 = rnd.nextFloat() * (1 - b1)
              Array.tabulate(3)(a => img.primCoord(s, a) * (1 - b1 - b2) + img.primCoord(s, 3 + a) * b1 + img.primCoord(s, 6 + a) * b2)
            }
            Array.tabulate(3)(a => target(a) - o(a))
          }
          val r = new PreparedRay(o(0), o(1), o(2), d(0), d(1), d(2), tmin, tmax)
          val q = dut.io.req(i).bits
          q.tu.poke(i.U) // a TU writes its own index
          q.cref.poke(u32(cref).U); q.tmax.poke(u32(fbits(tmax)).U)
          def pokeRay(to: RayData): Unit = {
            for ((x, a) <- Seq(r.ox, r.oy, r.oz).zipWithIndex) to.o(a).poke(u32(fbits(x)).U)
            for ((x, a) <- Seq(r.dx, r.dy, r.dz).zipWithIndex) to.d(a).poke(u32(fbits(x)).U)
            for ((x, a) <- Seq(r.ix, r.iy, r.iz).zipWithIndex) to.inv(a).poke(u32(fbits(x)).U)
            to.tmin.poke(u32(fbits(tmin)).U)
          }
          q.ray.foreach(pokeRay)
          for (w <- dut.io.rays) { w.valid.poke(true.B); w.bits.slot.poke(i.U); pokeRay(w.bits.ray); storeFree = false }
          dut.io.req(i).valid.poke(true.B)
          tuReq(i) = Some(Req(cref, tmax, r)); issued += 1
        }
        // ---- memory side
        val memReady = rnd.nextInt(4) != 0
        if (memReady != lastMemReady) { dut.io.mem.req.ready.poke(memReady.B); lastMemReady = memReady }
        val showBeat = ports.indices.map(k => beatQs(k).nonEmpty && cycle >= beatAt(k))
        for ((port, k) <- ports.zipWithIndex) if (showBeat(k) && !beatShown(k)) {
          val (d, last, err, _, tag) = beatQs(k).head
          port.bits.data.poke(d.U(beatBits.W)); port.bits.last.poke(last.B); port.bits.err.poke(err.B)
          for (t <- port.bits.tag) t.poke(tag.U)
          port.valid.poke(true.B); beatShown(k) = true
        }
        // ---- observe
        val memReqValid = dut.io.mem.req.valid.peek().litToBoolean
        val fired = (0 until p.tus).filter(i => tuReq(i).nonEmpty && dut.io.req(i).ready.peek().litToBoolean)
        if (memReqValid && memReady) {
          if (fired.length != 1) fail(s"a memory request with TU ports ${fired.mkString(",")} taken")
          val i = fired.head; val q = tuReq(i).get
          val ref = dut.io.mem.req.bits.childRef.peek().litValue.toInt
          if (ref != q.cref) fail(f"memory request for ref 0x$ref%08x, TU $i asked for 0x${q.cref}%08x")
          // the image's beats for this request, some poisoned
          val words: Seq[Int] =
            if (!codec.isPrim(ref)) img.nodes.slice(codec.nodeId(ref) * nodeWords, (codec.nodeId(ref) + 1) * nodeWords).toSeq
            else img.prims.slice(codec.firstPrim(ref) * primWords, (codec.firstPrim(ref) + codec.count(ref)) * primWords).toSeq
          val nBeats = words.length / beatWords
          val bad = Seq.fill(nBeats)(rnd.nextInt(100) < errPercent)
          val answer = (0 until nBeats).map { b =>
            val data = (0 until beatWords).map(w => u32(words(b * beatWords + w)) << (32 * w)).sum
            (if (bad(b)) data ^ ((BigInt(1) << beatBits) - 1) else data, b == nBeats - 1, bad(b), st.requests, i)
          }
          val bq = beatQs(if (respByPath && codec.isPrim(ref)) 1 else 0)
          if (!tagged) bq ++= answer else {
            // answer boundaries after the answer under way (its first beat shown or taken), and the end
            val underWay = bq.nonEmpty && (beatShown(if (bq eq beatQs(0)) 0 else 1) || deferred.get(bq.head._4).isEmpty)
            val bounds = (0 to bq.length).filter(j => (j == 0 || bq(j - 1)._2) && !(j == 0 && underWay))
            val at = bounds(rnd.nextInt(bounds.length))
            if (at < bq.length) st = st.copy(overtakes = st.overtakes + 1)
            bq.insertAll(at, answer)
          }
          def unitBad(u: Int, unitWords: Int) = (u * unitWords / beatWords until (u + 1) * unitWords / beatWords).exists(bad)
          val what = f"TU $i ref 0x$ref%08x"
          if (!codec.isPrim(ref)) {
            val id = codec.nodeId(ref)
            val err = unitBad(0, nodeWords)
            val res = (0 until m).map { j =>
              val cr = img.childRef(id, j)
              def w(k: Int) = java.lang.Float.intBitsToFloat(img.childWord(id, j, k))
              val tn = if (cr == 0 || err) Float.NaN else RayBox.test(q.r, q.tmax, w(0), w(1), w(2), w(3), w(4), w(5))
              (!tn.isNaN, fbits(tn), cr)
            }
            expect(st.requests)(boxQ.enqueue(BoxExp(i, res.map(_._1), res.map(_._2), res.map(_._3), err, s"$what node $id")))
            tuWait(i) = 1
            st = st.copy(nodes = st.nodes + 1, boxHits = st.boxHits + res.count(_._1), badNodes = st.badNodes + (if (err) 1 else 0))
          } else {
            val first = codec.firstPrim(ref); val n = codec.count(ref)
            val errs = (0 until n).map(k => unitBad(k, primWords))
            for (k <- 0 until n) {
              val s = first + k; val o = new RayTriangle.Result
              val hit = !errs(k) && RayTriangle.test(q.r, q.tmax, c => img.primCoord(s, c), o)
              val e = TriExp(i, hit, fbits(o.t), fbits(o.u), fbits(o.v), img.primId(s), k == n - 1, errs(k), s"$what primitive slot $s")
              expect(st.requests)(triQ.enqueue(e))
              if (hit) st = st.copy(triHits = st.triHits + 1)
            }
            tuWait(i) = n
            st = st.copy(prims = st.prims + n, badPrims = st.badPrims + errs.count(identity),
              mixedLeaves = st.mixedLeaves + (if (errs.exists(identity) && errs.exists(!_)) 1 else 0))
          }
          st = st.copy(requests = st.requests + 1, maxOutstanding = math.max(st.maxOutstanding, tuWait.count(_ > 0)))
          tuReq(i) = None
        } else if (fired.nonEmpty) fail(s"TU ports ${fired.mkString(",")} taken without a memory request")
        for ((port, k) <- ports.zipWithIndex) if (showBeat(k) && port.ready.peek().litToBoolean) {
          val taken = beatQs(k).remove(0); beatShown(k) = false
          for (es <- deferred.remove(taken._4); e <- es) e() // tagged: the answer's first beat
          if (!tagged && k == 0 && beatQs.length > 1 && beatQs(1).headOption.exists(_._4 < taken._4)) st = st.copy(overtakes = st.overtakes + 1)
          // RESP_ORDER=path: the leaf port is the slow one (a primitive miss), so that nodes overtake
          beatAt(k) = cycle + 1 + (if (rnd.nextInt(3) == 0) rnd.nextInt(8) else 0) + (if (k == 1) rnd.nextInt(12) else 0)
        }
        if (dut.io.box.valid.peek().litToBoolean) {
          if (boxQ.isEmpty) fail("a box result nobody asked for")
          val e = boxQ.dequeue(); val b = dut.io.box.bits; lastProgress = cycle
          def chk(ok: Boolean, field: String): Unit = if (!ok) fail(s"${e.what}: box $field differs from the model")
          chk(b.tu.peek().litValue == e.tu, s"tu ${b.tu.peek().litValue} (want ${e.tu})")
          chk(b.err.peek().litToBoolean == e.err, "err")
          for (j <- 0 until m) {
            chk(b.hit(j).peek().litToBoolean == e.hit(j), s"hit($j)")
            if (e.hit(j)) chk(b.tnear(j).peek().litValue == u32(e.tnear(j)), s"tnear($j)")
            if (!e.err) chk(b.cref(j).peek().litValue == u32(e.cref(j)), s"cref($j)")
          }
          tuWait(e.tu) -= 1
          if (tuWait(e.tu) == 0) tuNext(e.tu) = cycle + 1 + rnd.nextInt(6)
        }
        if (dut.io.tri.valid.peek().litToBoolean) {
          if (triQ.isEmpty) fail("a triangle result nobody asked for")
          val e = triQ.dequeue(); val t = dut.io.tri.bits; lastProgress = cycle
          def chk(ok: Boolean, field: String): Unit = if (!ok) fail(s"${e.what}: triangle $field differs from the model")
          chk(t.tu.peek().litValue == e.tu, s"tu ${t.tu.peek().litValue} (want ${e.tu})")
          chk(t.err.peek().litToBoolean == e.err, "err")
          chk(t.hit.peek().litToBoolean == e.hit, "hit")
          chk(t.last.peek().litToBoolean == e.last, "last")
          if (!e.err) chk(t.prim.peek().litValue == u32(e.prim), "prim")
          if (e.hit) {
            chk(t.t.peek().litValue == u32(e.t), "t"); chk(t.u.peek().litValue == u32(e.u), "u"); chk(t.v.peek().litValue == u32(e.v), "v")
          }
          tuWait(e.tu) -= 1
          if (tuWait(e.tu) == 0) tuNext(e.tu) = cycle + 1 + rnd.nextInt(6)
        }
        dut.clock.step(); cycle += 1
        // deassert what was taken at this edge
        for ((port, k) <- ports.zipWithIndex) if (!beatShown(k)) port.valid.poke(false.B)
        for (i <- 0 until p.tus) if (tuReq(i).isEmpty) dut.io.req(i).valid.poke(false.B)
      }
      for (_ <- 0 until 40) { // nothing more comes out
        dut.io.box.valid.expect(false.B); dut.io.tri.valid.expect(false.B); dut.io.mem.req.valid.expect(false.B); dut.clock.step()
      }
      assert(boxQ.isEmpty && triQ.isEmpty && beatQs.forall(_.isEmpty))
      st = st.copy(cycles = cycle)
    }
    st
  }

  private def report(s: Stats): String =
    s"${s.requests} requests (${s.nodes} nodes, ${s.prims} primitives), ${s.boxHits} child hits, ${s.triHits} triangle hits, " +
      s"${s.badNodes} poisoned nodes, ${s.badPrims} poisoned primitives (${s.mixedLeaves} leaves part poisoned), " +
      s"up to ${s.maxOutstanding} requests outstanding, ${s.cycles} cycles, ${s.overtakes} answers ahead of an older one " +
      "(path: node beats taken ahead of an older leaf's; tagged: answers placed ahead of an older one on their port)"

  private val regress = rtaccel.Regress.full
  // make regress adds M=8 on 128-bit beats and the quantized node (make test meets q8 in PlatformSpec and NodeDecodeSpec)
  // (make test: the 64-bit case, records across beats; the platform's own 256-bit IU at 4 TUs runs in PlatformSpec)
  for ((tus, m, beat, fit, n, seed) <- Seq((3, 2, 64, true, 2000, 2L)) ++
      (if (regress) Seq((4, 4, 256, false, 3000, 1L), (5, 8, 128, false, 2000, 3L)) else Nil))
    test(s"TUs=$tus M=$m, $beat-bit beats${if (fit) ", fitted reference fields" else ""}: results equal RayBox / RayTriangle bit for bit, tagged by TU; poisoned beats ($n requests, seed $seed)") {
      val img = soupImage(seed, PlatformParams(tus = tus, m = m, mppl = 4), fit)
      val s = run(img, beat, n, seed, errPercent = 3)
      info(report(s))
      assert(s.boxHits > 0 && s.triHits > 0 && s.badNodes > 0 && s.badPrims > 0 && s.mixedLeaves > 0,
        "the traffic must contain hits, poisoned nodes and primitives, and leaves with good and poisoned primitives")
      assert(s.maxOutstanding >= 2 && s.maxOutstanding <= tus, "requests overlap, at most one per TU")
    }

  // NODE_FORMAT=q8: memory sends the quantized 64 B node, the expected boxes are the model's decoded planes
  if (regress) test("NODE_FORMAT=q8, TUs=3 M=4, 256-bit beats: results equal RayBox on the decoded planes bit for bit; poisoned beats (2000 requests, seed 5)") {
    val img = soupImage(5L, PlatformParams(tus = 3, m = 4, mppl = 4, nodeQuantBits = 8), fit = false)
    assert(img.nodeWords == 16)
    val s = run(img, 256, 2000, 5L, errPercent = 3)
    info(report(s))
    assert(s.boxHits > 0 && s.triHits > 0 && s.badNodes > 0 && s.badPrims > 0)
  }

  // RESP_ORDER=path: two beat streams; each kind's results in its own order, nodes overtaking slower leaves
  // (make test at M=2: the build is the case's time and BoxPipe's lanes most of it; make regress M=4)
  private val pathM = if (regress) 4 else 2
  test(s"RESP_ORDER=path, TUs=4 M=$pathM: node and leaf beats on their own ports; results equal the model, node beats taken ahead of older leaves' (1500 requests, seed 6)") {
    val img = soupImage(6L, PlatformParams(tus = 4, m = pathM, mppl = 4), fit = false)
    val s = run(img, 256, 1500, 6L, errPercent = 3, order = RespOrder.Path)
    info(report(s))
    assert(s.boxHits > 0 && s.triHits > 0 && s.badNodes > 0 && s.badPrims > 0)
    assert(s.overtakes > 0, "no node beat was taken ahead of an older leaf's: the two kinds are not independent")
  }

  // RESP_ORDER=tagged: each port answers in any order, whole answers tagged by TU; the job tables route each one
  // (make test: in the RAY_STORE=1 case below, the same circuit with the rays in the store)
  if (regress) test("RESP_ORDER=tagged, TUs=5 M=4: answers in random order on each port, tagged by TU; results equal the model (1500 requests, seed 7)") {
    val img = soupImage(7L, PlatformParams(tus = 5, m = 4, mppl = 4), fit = false)
    val s = run(img, 256, 1500, 7L, errPercent = 3, order = RespOrder.Tagged)
    info(report(s))
    assert(s.boxHits > 0 && s.triHits > 0 && s.badNodes > 0 && s.badPrims > 0)
    assert(s.overtakes > 50, s"only ${s.overtakes} answers were placed ahead of an older one: the test does not reorder")
  }

  // RAY_STORE=1: requests carry no ray; every request brings a new random ray, written into the store as it is
  // presented, so a read of the wrong entry (or of a stale ray) gives another ray's results (make test: tagged, whose
  // answers come back in any order, the harder case for the store, and make test's tagged case; make regress adds
  // request order)
  for ((order, tus, seed) <- Seq((RespOrder.Tagged, 5, 8L)) ++ (if (regress) Seq((RespOrder.Request, 3, 9L)) else Nil))
    test(s"RAY_STORE=1, RESP_ORDER=$order, TUs=$tus M=4: rays from the ray store, results equal the model (1500 requests, seed $seed)") {
      val img = soupImage(seed, PlatformParams(tus = tus, m = 4, mppl = 4), fit = false)
      val s = run(img, 256, 1500, seed, errPercent = 3, order = order, rayStore = true)
      info(report(s))
      assert(s.boxHits > 0 && s.triHits > 0 && s.badNodes > 0 && s.badPrims > 0)
      if (order == RespOrder.Tagged) assert(s.overtakes > 50, s"only ${s.overtakes} answers were placed ahead of an older one: the test does not reorder")
    }

  // make regress: every other case mixes 97 % clean beats with the poisoned ones already
  if (regress) test("no memory errors: every result is clean, TUs=4 M=4 (1000 requests, seed 4)") {
    val img = soupImage(1L, PlatformParams(tus = 4, m = 4, mppl = 4), fit = false)
    val s = run(img, 256, 1000, 4L, errPercent = 0)
    info(report(s))
    assert(s.badNodes == 0 && s.badPrims == 0 && s.boxHits > 0 && s.triHits > 0)
  }
}
