package rtaccel.bvh

import rtaccel.config.{Numerics, PlatformParams}
import rtaccel.scene.Scene

/** The accelerator's onboard memory contents as 32-bit words (paper Section 4.1, Fig 2).
  * Node n occupies nodeSlotBytes at word n*nodeWords. Full nodes: child j at words 7j..7j+6 =
  * min x,y,z, max x,y,z (float bits), ref. Unused slots are all-zero (ref 0 = empty).
  * Primitive slot p occupies 64 bytes at word 16p: v0,v1,v2 (9 float bits) then the scene triangle id,
  * which the hardware returns as the hit's prim so that the host needs no table.
  * With PRIM_FORMAT=packed the same 10-word records lie back to back, a leaf per row of
  * PlatformParams.leafRowBytes (leafBytes(MPPL), whole beats): leaf row r at word r * rowWords, its record k at
  * 10 k words after; the leaf reference's first field is the row number (docs/numerics.md, "Packed primitives").
  * With NODE_FORMAT=q<k> the node array holds the quantized layout of QNodeLayout, as the hardware reads it;
  * `planes` is the same tree in the full layout, decoded from those words by the model's decoder (the one
  * view the traversal reads: child j of node n at planes(n*planeWords + 7j ..)). For full nodes it is `nodes`.
  */
final case class MemoryImage(p: PlatformParams, nodes: Array[Int], prims: Array[Int]) {
  val codec = new RefCodec(p.refs)
  val nodeWords: Int = p.nodeSlotBytes / 4
  val planeWords: Int = p.nodeStrideBytes / 4
  val primWords: Int = p.primStrideBytes / 4
  def numNodes: Int = nodes.length / nodeWords
  def numPrims: Int = prims.length / primWords
  /** The full-layout view of the node array (decoded once: the traversal's hot loop reads words, not bit fields). */
  lazy val planes: Array[Int] = if (p.nodeQuantBits == 0) nodes else {
    val lay = new QNodeLayout(p.m, p.nodeQuantBits)
    val out = new Array[Int](numNodes * planeWords)
    for (n <- 0 until numNodes) lay.decodeInto(nodes, n * nodeWords, out, n * planeWords)
    out
  }
  def childWord(node: Int, child: Int, k: Int): Int = planes(node * planeWords + 7 * child + k)
  def childRef(node: Int, child: Int): Int = childWord(node, child, 6)
  /** Words from one value of a leaf reference's first field to the next (a slot, or a packed leaf row). */
  val firstWords: Int = if (p.primPacked) p.leafRowBytes / 4 else primWords
  /** Words from one record of a leaf to the next (a slot, or a packed 40 B record). */
  val recordWords: Int = if (p.primPacked) Numerics.packedPrimBytes / 4 else primWords
  /** Word index of record k of the leaf whose reference's first field is `first`. */
  def primWord(first: Int, k: Int): Int = first * firstWords + k * recordWords
  /** Byte offset from the primitive base of that record, and the bytes a record reads. */
  def primByte(first: Int, k: Int): Long = 4L * first * firstWords + 4L * k * recordWords
  val recordBytes: Int = 4 * recordWords
  def primCoord(first: Int, k: Int, c: Int): Float = java.lang.Float.intBitsToFloat(prims(primWord(first, k) + c))
  def primId(first: Int, k: Int): Int = prims(primWord(first, k) + 9)
  /** slot64: slot s is record 0 of first field s */
  def primCoord(slot: Int, c: Int): Float = primCoord(slot, 0, c)
  def primId(slot: Int): Int = primId(slot, 0)
}

object MemoryImage {
  def pack(bvh: Mbvh, scene: Scene, p: PlatformParams): MemoryImage = {
    require(bvh.m == p.m, s"tree width ${bvh.m} differs from the config's M ${p.m}")
    val codec = new RefCodec(p.refs)
    val nw = p.nodeSlotBytes / 4; val pw = p.primStrideBytes / 4
    val nodes = new Array[Int](bvh.numNodes * nw)
    // PRIM_FORMAT=packed: a leaf reference addresses its row, the leaf's rank in slot order
    lazy val row: Map[Int, Int] = leafStarts(bvh).map(_._1).zipWithIndex.toMap
    val quant = if (p.nodeQuantBits == 0) None else Some(new QNodeLayout(p.m, p.nodeQuantBits))
    for (n <- bvh.nodes) {
      val refs = n.children.map(c => if (c.isLeaf) codec.leaf(if (p.primPacked) row(c.firstPrim) else c.firstPrim, c.count)
        else codec.node(c.node, n.level + 1))
      val planes = n.children.map(c => (Array.tabulate(3)(c.box.min(_)), Array.tabulate(3)(c.box.max(_))))
      quant match {
        case Some(lay) => if (planes.nonEmpty) lay.pack(Quantize.encode(planes, p.nodeQuantBits), refs, nodes, n.id * nw)
        case None =>
          for (j <- n.children.indices) {
            val base = n.id * nw + 7 * j
            for (a <- 0 until 3) {
              nodes(base + a) = java.lang.Float.floatToRawIntBits(planes(j)._1(a))
              nodes(base + 3 + a) = java.lang.Float.floatToRawIntBits(planes(j)._2(a))
            }
            nodes(base + 6) = refs(j)
          }
      }
    }
    MemoryImage(p, nodes, if (p.primPacked) packedPrims(bvh, scene, p) else slotPrims(bvh, scene, pw))
  }

  /** The record of triangle t: 9 coordinates (float bits), then t. */
  private def record(scene: Scene, t: Int, out: Array[Int], at: Int): Unit = {
    for (k <- 0 until 9) out(at + k) = java.lang.Float.floatToRawIntBits(scene.coords(9 * t + k))
    out(at + 9) = t
  }
  private def slotPrims(bvh: Mbvh, scene: Scene, pw: Int): Array[Int] = {
    val prims = new Array[Int](bvh.numPrims * pw)
    for (slot <- 0 until bvh.numPrims) record(scene, bvh.primOrder(slot), prims, slot * pw)
    prims
  }
  /** Leaf rows in slot order: the leaf starting at slot s is row rows(s) (the builder lays leaves out slot by slot). */
  private def leafStarts(bvh: Mbvh): Array[(Int, Int)] =
    bvh.nodes.flatMap(_.children.filter(_.isLeaf).map(c => (c.firstPrim, c.count))).sortBy(_._1).toArray
  private def packedPrims(bvh: Mbvh, scene: Scene, p: PlatformParams): Array[Int] = {
    val leaves = leafStarts(bvh); val rw = p.leafRowBytes / 4; val rec = Numerics.packedPrimBytes / 4
    val prims = new Array[Int](leaves.length * rw)
    for (((first, count), r) <- leaves.zipWithIndex; k <- 0 until count) {
      require(count <= p.mppl, s"a leaf of $count primitives does not fit a packed row of MPPL=${p.mppl}")
      record(scene, bvh.primOrder(first + k), prims, r * rw + k * rec)
    }
    prims
  }
}
