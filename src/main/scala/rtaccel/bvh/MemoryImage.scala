package rtaccel.bvh

import rtaccel.config.PlatformParams
import rtaccel.scene.Scene

/** The accelerator's onboard memory contents as 32-bit words (paper Section 4.1, Fig 2).
  * Node n occupies nodeSlotBytes at word n*nodeWords. Full nodes: child j at words 7j..7j+6 =
  * min x,y,z, max x,y,z (float bits), ref. Unused slots are all-zero (ref 0 = empty).
  * Primitive slot p occupies 64 bytes at word 16p: v0,v1,v2 (9 float bits) then the scene triangle id,
  * which the hardware returns as the hit's prim so that the host needs no table.
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
  def primCoord(slot: Int, k: Int): Float = java.lang.Float.intBitsToFloat(prims(slot * primWords + k))
  def primId(slot: Int): Int = prims(slot * primWords + 9)
}

object MemoryImage {
  def pack(bvh: Mbvh, scene: Scene, p: PlatformParams): MemoryImage = {
    require(bvh.m == p.m, s"tree width ${bvh.m} differs from the config's M ${p.m}")
    val codec = new RefCodec(p.refs)
    val nw = p.nodeSlotBytes / 4; val pw = p.primStrideBytes / 4
    val nodes = new Array[Int](bvh.numNodes * nw)
    val quant = if (p.nodeQuantBits == 0) None else Some(new QNodeLayout(p.m, p.nodeQuantBits))
    for (n <- bvh.nodes) {
      val refs = n.children.map(c => if (c.isLeaf) codec.leaf(c.firstPrim, c.count) else codec.node(c.node, n.level + 1))
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
    val prims = new Array[Int](bvh.numPrims * pw)
    for (slot <- 0 until bvh.numPrims) {
      val t = bvh.primOrder(slot)
      for (k <- 0 until 9) prims(slot * pw + k) = java.lang.Float.floatToRawIntBits(scene.coords(9 * t + k))
      prims(slot * pw + 9) = t
    }
    MemoryImage(p, nodes, prims)
  }
}
