package rtaccel.bvh

import rtaccel.config.RefFormat

/** Encodes and decodes child references (paper Fig 2 / Section 7.2) for a given field layout.
  * Ref word 0 marks an empty child slot: it would name the root, which is never anyone's child.
  */
final class RefCodec(f: RefFormat) {
  private[this] val primFlag = 1 << (f.refBits - 1)
  private def mask(bits: Int): Int = if (bits >= 32) -1 else (1 << bits) - 1

  def node(id: Int, level: Int): Int = {
    require(id >= 1 && (id.toLong >> f.nodeIdBits) == 0, s"node id $id does not fit ${f.nodeIdBits} bits")
    (math.min(level, f.maxLevelCode) << f.nodeIdBits) | id
  }
  def leaf(first: Int, count: Int): Int = {
    require(count >= 1 && count <= f.maxLeafPrims, s"leaf of $count prims does not fit ${f.countBits} count bits")
    require((first.toLong >> f.primIndexBits) == 0, s"primitive index $first does not fit ${f.primIndexBits} bits")
    primFlag | ((count - 1) << f.primIndexBits) | first
  }

  // masks computed once: the traversal decodes a reference per child slot
  private[this] val nodeIdMask = mask(f.nodeIdBits); private[this] val levelMask = mask(f.levelBits)
  private[this] val primIndexMask = mask(f.primIndexBits); private[this] val countMask = mask(f.countBits)
  private[this] val nodeIdBits = f.nodeIdBits; private[this] val primIndexBits = f.primIndexBits

  def isEmpty(ref: Int): Boolean = ref == 0
  def isPrim(ref: Int): Boolean = (ref & primFlag) != 0
  def nodeId(ref: Int): Int = ref & nodeIdMask
  def level(ref: Int): Int = (ref >>> nodeIdBits) & levelMask
  def firstPrim(ref: Int): Int = ref & primIndexMask
  def count(ref: Int): Int = ((ref >>> primIndexBits) & countMask) + 1
}
