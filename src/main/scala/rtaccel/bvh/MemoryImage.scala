package rtaccel.bvh

import rtaccel.config.PlatformParams
import rtaccel.scene.Scene

/** The accelerator's onboard memory contents as 32-bit words (paper Section 4.1, Fig 2).
  * Node n occupies nodeStrideBytes at word n*nodeWords: child j at words 7j..7j+6 =
  * min x,y,z, max x,y,z (float bits), ref. Unused slots are all-zero (ref 0 = empty).
  * Primitive slot p occupies 64 bytes at word 16p: v0,v1,v2 (9 float bits) then the scene triangle id,
  * which the hardware returns as the hit's prim so that the host needs no table.
  * With NODE_FORMAT=q<k> (a model-only format) the planes are the decoded quantized ones, in the same layout;
  * the DRAM bytes of a node fetch are PlatformParams.nodeSlotBytes.
  */
final case class MemoryImage(p: PlatformParams, nodes: Array[Int], prims: Array[Int]) {
  val codec = new RefCodec(p.refs)
  val nodeWords: Int = p.nodeStrideBytes / 4
  val primWords: Int = p.primStrideBytes / 4
  def numNodes: Int = nodes.length / nodeWords
  def numPrims: Int = prims.length / primWords
  def childWord(node: Int, child: Int, k: Int): Int = nodes(node * nodeWords + 7 * child + k)
  def childRef(node: Int, child: Int): Int = childWord(node, child, 6)
  def primCoord(slot: Int, k: Int): Float = java.lang.Float.intBitsToFloat(prims(slot * primWords + k))
  def primId(slot: Int): Int = prims(slot * primWords + 9)
}

object MemoryImage {
  def pack(bvh: Mbvh, scene: Scene, p: PlatformParams): MemoryImage = {
    require(bvh.m == p.m, s"tree width ${bvh.m} differs from the config's M ${p.m}")
    val codec = new RefCodec(p.refs)
    val nw = p.nodeStrideBytes / 4; val pw = p.primStrideBytes / 4
    val nodes = new Array[Int](bvh.numNodes * nw)
    for (n <- bvh.nodes) {
      // NODE_FORMAT=q<k>: the model keeps the full layout but stores the planes the quantized node decodes to
      val planes = n.children.map(c => (Array.tabulate(3)(c.box.min(_)), Array.tabulate(3)(c.box.max(_))))
      val stored = if (p.nodeQuantBits == 0 || planes.isEmpty) planes else Quantize.boxes(Quantize.encode(planes, p.nodeQuantBits))
      for ((c, j) <- n.children.zipWithIndex) {
        val base = n.id * nw + 7 * j
        for (a <- 0 until 3) {
          nodes(base + a) = java.lang.Float.floatToRawIntBits(stored(j)._1(a))
          nodes(base + 3 + a) = java.lang.Float.floatToRawIntBits(stored(j)._2(a))
        }
        nodes(base + 6) = if (c.isLeaf) codec.leaf(c.firstPrim, c.count) else codec.node(c.node, n.level + 1)
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
