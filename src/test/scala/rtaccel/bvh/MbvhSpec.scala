package rtaccel.bvh

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.config.{Fit, PlatformParams}
import rtaccel.scene.Scene

class MbvhSpec extends AnyFunSuite {
  private def triBox(s: Scene, t: Int) = Aabb(
    Array.tabulate(3)(a => (0 until 3).map(v => s.v(t, v, a)).min), Array.tabulate(3)(a => (0 until 3).map(v => s.v(t, v, a)).max))

  /** All structural invariants of a built and packed tree. */
  def checkInvariants(s: Scene, p: PlatformParams): Unit = {
    val bvh = Mbvh.build(s, p)
    val fp = Fit.fitTo(p, bvh)
    // every primitive exactly once
    assert(bvh.primOrder.sorted.sameElements(0 until s.triangles), "primitive order is not a permutation")
    val leafSlots = bvh.nodes.flatMap(_.children.filter(_.isLeaf)).flatMap(c => c.firstPrim until c.firstPrim + c.count)
    assert(leafSlots.sorted == (0 until s.triangles), "leaves do not cover every slot exactly once")
    for (n <- bvh.nodes) {
      assert(n.children.nonEmpty && n.children.length <= p.m, s"node ${n.id} has ${n.children.length} children")
      for (c <- n.children) {
        if (c.isLeaf) {
          assert(c.count >= 1 && c.count <= p.mppl, s"leaf of ${c.count} > MPPL ${p.mppl}")
          for (slot <- c.firstPrim until c.firstPrim + c.count)
            assert(c.box.contains(triBox(s, bvh.primOrder(slot))), s"leaf box misses triangle ${bvh.primOrder(slot)}")
        } else {
          val k = bvh.nodes(c.node)
          assert(k.level == n.level + 1, s"node ${k.id} level ${k.level} under level ${n.level}")
          assert(c.node > n.id, "breadth-first ids: a child comes after its parent")
          k.children.foreach(g => assert(c.box.contains(g.box), s"child box of node ${n.id} misses a grandchild"))
        }
      }
    }
    assert(bvh.nodes.map(_.level).sliding(2).forall(w => w.length < 2 || w(0) <= w(1)), "ids are not breadth-first")
    // memory image round trip: decode every child slot back to the tree
    val img = MemoryImage.pack(bvh, s, fp)
    assert(img.numNodes == bvh.numNodes && img.numPrims == bvh.numPrims)
    for (n <- bvh.nodes; j <- 0 until p.m) {
      val ref = img.childRef(n.id, j)
      if (j >= n.children.length) assert(img.codec.isEmpty(ref), "unused slot is not empty")
      else {
        val c = n.children(j)
        for (a <- 0 until 3) {
          assert(java.lang.Float.intBitsToFloat(img.childWord(n.id, j, a)) == c.box.min(a))
          assert(java.lang.Float.intBitsToFloat(img.childWord(n.id, j, 3 + a)) == c.box.max(a))
        }
        assert(img.codec.isPrim(ref) == c.isLeaf)
        if (c.isLeaf) { assert(img.codec.firstPrim(ref) == c.firstPrim); assert(img.codec.count(ref) == c.count) }
        else assert(img.codec.nodeId(ref) == c.node)
      }
    }
    for (slot <- 0 until s.triangles; k <- 0 until 9) {
      val t = img.primId(slot)
      assert(t == bvh.primOrder(slot))
      assert(java.lang.Float.floatToRawIntBits(img.primCoord(slot, k)) == java.lang.Float.floatToRawIntBits(s.coords(9 * t + k)))
    }
  }

  for (m <- Seq(2, 4, 8); mppl <- Seq(1, 2, 4, 8, 16))
    test(s"invariants on random soups, M=$m MPPL=$mppl") {
      for (seed <- 1 to 3) checkInvariants(TestScenes.soup(seed, 50 + 97 * seed), PlatformParams(m = m, mppl = mppl))
    }

  for (m <- Seq(2, 4, 8); mppl <- Seq(1, 4, 16))
    test(s"invariants on procedural fixtures, M=$m MPPL=$mppl") {
      val fx = TestScenes.fixtures
      assume(fx.nonEmpty, "procedural fixtures absent: run `make fixtures` (make test does)")
      fx.foreach { case (_, s, _) => checkInvariants(s, PlatformParams(m = m, mppl = mppl)) }
    }

  /** PRIM_FORMAT=packed, decoded from the raw words by the layout's definition: leaf row r at word r x rowWords with
    * rowWords = ceil(MPPL x 40 B / beat) beats, record k 10 k words after; every record is its scene triangle and id,
    * every leaf has its own row and the words past its records are zero.
    */
  def checkPacked(s: Scene, p0: PlatformParams): Unit = {
    val p = p0.copy(primPacked = true)
    val bvh = Mbvh.build(s, p)
    val img = MemoryImage.pack(bvh, s, Fit.fitTo(p, bvh))
    val beat = p.axiDataBits / 8
    val rowWords = (p.mppl * 40 + beat - 1) / beat * beat / 4
    val leaves = bvh.nodes.flatMap(n => n.children.zipWithIndex.filter(_._1.isLeaf).map { case (c, j) => (c, img.childRef(n.id, j)) })
    assert(img.prims.length == leaves.length * rowWords, "one row per leaf")
    val rows = leaves.map(l => img.codec.firstPrim(l._2))
    assert(rows.sorted == rows.indices, "leaf rows are 0 .. leaves - 1, each once")
    for ((c, ref) <- leaves) {
      val row = img.codec.firstPrim(ref); assert(img.codec.count(ref) == c.count)
      for (k <- 0 until c.count) {
        val t = bvh.primOrder(c.firstPrim + k); val w = row * rowWords + 10 * k
        assert(img.prims(w + 9) == t && img.primId(row, k) == t, s"leaf row $row record $k: id")
        for (a <- 0 until 9) {
          assert(img.prims(w + a) == java.lang.Float.floatToRawIntBits(s.coords(9 * t + a)), s"leaf row $row record $k word $a")
          assert(java.lang.Float.floatToRawIntBits(img.primCoord(row, k, a)) == img.prims(w + a))
        }
      }
      for (w <- row * rowWords + 10 * c.count until (row + 1) * rowWords) assert(img.prims(w) == 0, s"leaf row $row: padding word $w")
    }
  }

  for (bus <- Seq(64, 128, 256, 512); mppl <- Seq(1, 3, 4, 16))
    test(s"PRIM_FORMAT=packed image round trip: $bus-bit beats, MPPL=$mppl") {
      for (seed <- 1 to 2) checkPacked(TestScenes.soup(seed, 60 + 111 * seed), PlatformParams(mppl = mppl, axiDataBits = bus))
      TestScenes.fixtures.take(1).foreach { case (_, sc, _) => checkPacked(sc, PlatformParams(mppl = mppl, axiDataBits = bus)) }
    }

  test("a one-triangle scene gets a root node with one leaf child") {
    val s = Scene("one", Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f))
    val bvh = Mbvh.build(s, PlatformParams())
    assert(bvh.numNodes == 1 && bvh.nodes(0).children.map(_.isLeaf) == Seq(true))
    checkInvariants(s, PlatformParams())
  }

  test("identical triangles (all centroids equal) still split down to MPPL") {
    val s = Scene("stack", Array.fill(40)(Array(0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f, 0f)).flatten)
    checkInvariants(s, PlatformParams(mppl = 2))
    assert(Mbvh.build(s, PlatformParams(mppl = 2)).nodes.flatMap(_.children).filter(_.isLeaf).forall(_.count <= 2))
  }

  test("stack bound is (k-1) + deepest child bound, checked on a hand-built tree") {
    val b = Aabb(Array(0f, 0f, 0f), Array(1f, 1f, 1f))
    val leaf = Child(b, -1, 0, 1)
    val nodes = IndexedSeq(
      MNode(0, 0, IndexedSeq(Child(b, 1, 0, 0), leaf, leaf)),  // 3 children: 2 + bound(1)
      MNode(1, 1, IndexedSeq(Child(b, 2, 0, 0), leaf)),        // 2 children: 1 + bound(2)
      MNode(2, 2, IndexedSeq(leaf, leaf, leaf, leaf)))         // 4 leaves: 3
    assert(Mbvh(4, 1, nodes, Array(0)).stackBound == 2 + 1 + 3)
  }
}
