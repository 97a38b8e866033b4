package rtaccel.model

import rtaccel.bvh.{MemoryImage, Mbvh}
import rtaccel.config.PlatformParams
import rtaccel.scene.{Rays, Scene}

/** Counts accesses by tree level as they stream out of the traversal (no trace kept in memory). */
final class LevelCounter(maxLevel: Int) extends AccessSink {
  val nodeAccesses = new Array[Long](maxLevel + 2)
  var leafAccesses = 0L
  var primAccesses = 0L
  def node(ray: Int, id: Int, level: Int): Unit = nodeAccesses(level) += 1
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = { leafAccesses += 1; primAccesses += count }
  def totalNodeAccesses: Long = nodeAccesses.sum
}

/** Paper Section 5: bandwidth per ray for nodes and primitives vs MPPL (Fig 4) and node accesses by
  * tree level (Figs 5-6). Bytes per access are the config's nodeAccessBytes and primAccessBytes.
  */
object Analysis {
  final case class MpplRow(mppl: Int, rays: Int, nodes: Int, leaves: Int, depth: Int, nodeAccesses: Long,
                           leafAccesses: Long, primAccesses: Long, nodeBytesPerRay: Double, primBytesPerRay: Double) {
    def totalBytesPerRay: Double = nodeBytesPerRay + primBytesPerRay
  }
  final case class LevelRow(level: Int, nodes: Int, accesses: Long, accessesPerNode: Double,
                            cumNodeShare: Double, cumAccessShare: Double)

  /** Counts the accesses of `rays` over `bvh`, packed for `p` (already fitted to or checked against it). */
  def run(scene: Scene, bvh: Mbvh, p: PlatformParams, rays: Rays): LevelCounter = {
    val counter = new LevelCounter(bvh.maxLevel)
    new Traversal(MemoryImage.pack(bvh, scene, p)).traceAll(rays, counter)
    counter
  }

  def mpplRow(p: PlatformParams, rays: Rays, bvh: Mbvh, c: LevelCounter): MpplRow = MpplRow(
    p.mppl, rays.count, bvh.numNodes, bvh.numLeaves, bvh.maxLevel + 1, c.totalNodeAccesses, c.leafAccesses,
    c.primAccesses, c.totalNodeAccesses.toDouble * p.nodeAccessBytes / rays.count,
    c.primAccesses.toDouble * p.primAccessBytes / rays.count)

  def levels(bvh: Mbvh, c: LevelCounter): Seq[LevelRow] = {
    val perLevel = bvh.nodesPerLevel
    val totalNodes = perLevel.sum.toDouble; val totalAcc = math.max(1L, c.totalNodeAccesses).toDouble
    var cn = 0L; var ca = 0L
    perLevel.indices.map { l =>
      cn += perLevel(l); ca += c.nodeAccesses(l)
      LevelRow(l, perLevel(l), c.nodeAccesses(l), c.nodeAccesses(l).toDouble / perLevel(l), cn / totalNodes, ca / totalAcc)
    }
  }
}
