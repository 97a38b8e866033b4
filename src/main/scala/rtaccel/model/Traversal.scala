package rtaccel.model

import rtaccel.bvh.MemoryImage
import rtaccel.scene.{Hits, Rays}

/** Per-ray counters a traversal unit would keep. */
final class RayStats {
  var nodeFetches = 0L; var leafFetches = 0L; var primTests = 0L; var boxTests = 0L
  var maxStack = 0; var overflows = 0; var readErrors = 0; var restarts = 0L
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
  */
final class Traversal(img: MemoryImage, faults: MemFaults = MemFaults.none) {
  private val p = img.p
  private val m = p.m
  private val codec = img.codec
  private val sRef = new Array[Int](p.stackDepth); private val sT = new Array[Float](p.stackDepth)
  private val sLvl = new Array[Int](p.stackDepth)
  private val cRef = new Array[Int](m); private val cT = new Array[Float](m)
  private val tri = new RayTriangle.Result
  private var slot = 0
  // BOX_FORMAT narrower than fp32: the hardware's outward-rounded slab test (null: the fp32 test)
  private val outward = if (p.boxFormat == rtaccel.fp.FpFormat.fp32) null else new RayBoxOutward(p.boxFormat, p.boxSlackUlps)
  private val coord: Int => Float = k => img.primCoord(slot, k)
  // TRI_TEST=watertight: the sheared-edge test (null: Möller–Trumbore)
  private val slack = p.boxSlackUlps
  private val watertight = if (p.triTest == rtaccel.config.TriTest.Watertight) new RayTriangleWatertight else null

  def traceAll(rays: Rays, sink: AccessSink = AccessSink.none, stats: RayStats = new RayStats): Hits = {
    val h = Hits.empty(rays.count)
    for (i <- 0 until rays.count) trace(i, rays, h, sink, stats)
    h
  }

  /** Traces ray i with the configured stack: the full stack, or the short stack with restart. */
  def trace(i: Int, rays: Rays, out: Hits, sink: AccessSink, st: RayStats): Unit =
    if (p.shortStack > 0) traceShort(i, rays, out, sink, st) else traceFull(i, rays, out, sink, st)

  // Short stack with restart (docs/architecture.md, "short stack with restart"): a ring of p.shortStack
  // entries that overwrites its oldest entry, and a trail of finished children per level. A push never fails;
  // when the ring runs dry after it dropped entries, traversal restarts at the root and follows the trail.
  private val ringRef = new Array[Int](math.max(1, p.shortStack)); private val ringT = new Array[Float](math.max(1, p.shortStack))
  private val ringLvl = new Array[Int](math.max(1, p.shortStack))
  private var trail = new Array[Int](64)

  private def traceShort(i: Int, rays: Rays, out: Hits, sink: AccessSink, st: RayStats): Unit = {
    val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
    val cap = p.shortStack
    var tmax = r.tmax
    leaf.reset()
    var n = 0; var head = 0 // entries in the ring; head = slot of the next push
    var dropped = false
    java.util.Arrays.fill(trail, 0)
    def finished(level: Int): Unit = { // the path's node at `level` is done
      if (level >= 1) trail(level - 1) += 1
      var l = level; while (l < trail.length) { trail(l) = 0; l += 1 }
    }
    var cur = 0; var curLevel = 0; var running = true; var readError = false
    while (running) {
      if (curLevel + 1 >= trail.length) trail = java.util.Arrays.copyOf(trail, trail.length * 2)
      var descended = false
      if (!codec.isPrim(cur)) {
        val id = codec.nodeId(cur)
        sink.node(i, id, curLevel); st.nodeFetches += 1
        val bad = faults.nodeBad(id) // as the full stack: no child of a poisoned node is trusted
        if (bad) readError = true
        val k = if (bad) 0 else hitChildren(r, tmax, id, st)
        val skip = trail(curLevel) // children finished on earlier passes (0 on a first visit)
        if (skip < k) {
          var q = k - 1
          while (q > skip) { // far first, as the full stack
            ringRef(head) = cRef(q); ringT(head) = cT(q); ringLvl(head) = curLevel + 1
            head = (head + 1) % cap
            if (n == cap) dropped = true else n += 1
            q -= 1
          }
          if (n > st.maxStack) st.maxStack = n
          cur = cRef(skip); curLevel += 1; descended = true
        } // else: every hit child is finished, so is this node (below: pop, restart or end)
      } else tmax = testLeaf(i, r, cur, curLevel, tmax, sink, st)
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
    record(i, out, st, tmax, overflowed = false, readError || leaf.readError)
  }

  private def traceFull(i: Int, rays: Rays, out: Hits, sink: AccessSink, st: RayStats): Unit = {
    val r = new PreparedRay(rays(i, 0), rays(i, 1), rays(i, 2), rays(i, 3), rays(i, 4), rays(i, 5), rays(i, 6), rays(i, 7))
    var tmax = r.tmax
    leaf.reset()
    var sp = 0
    var overflowed = false; var readError = false
    var cur = 0; var curLevel = 0; var hasCur = true // root node: ref 0 means node id 0
    while (hasCur) {
      if (!codec.isPrim(cur)) {
        val id = codec.nodeId(cur)
        sink.node(i, id, curLevel); st.nodeFetches += 1
        val bad = faults.nodeBad(id) // no child of a poisoned node is trusted
        if (bad) readError = true
        val k = if (bad) 0 else hitChildren(r, tmax, id, st)
        var q = k - 1
        while (q >= 1) {
          if (sp == sRef.length) overflowed = true // dropped, as the TU drops it
          else { sRef(sp) = cRef(q); sT(sp) = cT(q); sLvl(sp) = curLevel + 1; sp += 1 }
          q -= 1
        }
        if (sp > st.maxStack) st.maxStack = sp
        if (k > 0) { cur = cRef(0); curLevel += 1 } else hasCur = false
      } else { tmax = testLeaf(i, r, cur, curLevel, tmax, sink, st); hasCur = false }
      while (!hasCur && sp > 0) {
        sp -= 1
        if (!(sT(sp) > tmax)) { cur = sRef(sp); curLevel = sLvl(sp); hasCur = true }
      }
    }
    record(i, out, st, tmax, overflowed, readError || leaf.readError)
  }

  /** Writes ray i's hit record: a fault record (a read error wins over an overflow), the closest hit, or a miss. */
  private def record(i: Int, out: Hits, st: RayStats, tmax: Float, overflowed: Boolean, readError: Boolean): Unit = {
    if (overflowed) st.overflows += 1
    if (readError) st.readErrors += 1
    if (readError || overflowed) {
      out.t(i) = Float.PositiveInfinity; out.prim(i) = if (readError) Hits.ReadError else Hits.Overflow; out.u(i) = 0f; out.v(i) = 0f
    }
    else if (leaf.prim >= 0) { out.t(i) = tmax; out.prim(i) = leaf.prim; out.u(i) = leaf.u; out.v(i) = leaf.v }
  }

  /** The closest hit found so far in the current ray's leaves, and whether a primitive read failed. */
  private object leaf {
    var prim = -1; var u = 0f; var v = 0f; var readError = false
    def reset(): Unit = { prim = -1; u = 0f; v = 0f; readError = false }
  }

  /** Tests the primitives of leaf `ref` in slot order against [tmin, tmax); a hit closer than tmax becomes
    * `leaf`'s closest (an equal t keeps the earlier one); a poisoned primitive is not hit and flags the ray.
    * Returns the new tmax.
    */
  private def testLeaf(i: Int, r: PreparedRay, ref: Int, level: Int, tmax0: Float, sink: AccessSink, st: RayStats): Float = {
    val first = codec.firstPrim(ref); val n = codec.count(ref)
    sink.leaf(i, first, n, level); st.leafFetches += 1; st.primBytes += p.leafBytes(n)
    var tmax = tmax0
    var s = first
    while (s < first + n) {
      slot = s; st.primTests += 1
      if (faults.primBad(s)) leaf.readError = true
      else if (if (watertight == null) RayTriangle.test(r, tmax, coord, tri) else watertight.test(r, tmax, coord, tri)) { tmax = tri.t; leaf.prim = img.primId(s); leaf.u = tri.u; leaf.v = tri.v }
      s += 1
    }
    tmax
  }

  /** Slab-tests the non-empty children of node `id` and leaves the hit ones in cRef/cT sorted by entry
    * distance (stable: equal distances keep slot order); returns how many hit.
    */
  private def hitChildren(r: PreparedRay, tmax: Float, id: Int, st: RayStats): Int = {
    var k = 0; var j = 0
    while (j < m) {
      val ref = img.childRef(id, j)
      if (!codec.isEmpty(ref)) {
        st.boxTests += 1
        val tn = if (outward == null) RayBox.test(r, tmax, box(id, j, 0), box(id, j, 1), box(id, j, 2), box(id, j, 3), box(id, j, 4), box(id, j, 5), slack)
          else outward.test(r, tmax, box(id, j, 0), box(id, j, 1), box(id, j, 2), box(id, j, 3), box(id, j, 4), box(id, j, 5))
        if (!tn.isNaN) {
          var pos = k
          while (pos > 0 && cT(pos - 1) > tn) { cRef(pos) = cRef(pos - 1); cT(pos) = cT(pos - 1); pos -= 1 }
          cRef(pos) = ref; cT(pos) = tn; k += 1
        }
      }
      j += 1
    }
    k
  }

  @inline private def box(id: Int, j: Int, q: Int): Float = java.lang.Float.intBitsToFloat(img.childWord(id, j, q))
}
