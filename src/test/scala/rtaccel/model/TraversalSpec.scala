package rtaccel.model

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.bvh.{MemoryImage, Mbvh}
import rtaccel.config.{Fit, PlatformParams}
import rtaccel.scene.{Hits, Normalize, Rays, Scene}

object BruteForce {
  /** Closest hit over every triangle in index order with the same Möller–Trumbore: the independent answer
    * the traversal must reproduce (first-found wins a tie, so prims may differ only at equal t).
    */
  def trace(s: Scene, rays: Rays): Hits = {
    val h = Hits.empty(rays.count); val o = new RayTriangle.Result
    for (i <- 0 until rays.count) {
      val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
      var tmax = r.tmax
      for (t <- 0 until s.triangles)
        if (RayTriangle.test(r, tmax, (k: Int) => s.coords(9 * t + k), o)) {
          tmax = o.t; h.t(i) = o.t; h.prim(i) = t; h.u(i) = o.u; h.v(i) = o.v
        }
    }
    h
  }
  def tOf(s: Scene, rays: Rays, i: Int, t: Int): Option[Float] = {
    val o = new RayTriangle.Result
    val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), Float.PositiveInfinity)
    if (RayTriangle.test(r, Float.PositiveInfinity, (k: Int) => s.coords(9 * t + k), o)) Some(o.t) else None
  }
}

class TraversalSpec extends AnyFunSuite {
  private def bits(f: Float) = java.lang.Float.floatToRawIntBits(f)

  private def traverse(s: Scene, p: PlatformParams, rays: Rays, sink: AccessSink = AccessSink.none, st: RayStats = new RayStats) = {
    val bvh = Mbvh.build(s, p)
    (new Traversal(MemoryImage.pack(bvh, s, Fit.fitTo(p, bvh))).traceAll(rays, sink, st), bvh)
  }

  /** Traversal == brute force: t bit for bit; the same prim (then u, v bit for bit) unless the brute-force
    * answer and the traversal's prim tie exactly in t. Returns the number of such exact ties.
    */
  private def assertSame(s: Scene, rays: Rays, a: Hits, b: Hits, what: String): Int = {
    var ties = 0
    for (i <- 0 until rays.count) {
      assert(bits(a.t(i)) == bits(b.t(i)), s"$what ray $i: t ${a.t(i)} vs brute force ${b.t(i)} (prims ${a.prim(i)} / ${b.prim(i)})")
      if (a.prim(i) != b.prim(i)) {
        assert(BruteForce.tOf(s, rays, i, a.prim(i)).map(bits) == Some(bits(b.t(i))), s"$what ray $i: prim ${a.prim(i)} vs ${b.prim(i)}")
        ties += 1
      } else assert(bits(a.u(i)) == bits(b.u(i)) && bits(a.v(i)) == bits(b.v(i)), s"$what ray $i: barycentrics differ")
    }
    ties
  }

  for (m <- Seq(2, 4, 8); mppl <- Seq(1, 2, 4, 8, 16))
    test(s"bit-exact against brute force on random soups, M=$m MPPL=$mppl") {
      for (seed <- 1 to 2) {
        val s = TestScenes.soup(seed, 300); val rays = TestScenes.rays(seed + 100, 800)
        assertSame(s, rays, traverse(s, PlatformParams(m = m, mppl = mppl), rays)._1, BruteForce.trace(s, rays), s"soup$seed")
      }
    }

  for ((m, mppl) <- Seq((2, 1), (4, 4), (8, 16)))
    test(s"bit-exact against brute force on procedural fixtures with golden rays, M=$m MPPL=$mppl") {
      val fx = TestScenes.fixtures
      assume(fx.nonEmpty, "procedural fixtures absent: run `make fixtures` (make test does)")
      for ((name, s, allRays) <- fx) {
        val n = math.min(allRays.count, 1500)
        val rays = Rays(allRays.data.take(8 * n))
        val ties = assertSame(s, rays, traverse(s, PlatformParams(m = m, mppl = mppl), rays)._1, BruteForce.trace(s, rays), name)
        info(s"$name: $n rays, $ties exact-t ties resolved differently from index order")
      }
    }

  test("access trace: starts at the root, node levels match the tree, leaves carry their counts") {
    val s = TestScenes.soup(3, 400); val rays = TestScenes.rays(4, 300); val p = PlatformParams(m = 4, mppl = 4)
    val rec = new AccessRecorder; val st = new RayStats
    val (_, bvh) = traverse(s, p, rays, rec, st)
    val rows = rec.toArray.grouped(5).toSeq
    assert(rows.length == st.nodeFetches + st.leafFetches)
    val firstPerRay = rows.groupBy(_(0)).view.mapValues(_.head).toMap
    assert(firstPerRay.size == rays.count && firstPerRay.values.forall(r => r(1) == 0 && r(2) == 0 && r(3) == 0))
    val leafCounts = bvh.nodes.flatMap(_.children.filter(_.isLeaf)).map(c => c.firstPrim -> c.count).toMap
    for (r <- rows) {
      if (r(1) == 0) assert(bvh.nodes(r(2)).level == r(3), s"node ${r(2)} logged at level ${r(3)}")
      else assert(leafCounts.get(r(2)).contains(r(4)), s"leaf at slot ${r(2)} logged with ${r(4)} prims")
    }
    assert(rows.filter(_(1) == 1).map(_(4).toLong).sum == st.primTests)
    assert(st.maxStack <= bvh.stackBound)
  }

  test("a stack shallower than the ray needs: the ray gets the overflow record, every other ray is unchanged") {
    val s = TestScenes.soup(9, 2000); val rays = TestScenes.rays(10, 200)
    val deep = new RayStats; val shallow = new RayStats
    val p = PlatformParams(m = 8, mppl = 1)
    val (h1, _) = traverse(s, p, rays, st = deep)
    assert(deep.overflows == 0)
    val bvh = Mbvh.build(s, p)
    val h2 = new Traversal(MemoryImage.pack(bvh, s, Fit.fitTo(p, bvh).copy(stackDepth = 2))).traceAll(rays, stats = shallow)
    assert(shallow.overflows > 0 && shallow.overflows < rays.count && shallow.maxStack == 2)
    val flagged = (0 until rays.count).filter(i => h2.prim(i) == rtaccel.scene.Hits.Overflow)
    assert(flagged.length == shallow.overflows)
    for (i <- flagged) assert(h2.t(i).isPosInfinity && h2.u(i) == 0f && h2.v(i) == 0f)
    for (i <- 0 until rays.count if !flagged.contains(i))
      assert(h1.prim(i) == h2.prim(i) && java.lang.Float.floatToRawIntBits(h1.t(i)) == java.lang.Float.floatToRawIntBits(h2.t(i)), s"ray $i")
  }

  test("power-of-two normalisation leaves every result bit-identical (1e30- and 1e-30-sized scenes)") {
    val s = TestScenes.soup(21, 300); val rays = TestScenes.rays(22, 500); val p = PlatformParams()
    val ref = traverse(s, p, rays)._1
    for (k <- Seq(100, -100, 20, -20)) {
      val scaled = Scene("scaled", s.coords.map(x => java.lang.Math.scalb(x, k)))
      val sr = Rays(rays.data.zipWithIndex.map { case (x, i) => if (i % 8 < 6) java.lang.Math.scalb(x, k) else x })
      val e = Normalize.exponent(scaled)
      val h = traverse(Normalize.scene(scaled, e), p, Normalize.rays(sr, e))._1
      for (i <- 0 until rays.count) {
        assert(h.prim(i) == ref.prim(i), s"2^$k ray $i")
        assert(bits(h.t(i)) == bits(ref.t(i)) && bits(h.u(i)) == bits(ref.u(i)) && bits(h.v(i)) == bits(ref.v(i)))
      }
      if (math.abs(k) == 100) assert(traverse(scaled, p, sr)._1.prim.forall(_ == -1), "without normalisation fp32 overflows or underflows")
    }
  }

  test("rays with a tmax before every surface miss; the window [tmin, tmax) is honoured") {
    val s = TestScenes.soup(5, 200); val rays = TestScenes.rays(6, 300)
    val full = traverse(s, PlatformParams(), rays)._1
    val cut = Rays(rays.data.zipWithIndex.map { case (x, i) => if (i % 8 == 7) { val r = i / 8; if (full.prim(r) >= 0) full.t(r) else x } else x })
    val h = traverse(s, PlatformParams(), cut)._1
    for (i <- 0 until rays.count if full.prim(i) >= 0) assert(h.prim(i) == -1 || h.t(i) < full.t(i))
  }

  // The short stack with restart must find exactly the full stack's hits (the same first-visit order of leaves;
  // revisits cannot replace an equal t), never overflow, and pay only extra node fetches.
  test("short stack with restart: bit-identical hits to the full stack at 1, 2 and 4 entries, with restarts") {
    val cases = Seq((TestScenes.soup(51, 3000), TestScenes.rays(52, 400), 4, 1), (TestScenes.soup(53, 2000), TestScenes.rays(54, 300), 8, 1),
      (TestScenes.soup(55, 2500), TestScenes.rays(56, 300), 2, 2)) ++
      TestScenes.fixtures.map { case (_, sc, ry) => (sc, ry, 4, 4) }
    for ((scene, rays, m, mppl) <- cases; ring <- Seq(1, 2, 4)) {
      val p = PlatformParams(m = m, mppl = mppl)
      val bvh = Mbvh.build(scene, p); val fp = Fit.fitTo(p, bvh)
      val full = new RayStats; val short = new RayStats
      val h0 = new Traversal(MemoryImage.pack(bvh, scene, fp)).traceAll(rays, stats = full)
      val h1 = new Traversal(MemoryImage.pack(bvh, scene, fp.copy(shortStack = ring))).traceAll(rays, stats = short)
      def bits(f: Float) = java.lang.Float.floatToRawIntBits(f)
      for (i <- 0 until rays.count)
        assert(h0.prim(i) == h1.prim(i) && bits(h0.t(i)) == bits(h1.t(i)) && bits(h0.u(i)) == bits(h1.u(i)) && bits(h0.v(i)) == bits(h1.v(i)),
          s"M=$m ring=$ring ray $i: full ${h0.prim(i)} ${h0.t(i)} vs short ${h1.prim(i)} ${h1.t(i)}")
      assert(short.overflows == 0 && short.nodeFetches >= full.nodeFetches && short.primTests >= full.primTests)
      if (ring == 1) assert(short.restarts > 0, s"M=$m: a one-entry ring must restart")
    }
  }

  test("step limit: a ray that needs more than MAX_STEPS fetches ends with its first MAX_STEPS and prim -4; the others are unchanged; no ray reaches the default") {
    val s = TestScenes.soup(61, 1500); val rays = TestScenes.rays(62, 300)
    val p = PlatformParams(m = 4, mppl = 2); val bvh = Mbvh.build(s, p)
    def bits(f: Float) = java.lang.Float.floatToRawIntBits(f)
    for (ring <- Seq(0, 2)) {
      val fp = Fit.fitTo(p, bvh).copy(shortStack = ring)
      def run(q: PlatformParams) = {
        val acc = IndexedSeq.fill(rays.count)(scala.collection.mutable.ArrayBuffer[(Int, Int)]())
        val sink = new AccessSink {
          def node(ray: Int, id: Int, level: Int): Unit = acc(ray) += (0 -> id)
          def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = acc(ray) += (1 -> firstPrim)
        }
        val st = new RayStats
        (new Traversal(MemoryImage.pack(bvh, s, q)).traceAll(rays, sink, st), acc, st)
      }
      val (h0, a0, st0) = run(fp)
      val need = a0.map(_.length)
      // the default bound: above every ray's need (for the full stack, nodes + leaves bounds it already)
      assert(st0.stepLimits == 0 && need.max < fp.stepBound, s"ring $ring: a ray needs ${need.max}, the default is ${fp.stepBound}")
      if (ring == 0) assert(need.max <= bvh.numNodes + bvh.numLeaves && fp.stepBound >= bvh.numNodes + bvh.numLeaves)
      val limit = need.sorted.apply(need.length / 2)
      val (h1, a1, st1) = run(fp.copy(maxSteps = Some(limit)))
      for (i <- 0 until rays.count)
        if (need(i) > limit) {
          assert(a1(i) == a0(i).take(limit) && h1.prim(i) == Hits.StepLimit && h1.t(i).isPosInfinity && h1.u(i) == 0f && h1.v(i) == 0f, s"ring $ring ray $i")
          assert(st1.stepLimitRays(i))
        } else assert(a1(i) == a0(i) && h1.prim(i) == h0.prim(i) && bits(h1.t(i)) == bits(h0.t(i)) && !st1.stepLimitRays(i), s"ring $ring ray $i")
      assert(st1.stepLimits == need.count(_ > limit) && st1.stepLimits > 0)
      val (h2, _, st2) = run(fp.copy(maxSteps = Some(0))) // no limit
      assert(st2.stepLimits == 0 && (0 until rays.count).forall(i => h2.prim(i) == h0.prim(i) && bits(h2.t(i)) == bits(h0.t(i))))
    }
  }
}
