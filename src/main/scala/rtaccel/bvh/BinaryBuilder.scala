package rtaccel.bvh

import rtaccel.scene.Scene

/** Binary BVH produced by the binned SAH builder; collapsed into an M-wide tree afterwards. */
private[bvh] sealed trait BNode { def box: Aabb }
private[bvh] final case class BLeaf(box: Aabb, start: Int, count: Int) extends BNode
private[bvh] final case class BInner(box: Aabb, left: BNode, right: BNode) extends BNode

/** Axis-aligned box in float32; min/max of float coordinates are exact, so boxes contain their
  * triangles bit for bit (no rounding outward is needed).
  */
final case class Aabb(min: Array[Float], max: Array[Float]) {
  def area: Double = {
    val dx = max(0).toDouble - min(0); val dy = max(1).toDouble - min(1); val dz = max(2).toDouble - min(2)
    if (dx < 0) 0.0 else 2.0 * (dx * dy + dy * dz + dz * dx)
  }
  def contains(o: Aabb): Boolean = (0 until 3).forall(a => min(a) <= o.min(a) && o.max(a) <= max(a))
}

object Aabb {
  def empty: Aabb = Aabb(Array.fill(3)(Float.PositiveInfinity), Array.fill(3)(Float.NegativeInfinity))
  def union(a: Aabb, b: Aabb): Aabb =
    Aabb(Array.tabulate(3)(i => math.min(a.min(i), b.min(i))), Array.tabulate(3)(i => math.max(a.max(i), b.max(i))))
  def ofTriangles(s: Scene, order: Array[Int], start: Int, end: Int): Aabb = {
    val mn = Array.fill(3)(Float.PositiveInfinity); val mx = Array.fill(3)(Float.NegativeInfinity)
    var i = start
    while (i < end) {
      val t = order(i); var k = 0
      while (k < 9) { val a = k % 3; val c = s.coords(9 * t + k); if (c < mn(a)) mn(a) = c; if (c > mx(a)) mx(a) = c; k += 1 }
      i += 1
    }
    Aabb(mn, mx)
  }
}

/** Binned SAH builder with the paper's MPPL rule (Section 5.2): a range of more than MPPL primitives is
  * always split; at or below MPPL the SAH decides between a leaf and a split.
  * Costs are memory traffic, as the paper states (Section 5.1): the node's access size is the traversal cost
  * of a split and a primitive's access size its intersection cost. (Charging only nodeBytes/(M-1) per
  * binary split, the M-wide fetch spread over the splits it replaces, makes the SAH split nearly every
  * leaf down to one primitive, and MPPL stops mattering: unlike the paper's Fig 4.)
  */
private[bvh] final class BinaryBuilder(s: Scene, mppl: Int, bins: Int, nodeCost: Double, primCost: Double) {
  val order: Array[Int] = Array.tabulate(s.triangles)(identity)
  private val cent: Array[Float] = Array.tabulate(s.triangles * 3) { k =>
    val t = k / 3; val a = k % 3
    ((s.v(t, 0, a).toDouble + s.v(t, 1, a) + s.v(t, 2, a)) / 3.0).toFloat
  }
  private val tmn: Array[Float] = Array.tabulate(s.triangles * 3)(k => math.min(math.min(s.v(k / 3, 0, k % 3), s.v(k / 3, 1, k % 3)), s.v(k / 3, 2, k % 3)))
  private val tmx: Array[Float] = Array.tabulate(s.triangles * 3)(k => math.max(math.max(s.v(k / 3, 0, k % 3), s.v(k / 3, 1, k % 3)), s.v(k / 3, 2, k % 3)))

  def build(): BNode = build(0, s.triangles)

  private def build(start: Int, end: Int): BNode = {
    val n = end - start
    val box = Aabb.ofTriangles(s, order, start, end)
    if (n == 1) return BLeaf(box, start, 1)
    val (cmin, cmax) = centroidBounds(start, end)
    var bestCost = Double.PositiveInfinity; var bestAxis = -1; var bestPlane = -1
    val area = math.max(box.area, Double.MinPositiveValue)
    for (axis <- 0 until 3 if cmax(axis) > cmin(axis)) {
      // Per-bin counts and bounds in flat arrays: this loop runs for every primitive on every level.
      val cnt = new Array[Int](bins)
      val bmn = Array.fill(bins * 3)(Float.PositiveInfinity); val bmx = Array.fill(bins * 3)(Float.NegativeInfinity)
      var i = start
      while (i < end) {
        val t = order(i); val b = binOf(t, axis, cmin(axis), cmax(axis)); cnt(b) += 1
        var a = 0
        while (a < 3) {
          if (tmn(3 * t + a) < bmn(3 * b + a)) bmn(3 * b + a) = tmn(3 * t + a)
          if (tmx(3 * t + a) > bmx(3 * b + a)) bmx(3 * b + a) = tmx(3 * t + a)
          a += 1
        }
        i += 1
      }
      def binBox(b: Int) = Aabb(Array(bmn(3 * b), bmn(3 * b + 1), bmn(3 * b + 2)), Array(bmx(3 * b), bmx(3 * b + 1), bmx(3 * b + 2)))
      // Sweep from the right to get suffix areas, then from the left to evaluate each plane.
      val rArea = new Array[Double](bins); val rCnt = new Array[Int](bins)
      var acc = Aabb.empty; var c = 0
      for (b <- bins - 1 to 1 by -1) { acc = Aabb.union(acc, binBox(b)); c += cnt(b); rArea(b) = acc.area; rCnt(b) = c }
      acc = Aabb.empty; c = 0
      for (b <- 0 until bins - 1) {
        acc = Aabb.union(acc, binBox(b)); c += cnt(b)
        if (c > 0 && rCnt(b + 1) > 0) {
          val cost = nodeCost + primCost * (acc.area * c + rArea(b + 1) * rCnt(b + 1)) / area
          if (cost < bestCost) { bestCost = cost; bestAxis = axis; bestPlane = b }
        }
      }
    }
    if (n <= mppl && n * primCost <= bestCost) return BLeaf(box, start, n)
    val mid =
      if (bestAxis < 0) {
        if (n <= mppl) return BLeaf(box, start, n)
        start + n / 2 // all centroids coincide: split the index range in half
      } else partition(start, end, bestAxis, bestPlane, cmin(bestAxis), cmax(bestAxis))
    BInner(box, build(start, mid), build(mid, end))
  }

  private def binOf(t: Int, axis: Int, lo: Float, hi: Float): Int = {
    val b = ((cent(3 * t + axis).toDouble - lo) / (hi.toDouble - lo) * bins).toInt
    math.max(0, math.min(bins - 1, b))
  }

  private def centroidBounds(start: Int, end: Int): (Array[Float], Array[Float]) = {
    val mn = Array.fill(3)(Float.PositiveInfinity); val mx = Array.fill(3)(Float.NegativeInfinity)
    for (i <- start until end; a <- 0 until 3) {
      val c = cent(3 * order(i) + a); if (c < mn(a)) mn(a) = c; if (c > mx(a)) mx(a) = c
    }
    (mn, mx)
  }

  /** In-place partition of order(start until end) by bin; returns the first index of the right side. */
  private def partition(start: Int, end: Int, axis: Int, plane: Int, lo: Float, hi: Float): Int = {
    var i = start; var j = end - 1
    while (i <= j) {
      if (binOf(order(i), axis, lo, hi) <= plane) i += 1
      else { val tmp = order(i); order(i) = order(j); order(j) = tmp; j -= 1 }
    }
    i
  }
}
