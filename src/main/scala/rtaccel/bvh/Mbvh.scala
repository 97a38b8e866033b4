package rtaccel.bvh

import scala.collection.mutable.ArrayBuffer
import rtaccel.config.PlatformParams
import rtaccel.scene.Scene

/** One child slot of an M-wide node: its box and either a node id or a leaf's primitive range. */
final case class Child(box: Aabb, node: Int, firstPrim: Int, count: Int) {
  def isLeaf: Boolean = node < 0
}

/** An M-wide node; `level` is its depth below the root (root = 0). */
final case class MNode(id: Int, level: Int, children: IndexedSeq[Child])

/** M-wide BVH with node ids in breadth-first order (root = 0, so the N highest nodes are ids 0..N-1)
  * and primitives laid out leaf by leaf; `primOrder(slot)` is the scene triangle stored in that slot.
  */
final case class Mbvh(m: Int, mppl: Int, nodes: IndexedSeq[MNode], primOrder: Array[Int]) {
  def numNodes: Int = nodes.length
  def numPrims: Int = primOrder.length
  def numLeaves: Int = nodes.map(_.children.count(_.isLeaf)).sum
  def maxLevel: Int = nodes.map(_.level).max
  def maxLeafPrims: Int = nodes.flatMap(_.children.filter(_.isLeaf).map(_.count)).max

  /** Worst-case traversal stack occupancy: at a node with k hit children the TU visits the nearest and
    * pushes k-1; any child can be the nearest, so the bound is (k-1) + the largest bound of a node child.
    */
  lazy val stackBound: Int = {
    val b = new Array[Int](numNodes)
    for (n <- nodes.reverseIterator) { // BFS order reversed = children before parents
      val deepest = n.children.filterNot(_.isLeaf).map(c => b(c.node)).maxOption.getOrElse(0)
      b(n.id) = n.children.length - 1 + deepest
    }
    b(0)
  }

  def nodesPerLevel: Array[Int] = {
    val c = new Array[Int](maxLevel + 1); nodes.foreach(n => c(n.level) += 1); c
  }
}

object Mbvh {
  def build(scene: Scene, p: PlatformParams): Mbvh = {
    val nodeCost = p.treeNodeBytes.toDouble
    val bb = new BinaryBuilder(scene, p.mppl, p.sahBins, nodeCost, p.primAccessBytes.toDouble)
    val root = bb.build() match {
      case l: BLeaf => BInner(l.box, l, null) // the root must be a node: a one-leaf scene gets a one-child root
      case i: BInner => i
    }
    // Collapse: open the largest-area inner child until the node has M children.
    def open(b: BInner): IndexedSeq[BNode] = {
      val kids = ArrayBuffer[BNode](b.left) ++ Option(b.right)
      var done = false
      while (kids.length < p.m && !done) {
        val inner = kids.indices.filter(i => kids(i).isInstanceOf[BInner])
        if (inner.isEmpty) done = true
        else {
          val i = inner.maxBy(i => kids(i).box.area)
          val bi = kids(i).asInstanceOf[BInner]
          kids(i) = bi.left; kids.insert(i + 1, bi.right)
        }
      }
      kids.toIndexedSeq
    }
    // Breadth-first numbering: a queue of (binary inner node, level); ids are queue positions.
    val queue = ArrayBuffer[(BInner, Int)]((root, 0))
    val nodes = ArrayBuffer[MNode]()
    var head = 0
    while (head < queue.length) {
      val (b, level) = queue(head)
      val kids = open(b).map {
        case l: BLeaf => Child(l.box, -1, l.start, l.count)
        case i: BInner => queue += ((i, level + 1)); Child(i.box, queue.length - 1, 0, 0)
      }
      nodes += MNode(head, level, kids)
      head += 1
    }
    Mbvh(p.m, p.mppl, nodes.toIndexedSeq, bb.order)
  }
}
