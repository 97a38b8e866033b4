package rtaccel.model

import rtaccel.bvh.MemoryImage
import rtaccel.scene.{Hits, Rays}

/** Per-ray counters a traversal unit would keep. */
final class RayStats {
  var nodeFetches = 0L; var leafFetches = 0L; var primTests = 0L; var boxTests = 0L
  var maxStack = 0; var overflows = 0; var readErrors = 0; var stepLimits = 0; var restarts = 0L
  // which rays carry each fault flag: a ray can carry several, and its record then shows the first of read error,
  // step limit, overflow (Traversal.record)
  val overflowRays = scala.collection.mutable.BitSet(); val readErrorRays = scala.collection.mutable.BitSet()
  val stepLimitRays = scala.collection.mutable.BitSet()
  var primBytes = 0L // DRAM bytes of the leaves fetched (PlatformParams.leafBytes)
}

/** Reference traversal of one TU over the packed memory image (paper Section 2), defining the order the
  * hardware must follow bit for bit:
  *  - start with the root (node 0) as the current reference;
  *  - node: fetch it, slab-test every non-empty child against [tmin, tmax] (tmax = closest hit so far),
  *    sort hit children by entry distance (stable by slot), make the nearest current and push the others
  *    far-first so the nearer ones pop first;
  *  - leaf: fetch its primitives and test them in slot order; a hit with t < tmax becomes the closest hit
  *    (ties keep the earlier one);
  *  - pop: discard an entry whose entry distance exceeds tmax; done when the stack is empty.
  * Stack overflow, the one semantic shared with the TU (docs/architecture.md): a push onto a full stack
  * (params.stackDepth entries) is dropped, the ray is flagged and traversal carries on, so that the
  * accesses stay identical to the hardware's; the flagged ray's hit record is `Hits.Overflow` (prim -3,
  * t = +inf, u = v = 0), never a plausible wrong hit.
  * Step limit (docs/architecture.md, "Step limit"): a step is one fetch, node or leaf, counted as the TU counts its
  * requests; a ray that has made params.stepLimit fetches (0: no limit) and needs another stops there, unfetched,
  * and its record is `Hits.StepLimit` (prim -4): a loop through a corrupted image ends. With the short stack a node
  * deeper than the trail's treeLevels levels ends the ray the same way.
  */
final class Traversal(img: MemoryImage, faults: MemFaults = MemFaults.none) {
  // The hot loop reads the image's word arrays directly and keeps its state in private[this] fields and
  // locals: no allocation and no closure per ray, node or primitive (docs/architecture.md, "reference model speed").
  private[this] val p = img.p
  private[this] val m = p.m
  private[this] val codec = img.codec
  private[this] val nodes = img.planes; private[this] val nodeWords = img.planeWords // full layout (decoded for q<k>)
  private[this] val prims = img.prims
  // record k of the leaf whose first field is f: word f * firstWords + k * recordWords (slot64 or packed rows)
  private[this] val firstWords = img.firstWords; private[this] val recordWords = img.recordWords
  private[this] val faulty = faults.enabled
  private[this] val stepLimit = p.stepLimit // 0: no limit
  private[this] val sRef = new Array[Int](p.stackDepth); private[this] val sT = new Array[Float](p.stackDepth)
  private[this] val sLvl = new Array[Int](p.stackDepth)
  private[this] val cRef = new Array[Int](m); private[this] val cT = new Array[Float](m)
  private[this] val tri = new RayTriangle.Result
  private[this] val r = new PreparedRay(0f, 0f, 0f, 1f, 1f, 1f, 0f, 0f) // the current ray, set per ray
  // BOX_FORMAT narrower than fp32: the hardware's outward-rounded slab test (null: the fp32 test)
  private[this] val outward = if (p.boxFormat == rtaccel.fp.FpFormat.fp32) null else new RayBoxOutward(p.boxFormat, p.boxSlackUlps)
  // fp32 boxes without a NaN word and without slack: a regular ray can take RayBox.testRegular (the same result, bit for bit)
  private[this] val slack = p.boxSlackUlps // TRI_TEST=watertight widens every box (RayBox.test's slack)
  private[this] val nanFreeBoxes = outward == null && slack == 0 && {
    var ok = true; var w = 0
    while (ok && w < nodes.length) { // box words only: child j's min, max at 7j .. 7j+5 (a ref may look like a NaN)
      val q = w % nodeWords
      if (q < 7 * m && q % 7 != 6) ok = !f(nodes(w)).isNaN
      w += 1
    }
    ok
  }
  // ... and every non-empty child's box has min <= max on each axis: then a regular ray takes hitChildrenOrdered
  private[this] val orderedBoxes = nanFreeBoxes && {
    var ok = true; var w = 0
    while (ok && w < nodes.length) { // child j's min words 7j .. 7j+2, each against its max 3 words on
      val q = w % nodeWords
      if (q < 7 * m && q % 7 < 3 && !codec.isEmpty(nodes(w - q % 7 + 6))) ok = f(nodes(w)) <= f(nodes(w + 3))
      w += 1
    }
    ok
  }
  private[this] var regular = false // the current ray takes the fast box test
  private[this] var ordered = false // ... and the ordered one (regular on orderedBoxes)
  // the near plane of each axis for the current ray: word 0 (min) when the reciprocal direction is positive, else 3 (max)
  private[this] var nearX = 0; private[this] var nearY = 0; private[this] var nearZ = 0
  // the current ray's counters, added to the caller's RayStats when the ray is done (record)
  private[this] var nodeFetches = 0L; private[this] var leafFetches = 0L; private[this] var primTests = 0L
  private[this] var boxTests = 0L; private[this] var maxStack = 0
  private[this] var primBytes = 0L // DRAM bytes of the leaves fetched (PlatformParams.leafBytes)
  // the closest hit found so far in the current ray's leaves, and whether a primitive read failed
  // (whether there is one is a flag of its own: the id is the record's word as memory holds it, and a corrupted image
  // may hold a negative one, which the TU returns as it reads it)
  private[this] var hasHit = false
  private[this] var hitPrim = -1; private[this] var hitU = 0f; private[this] var hitV = 0f; private[this] var primError = false
  // TRI_TEST=watertight: the sheared-edge test (null: Möller–Trumbore)
  private[this] val watertight = if (p.triTest == rtaccel.config.TriTest.Watertight) new RayTriangleWatertight else null
  // TRI_FORMAT wider than fp32: Möller–Trumbore in that format (null: the fp32 test)
  private[this] val wide = if (p.triFormat == rtaccel.fp.FpFormat.fp32) null else new RayTriangleWide(p.triFormat)

  def traceAll(rays: Rays, sink: AccessSink = AccessSink.none, stats: RayStats = new RayStats): Hits = {
    val h = Hits.empty(rays.count)
    var i = 0
    while (i < rays.count) { trace(i, rays, h, sink, stats); i += 1 }
    h
  }

  /** Traces ray i with the configured stack: the full stack, or the short stack with restart. */
  def trace(i: Int, rays: Rays, out: Hits, sink: AccessSink, st: RayStats): Unit =
    if (p.shortStack > 0) traceShort(i, rays, out, sink, st) else traceFull(i, rays, out, sink, st)

  // Short stack with restart (docs/architecture.md, "short stack with restart"): a ring of p.shortStack
  // entries that overwrites its oldest entry, and a trail of finished children per level. A push never fails;
  // when the ring runs dry after it dropped entries, traversal restarts at the root and follows the trail.
  private[this] val ringRef = new Array[Int](math.max(1, p.shortStack)); private[this] val ringT = new Array[Float](math.max(1, p.shortStack))
  private[this] val ringLvl = new Array[Int](math.max(1, p.shortStack))
  private[this] var trail = new Array[Int](64)

  /** Makes ray i the current ray and clears its counters and closest hit. */
  private def start(i: Int, rays: Rays): Unit = {
    r.set(rays.data, i); regular = nanFreeBoxes && r.regular; ordered = regular && orderedBoxes
    nearX = if (r.ix > 0f) 0 else 3; nearY = if (r.iy > 0f) 0 else 3; nearZ = if (r.iz > 0f) 0 else 3
    nodeFetches = 0L; leafFetches = 0L; primTests = 0L; boxTests = 0L; maxStack = 0; primBytes = 0L
    hasHit = false; hitPrim = -1; hitU = 0f; hitV = 0f; primError = false
  }

  private def traceShort(i: Int, rays: Rays, out: Hits, sink: AccessSink, st: RayStats): Unit = {
    start(i, rays)
    val cap = p.shortStack
    var tmax = r.tmax
    var n = 0; var head = 0 // entries in the ring; head = slot of the next push
    var dropped = false
    java.util.Arrays.fill(trail, 0)
    def finished(level: Int): Unit = { // the path's node at `level` is done
      if (level >= 1) trail(level - 1) += 1
      var l = level; while (l < trail.length) { trail(l) = 0; l += 1 }
    }
    var cur = 0; var curLevel = 0; var running = true; var readError = false; var limited = false
    while (running) {
      if (curLevel + 1 >= trail.length) trail = java.util.Arrays.copyOf(trail, trail.length * 2)
      var descended = false
      // ends here, unfetched: out of steps, or a node below the trail's treeLevels levels (no tree that fits the trail
      // has one: only a loop through a corrupted image makes it; the TU's trail could not track it)
      if (outOfSteps || (curLevel >= p.treeLevels && !codec.isPrim(cur))) { limited = true; running = false; descended = true }
      else if (!codec.isPrim(cur)) {
        val id = codec.nodeId(cur)
        sink.node(i, id, curLevel); nodeFetches += 1
        val bad = faulty && faults.nodeBad(id) // as the full stack: no child of a poisoned node is trusted
        if (bad) readError = true
        val k = if (bad) 0 else hitChildren(tmax, id)
        val skip = trail(curLevel) // children finished on earlier passes (0 on a first visit)
        if (skip < k) {
          var q = k - 1
          while (q > skip) { // far first, as the full stack
            ringRef(head) = cRef(q); ringT(head) = cT(q); ringLvl(head) = curLevel + 1
            head = (head + 1) % cap
            if (n == cap) dropped = true else n += 1
            q -= 1
          }
          if (n > maxStack) maxStack = n
          cur = cRef(skip); curLevel += 1; descended = true
        } // else: every hit child is finished, so is this node (below: pop, restart or end)
      } else tmax = testLeaf(i, cur, curLevel, tmax, sink)
      if (!descended) {
        // the subtree at curLevel is done: take the next pending sibling (newest first), or restart
        var next = false
        while (!next && n > 0) {
          head = (head - 1 + cap) % cap; n -= 1
          val lvl = ringLvl(head)
          finished(lvl) // popping a sibling at lvl means the path's node at lvl is done
          curLevel = lvl
          if (!(ringT(head) > tmax)) { cur = ringRef(head); next = true }
        }
        if (!next) {
          if (dropped) {
            finished(curLevel); dropped = false
            if (curLevel == 0) running = false // the root itself is done
            else { cur = 0; curLevel = 0; st.restarts += 1 }
          } else running = false // nothing pending and nothing dropped since the last (re)start: done
        }
      }
    }
    record(i, out, st, tmax, overflowed = false, readError || primError, limited)
  }

  /** The current ray has made stepLimit fetches and may make no more. */
  @inline private def outOfSteps: Boolean = stepLimit != 0 && nodeFetches + leafFetches == stepLimit

  private def traceFull(i: Int, rays: Rays, out: Hits, sink: AccessSink, st: RayStats): Unit = {
    start(i, rays)
    var tmax = r.tmax
    var sp = 0
    var overflowed = false; var readError = false; var limited = false
    var cur = 0; var curLevel = 0; var hasCur = true // root node: ref 0 means node id 0
    while (hasCur) {
      if (outOfSteps) { limited = true; hasCur = false; sp = 0 } // ends here, unfetched
      else if (!codec.isPrim(cur)) {
        val id = codec.nodeId(cur)
        sink.node(i, id, curLevel); nodeFetches += 1
        val bad = faulty && faults.nodeBad(id) // no child of a poisoned node is trusted
        if (bad) readError = true
        val k = if (bad) 0 else hitChildren(tmax, id)
        var q = k - 1
        while (q >= 1) {
          if (sp == sRef.length) overflowed = true // dropped, as the TU drops it
          else { sRef(sp) = cRef(q); sT(sp) = cT(q); sLvl(sp) = curLevel + 1; sp += 1 }
          q -= 1
        }
        if (sp > maxStack) maxStack = sp
        if (k > 0) { cur = cRef(0); curLevel += 1 } else hasCur = false
      } else { tmax = testLeaf(i, cur, curLevel, tmax, sink); hasCur = false }
      while (!hasCur && sp > 0) {
        sp -= 1
        if (!(sT(sp) > tmax)) { cur = sRef(sp); curLevel = sLvl(sp); hasCur = true }
      }
    }
    record(i, out, st, tmax, overflowed, readError || primError, limited)
  }

  /** Writes ray i's hit record: a fault record (a read error wins over the step limit, and that over an overflow:
    * a reported memory error is a certain cause, a loop through a corrupted image usually fills the stack too), the
    * closest hit, or a miss; adds the ray's counters to `st`.
    */
  private def record(i: Int, out: Hits, st: RayStats, tmax: Float, overflowed: Boolean, readError: Boolean, limited: Boolean): Unit = {
    st.nodeFetches += nodeFetches; st.leafFetches += leafFetches; st.primTests += primTests; st.boxTests += boxTests; st.primBytes += primBytes
    if (maxStack > st.maxStack) st.maxStack = maxStack
    if (overflowed) { st.overflows += 1; st.overflowRays += i }
    if (readError) { st.readErrors += 1; st.readErrorRays += i }
    if (limited) { st.stepLimits += 1; st.stepLimitRays += i }
    if (readError || limited || overflowed) {
      out.t(i) = Float.PositiveInfinity; out.u(i) = 0f; out.v(i) = 0f
      out.prim(i) = if (readError) Hits.ReadError else if (limited) Hits.StepLimit else Hits.Overflow
    }
    else if (hasHit) { out.t(i) = tmax; out.prim(i) = hitPrim; out.u(i) = hitU; out.v(i) = hitV }
  }

  /** Tests the primitives of leaf `ref` in slot order against [tmin, tmax); a hit closer than tmax becomes
    * the closest (an equal t keeps the earlier one); a poisoned primitive is not hit and flags the ray.
    * Returns the new tmax.
    */
  private def testLeaf(i: Int, ref: Int, level: Int, tmax0: Float, sink: AccessSink): Float = {
    val first = codec.firstPrim(ref); val n = codec.count(ref)
    sink.leaf(i, first, n, level); leafFetches += 1; primTests += n; primBytes += p.leafBytes(n)
    var tmax = tmax0
    var k = 0
    while (k < n) {
      val w = first * firstWords + k * recordWords // v0, v1, v2 as float bits, then the scene triangle id (MemoryImage)
      if (faulty && faults.recordBad(4L * w, img.recordBytes)) primError = true
      else if (if (wide != null) wide.test(r, tmax, f(prims(w)), f(prims(w + 1)), f(prims(w + 2)), f(prims(w + 3)),
            f(prims(w + 4)), f(prims(w + 5)), f(prims(w + 6)), f(prims(w + 7)), f(prims(w + 8)), tri) && tri.t < tmax // the TU's fp32 check
          else if (watertight == null) RayTriangle.test(r, tmax, f(prims(w)), f(prims(w + 1)), f(prims(w + 2)), f(prims(w + 3)),
            f(prims(w + 4)), f(prims(w + 5)), f(prims(w + 6)), f(prims(w + 7)), f(prims(w + 8)), tri)
          else watertight.test(r, tmax, f(prims(w)), f(prims(w + 1)), f(prims(w + 2)), f(prims(w + 3)), f(prims(w + 4)),
            f(prims(w + 5)), f(prims(w + 6)), f(prims(w + 7)), f(prims(w + 8)), tri)) {
        tmax = tri.t; hasHit = true; hitPrim = prims(w + 9); hitU = tri.u; hitV = tri.v
      }
      k += 1
    }
    tmax
  }

  /** Slab-tests the non-empty children of node `id` and leaves the hit ones in cRef/cT sorted by entry
    * distance (stable: equal distances keep slot order); returns how many hit.
    */
  private def hitChildren(tmax: Float, id: Int): Int = if (ordered) hitChildrenOrdered(tmax, id) else {
    var k = 0; var j = 0
    var w = id * nodeWords // child j: min x,y,z, max x,y,z (float bits), ref at w .. w+6 (MemoryImage.planes)
    while (j < m) {
      val ref = nodes(w + 6)
      if (!codec.isEmpty(ref)) {
        boxTests += 1
        val tn = if (regular) RayBox.testRegular(r, tmax, f(nodes(w)), f(nodes(w + 1)), f(nodes(w + 2)), f(nodes(w + 3)), f(nodes(w + 4)), f(nodes(w + 5)))
          else if (outward == null) RayBox.test(r, tmax, f(nodes(w)), f(nodes(w + 1)), f(nodes(w + 2)), f(nodes(w + 3)), f(nodes(w + 4)), f(nodes(w + 5)), slack)
          else outward.test(r, tmax, f(nodes(w)), f(nodes(w + 1)), f(nodes(w + 2)), f(nodes(w + 3)), f(nodes(w + 4)), f(nodes(w + 5)))
        if (!tn.isNaN) { insert(k, ref, tn); k += 1 }
      }
      j += 1; w += 7
    }
    k
  }

  /** hitChildren for a regular ray on orderedBoxes, the same hits in the same order. With no NaN anywhere, a
    * finite nonzero reciprocal direction and min <= max, (min - o) * inv <= (max - o) * inv when inv > 0 and the
    * reverse when inv < 0 (subtraction and multiplication are monotone), so the per-axis min and max of the slab
    * test are the near and the far plane chosen once per ray, and 6 of its 12 min/max go. The remaining min/max
    * are Math.min/max (branch-free; see RayBox.testRegular). tnear then equals RayBox.test's but for the sign
    * of a zero, which nothing observes: the entry distance is only compared (the sort, the pop's cull), and
    * -0 == +0 in every comparison.
    */
  private def hitChildrenOrdered(tmax: Float, id: Int): Int = {
    var k = 0; var j = 0
    val ox = r.ox; val oy = r.oy; val oz = r.oz; val ix = r.ix; val iy = r.iy; val iz = r.iz; val tmin = r.tmin
    val nx = nearX; val ny = nearY; val nz = nearZ
    var w = id * nodeWords
    while (j < m) {
      val ref = nodes(w + 6)
      if (!codec.isEmpty(ref)) {
        boxTests += 1
        val tn = Math.max(Math.max(Math.max(tmin, (f(nodes(w + nx)) - ox) * ix), (f(nodes(w + 1 + ny)) - oy) * iy), (f(nodes(w + 2 + nz)) - oz) * iz)
        val tf = Math.min(Math.min(Math.min(tmax, (f(nodes(w + 3 - nx)) - ox) * ix), (f(nodes(w + 4 - ny)) - oy) * iy), (f(nodes(w + 5 - nz)) - oz) * iz)
        if (tn <= tf) { insert(k, ref, tn); k += 1 }
      }
      j += 1; w += 7
    }
    k
  }

  /** Inserts hit child `ref` at entry distance tn among the k sorted in cRef/cT, after the equal ones (stable). */
  @inline private def insert(k: Int, ref: Int, tn: Float): Unit = {
    var pos = k
    while (pos > 0 && cT(pos - 1) > tn) { cRef(pos) = cRef(pos - 1); cT(pos) = cT(pos - 1); pos -= 1 }
    cRef(pos) = ref; cT(pos) = tn
  }

  @inline private def f(bits: Int): Float = java.lang.Float.intBitsToFloat(bits)
}
