package rtaccel.model

import scala.collection.mutable.ArrayBuffer
import scala.util.Random
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.bvh.{Child, MemoryImage, Mbvh}
import rtaccel.config.{Fit, PlatformParams}
import rtaccel.fp.FpFormat
import rtaccel.scene.{Hits, Rays, Scene}

/** The traversal order of Traversal's doc comment, written as plainly as possible on the tree (Mbvh) rather
  * than on the packed memory image, with Scala collections, the exact box test (RayBox.test or RayBoxOutward)
  * and the closure form of the triangle test: the independent answer the optimized Traversal must give bit
  * for bit (hits, access trace and counters).
  */
object ReferenceTraversal {
  final case class Out(hits: Hits, rows: Array[Int], counts: Seq[Long])

  def trace(bvh: Mbvh, scene: Scene, p: PlatformParams, rays: Rays, faults: MemFaults): Out = {
    val h = Hits.empty(rays.count); val rows = ArrayBuffer[Int]()
    var nodeFetches, leafFetches, primTests, boxTests, overflows, readErrors = 0L; var maxStack = 0
    val outward = if (p.boxFormat == FpFormat.fp32) None else Some(new RayBoxOutward(p.boxFormat))
    val tri = new RayTriangle.Result
    for (i <- 0 until rays.count) {
      val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
      var tmax = r.tmax; var best: Option[(Int, Float, Float)] = None
      var overflow = false; var readError = false
      val stack = scala.collection.mutable.Stack[(Child, Float, Int)]() // child, entry distance, level
      // the current reference: Left(node id) or Right(leaf child), with its level
      var cur: Option[(Either[Int, Child], Int)] = Some((Left(0), 0))
      while (cur.isDefined) {
        val (ref, level) = cur.get; cur = None
        ref match {
          case Left(id) =>
            rows ++= Seq(i, 0, id, level, 0); nodeFetches += 1
            val kids = if (faults.nodeBad(id)) { readError = true; Seq() } else bvh.nodes(id).children
            boxTests += kids.length
            val hit = kids.map { c =>
              val (lo, hi) = (c.box.min, c.box.max)
              (c, outward.fold(RayBox.test(r, tmax, lo(0), lo(1), lo(2), hi(0), hi(1), hi(2)))(_.test(r, tmax, lo(0), lo(1), lo(2), hi(0), hi(1), hi(2))))
            }.filterNot(_._2.isNaN).sortWith(_._2 < _._2) // stable: equal distances keep slot order
            for ((c, t) <- hit.drop(1).reverse) // far first, so that the nearer ones pop first
              if (stack.length == p.stackDepth) overflow = true else stack.push((c, t, level + 1))
            maxStack = math.max(maxStack, stack.length)
            cur = hit.headOption.map { case (c, _) => (if (c.isLeaf) Right(c) else Left(c.node), level + 1) }
          case Right(leaf) =>
            rows ++= Seq(i, 1, leaf.firstPrim, level, leaf.count); leafFetches += 1
            for (s <- leaf.firstPrim until leaf.firstPrim + leaf.count) {
              primTests += 1
              val t = bvh.primOrder(s)
              if (faults.primBad(s)) readError = true
              else if (RayTriangle.test(r, tmax, (k: Int) => scene.coords(9 * t + k), tri)) { tmax = tri.t; best = Some((t, tri.u, tri.v)) }
            }
        }
        while (cur.isEmpty && stack.nonEmpty) {
          val (c, t, l) = stack.pop()
          if (!(t > tmax)) cur = Some((if (c.isLeaf) Right(c) else Left(c.node), l))
        }
      }
      if (overflow) overflows += 1
      if (readError) readErrors += 1
      if (readError || overflow) { h.t(i) = Float.PositiveInfinity; h.prim(i) = if (readError) Hits.ReadError else Hits.Overflow; h.u(i) = 0f; h.v(i) = 0f }
      else best.foreach { case (t, u, v) => h.t(i) = tmax; h.prim(i) = t; h.u(i) = u; h.v(i) = v }
    }
    Out(h, rows.toArray, Seq(nodeFetches, leafFetches, primTests, boxTests, overflows, readErrors, maxStack.toLong))
  }
}

class TraversalReferenceSpec extends AnyFunSuite {
  private def bits(f: Float) = java.lang.Float.floatToRawIntBits(f)

  /** A lattice scene: small triangles with integer vertex coordinates, so that box planes coincide with the
    * integer ray origins below (slab distances of exactly ±0, ties between children).
    */
  private def lattice(seed: Long, n: Int): Scene = {
    val rnd = new Random(seed)
    Scene(s"lattice$seed", Array.fill(n)(Array.fill(3)(rnd.nextInt(8).toFloat)).flatMap { c =>
      Array.tabulate(9)(k => c(k % 3) + (if (k / 3 == k % 3 || rnd.nextInt(4) == 0) 1f else 0f))
    })
  }

  /** Random rays, a share of them with edge-case values: integer origins on box planes, zero and -0
    * direction components (an infinite reciprocal: the general box test), tmin of -0, +0 and 1, a NaN tmin.
    */
  private def rays(seed: Long, n: Int): Rays = {
    val base = TestScenes.rays(seed, n, -1f, 9f); val rnd = new Random(seed + 7)
    val d = base.data.clone
    for (i <- 0 until n) rnd.nextInt(6) match {
      case 0 => for (k <- 0 until 3) d(8 * i + k) = rnd.nextInt(9).toFloat
      case 1 => d(8 * i + 3 + rnd.nextInt(3)) = if (rnd.nextBoolean()) 0f else -0f
      case 2 => d(8 * i + 6) = Seq(-0f, 0f, 1f)(rnd.nextInt(3))
      case 3 => d(8 * i + 6) = Float.NaN
      case _ =>
    }
    Rays(d)
  }

  private def check(name: String, scene: Scene, ry: Rays, p0: PlatformParams, stack: Option[Int] = None,
                    faultThreshold: Int = 0, nanInEmptySlot: Boolean = false, swappedPlanes: Boolean = false): Unit = {
    val bvh = Mbvh.build(scene, p0)
    val p = stack.fold(Fit.fitTo(p0, bvh))(s => Fit.fitTo(p0, bvh).copy(stackDepth = s))
    val img0 = MemoryImage.pack(bvh, scene, p)
    val img = if (nanInEmptySlot) {
      // a NaN in the box words of an empty child slot: never tested, but it turns the fast box test off
      val n = bvh.nodes.find(_.children.length < p.m).getOrElse(cancel(s"$name: no node with an empty slot"))
      val nodes = img0.nodes.clone; nodes(n.id * img0.nodeWords + 7 * n.children.length) = java.lang.Float.floatToRawIntBits(Float.NaN)
      img0.copy(nodes = nodes)
    } else if (swappedPlanes) {
      // the root's first child with min and max swapped on an axis where they differ: the slab test takes the
      // min and max of the two planes, so it sees the same box as the reference's, but a box with min > max must
      // keep every ray off the ordered test (which takes the near plane from the ray's direction alone)
      val w = 0 // the root is node 0 (Mbvh: breadth-first ids)
      val f = (k: Int) => java.lang.Float.intBitsToFloat(img0.nodes(w + k))
      val axis = (0 until 3).find(a => f(a) < f(a + 3)).getOrElse(cancel(s"$name: the root's first child is flat"))
      val nodes = img0.nodes.clone; nodes(w + axis) = img0.nodes(w + axis + 3); nodes(w + axis + 3) = img0.nodes(w + axis)
      img0.copy(nodes = nodes)
    } else img0
    val faults = if (faultThreshold == 0) MemFaults.none
      else MemFaults(faultThreshold, 5, 32, p.nodeStrideBytes, img.nodes.length * 4L, p.primStrideBytes)
    val rec = new AccessRecorder; val st = new RayStats
    val got = new Traversal(img, faults).traceAll(ry, rec, st)
    val want = ReferenceTraversal.trace(bvh, scene, p, ry, faults)
    for (i <- 0 until ry.count)
      assert(got.prim(i) == want.hits.prim(i) && bits(got.t(i)) == bits(want.hits.t(i)) && bits(got.u(i)) == bits(want.hits.u(i)) &&
        bits(got.v(i)) == bits(want.hits.v(i)), s"$name ray $i: ${got.prim(i)} ${got.t(i)} vs reference ${want.hits.prim(i)} ${want.hits.t(i)}")
    val rows = rec.toArray
    val firstDiff = rows.indices.find(k => k >= want.rows.length || rows(k) != want.rows(k))
    assert(rows.length == want.rows.length && firstDiff.isEmpty,
      s"$name: access traces differ (${rows.length / 5} vs ${want.rows.length / 5} rows, first at row ${firstDiff.map(_ / 5)})")
    assert(Seq(st.nodeFetches, st.leafFetches, st.primTests, st.boxTests, st.overflows.toLong, st.readErrors.toLong, st.maxStack.toLong) == want.counts,
      s"$name: counters (node, leaf, prim, box fetches/tests, overflows, read errors, max stack)")
    if (faultThreshold > 0) assert(want.counts(5) > 0, s"$name: no ray met a poisoned beat; raise the threshold")
    if (stack.isDefined) assert(want.counts(4) > 0, s"$name: no ray overflowed")
  }

  private val scenes = Seq(("soup", TestScenes.soup(61, 1500), rays(62, 800)), ("lattice", lattice(63, 600), rays(64, 800)))

  for ((name, scene, ry) <- scenes; (m, mppl) <- Seq((2, 1), (4, 4), (8, 16)))
    test(s"optimized traversal == reference traversal bit for bit (hits, access trace, counters): $name, M=$m MPPL=$mppl") {
      check(s"$name M=$m", scene, ry, PlatformParams(m = m, mppl = mppl))
    }

  for ((name, scene, ry) <- scenes)
    test(s"optimized traversal == reference under stack overflow, poisoned memory, bf16 boxes, a NaN box word and a box with min > max: $name") {
      val p = PlatformParams(m = 4, mppl = 4)
      check(s"$name stack=2", scene, ry, p, stack = Some(2))
      check(s"$name faults", scene, ry, p, faultThreshold = 3000)
      check(s"$name bf16", scene, ry, p.copy(boxFormat = FpFormat.parse("bf16")))
      check(s"$name NaN word", scene, ry, p, nanInEmptySlot = true)
      check(s"$name min > max", scene, ry, p, swappedPlanes = true)
    }

  test("RayBox.testRegular == RayBox.test bit for bit on regular rays (ties, zeros of both signs, infinities)") {
    val rnd = new Random(71)
    val special = Array(0f, -0f, 1f, -1f, 2f, Float.PositiveInfinity, Float.NegativeInfinity, Float.MinPositiveValue, -Float.MinPositiveValue, Float.MaxValue)
    def v(): Float = if (rnd.nextInt(3) == 0) special(rnd.nextInt(special.length)) else (rnd.nextInt(9) - 4).toFloat * (if (rnd.nextBoolean()) 1f else rnd.nextFloat())
    var tested, zeros = 0
    while (tested < 200000) {
      val r = new PreparedRay(rnd.nextInt(5) - 2f, rnd.nextInt(5) - 2f, if (rnd.nextBoolean()) 0f else -0f, v(), v(), v(),
        Seq(0f, -0f, 1f, v())(rnd.nextInt(4)), Seq(Float.PositiveInfinity, 0f, -0f, 3f, v())(rnd.nextInt(5)))
      val b = Array.fill(6)(v())
      if (r.regular) {
        val tmax = if (rnd.nextBoolean()) r.tmax else v()
        val want = RayBox.test(r, tmax, b(0), b(1), b(2), b(3), b(4), b(5))
        val got = RayBox.testRegular(r, tmax, b(0), b(1), b(2), b(3), b(4), b(5))
        assert(bits(got) == bits(want) || (got.isNaN && want.isNaN), s"ray (${r.ox}, ${r.oy}, ${r.oz}) dir (${r.dx}, ${r.dy}, ${r.dz}) " +
          s"[${r.tmin}, $tmax] box ${b.mkString(", ")}: $got vs $want")
        if (want == 0f) zeros += 1
        tested += 1
      }
    }
    assert(zeros > 1000, s"only $zeros zero entry distances: the sign-of-zero path is not exercised")
  }

  test("PreparedRay: regular only with a finite origin, finite nonzero reciprocals and no NaN bound; set == new") {
    assert(new PreparedRay(0f, 0f, 0f, 1f, -2f, 3f, 0f, Float.PositiveInfinity).regular)
    for (bad <- Seq(new PreparedRay(0f, 0f, 0f, 0f, 1f, 1f, 0f, 1f), new PreparedRay(0f, 0f, 0f, 1f, -0f, 1f, 0f, 1f),
      new PreparedRay(0f, 0f, 0f, 1f, 1f, Float.PositiveInfinity, 0f, 1f), new PreparedRay(Float.NegativeInfinity, 0f, 0f, 1f, 1f, 1f, 0f, 1f),
      new PreparedRay(0f, 0f, 0f, 1f, 1f, 1e-40f, 0f, 1f), new PreparedRay(0f, 0f, 0f, 1f, 1f, 1f, Float.NaN, 1f),
      new PreparedRay(0f, 0f, 0f, 1f, 1f, 1f, 0f, Float.NaN), new PreparedRay(0f, Float.NaN, 0f, 1f, 1f, 1f, 0f, 1f)))
      assert(!bad.regular, s"(${bad.ox}, ${bad.oy}, ${bad.oz}) (${bad.dx}, ${bad.dy}, ${bad.dz}) [${bad.tmin}, ${bad.tmax}]")
    val ry = rays(81, 50); val reused = new PreparedRay(0f, 0f, 0f, 1f, 1f, 1f, 0f, 0f)
    for (i <- 0 until ry.count) {
      val fresh = new PreparedRay(ry(i, 0), ry(i, 1), ry(i, 2), ry(i, 3), ry(i, 4), ry(i, 5), ry(i, 6), ry(i, 7))
      reused.set(ry.data, i)
      assert(Seq(reused.ox, reused.oy, reused.oz, reused.dx, reused.dy, reused.dz, reused.tmin, reused.tmax, reused.ix, reused.iy, reused.iz).map(bits) ==
        Seq(fresh.ox, fresh.oy, fresh.oz, fresh.dx, fresh.dy, fresh.dz, fresh.tmin, fresh.tmax, fresh.ix, fresh.iy, fresh.iz).map(bits), s"ray $i")
    }
  }
}
