package rtaccel.config

import rtaccel.bvh.Mbvh
import rtaccel.io.InputError

/** What a scene's tree needs from a configuration, and the two ways to use it: shrink a config to the
  * scene (fitTo) or refuse a scene that a fixed preset cannot hold (check).
  */
final case class SceneNeeds(nodeIdBits: Int, primIndexBits: Int, countBits: Int, levelBits: Int, stackDepth: Int,
                            nodes: Int, prims: Int, maxLevel: Int)

object Fit {
  /** Bits to represent values 0..maxValue (at least 1). */
  def bitsFor(maxValue: Long): Int = math.max(1, 64 - java.lang.Long.numberOfLeadingZeros(maxValue))

  def needs(bvh: Mbvh): SceneNeeds = SceneNeeds(
    nodeIdBits = bitsFor(bvh.numNodes - 1),
    primIndexBits = bitsFor(bvh.numPrims - 1),
    countBits = if (bvh.mppl <= 1) 0 else bitsFor(bvh.mppl - 1),
    levelBits = bitsFor(bvh.maxLevel),
    stackDepth = math.max(1, bvh.stackBound),
    nodes = bvh.numNodes, prims = bvh.numPrims, maxLevel = bvh.maxLevel)

  /** Cache policies that read the node level from the reference. */
  def levelAware(p: PlatformParams): Boolean = p.nodeCache.entries > 0 && p.nodeCache.policy.levelAware

  /** The smallest configuration of `p`'s kind that holds the scene; the level field is kept only when the
    * config had one or its node cache is level-aware, and then sized so no level saturates.
    */
  def fitTo(p: PlatformParams, bvh: Mbvh): PlatformParams = {
    val n = needs(bvh)
    p.copy(name = if (p.name.endsWith("fit")) p.name else s"${p.name}-fit",
      refs = RefFormat(n.nodeIdBits, n.primIndexBits, n.countBits, if (p.refs.levelBits == 0 && !levelAware(p)) 0 else n.levelBits),
      stackDepth = n.stackDepth, treeLevels = n.maxLevel + 1)
  }

  /** Level-aware node caches read each node's level from its reference: the config must have the field. */
  def checkLevelField(p: PlatformParams): Unit =
    if (levelAware(p) && p.refs.levelBits == 0)
      throw new InputError(s"NODE_POLICY=${p.nodeCache.policy} reads each node's level from its reference, but config '${p.name}' " +
        "has no level field; use CONFIG=paper2017-lrp or CONFIG=fit")

  /** Refuses a scene that exceeds a fixed configuration, naming the field and both numbers. */
  def check(p: PlatformParams, bvh: Mbvh, sceneName: String): Unit = {
    val n = needs(bvh)
    def refuse(field: String, need: String, have: String, fix: String) =
      throw new InputError(s"scene '$sceneName' does not fit config '${p.name}': $field needs $need but the config has $have; $fix")
    if (n.nodeIdBits > p.refs.nodeIdBits)
      refuse("node id field", s"${n.nodeIdBits} bits (${n.nodes} nodes)", s"${p.refs.nodeIdBits} bits", "use CONFIG=fit or widen nodeIdBits")
    if (n.primIndexBits > p.refs.primIndexBits)
      refuse("primitive index field", s"${n.primIndexBits} bits (${n.prims} primitives)", s"${p.refs.primIndexBits} bits", "use CONFIG=fit or widen primIndexBits")
    checkLevelField(p)
    if (p.shortStack == 0 && n.stackDepth > p.stackDepth) // a short stack never overflows
      refuse("traversal stack", s"${n.stackDepth} entries (tree of ${n.maxLevel + 1} levels)", s"${p.stackDepth} entries", "raise stackDepth, raise MPPL or use CONFIG=fit")
    checkTrail(p, n, sceneName)
  }

  /** The short stack's trail holds one counter per node level; a deeper tree cannot be walked. */
  def checkTrail(p: PlatformParams, n: SceneNeeds, sceneName: String): Unit =
    if (p.shortStack > 0 && n.maxLevel + 1 > p.treeLevels)
      throw new InputError(s"scene '$sceneName' does not fit config '${p.name}': the short stack's trail needs ${n.maxLevel + 1} levels " +
        s"but the config has ${p.treeLevels}; raise treeLevels, raise MPPL or use CONFIG=fit")
}
