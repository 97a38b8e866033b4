package rtaccel.config

import rtaccel.io.InputError

/** Replacement policy of a cache, one value per policy the model and the RTL build (docs/caches.md).
  * `name` is what users type (NODE_POLICY=) and what outputs print; everything else matches on the type.
  */
sealed abstract class CachePolicy(val name: String, val levelAware: Boolean) {
  override def toString: String = name
}

object CachePolicy {
  /** direct-mapped (1 way), every miss fills */
  case object Dm extends CachePolicy("dm", false)
  /** true LRU sets */
  case object Lru extends CachePolicy("lru", false)
  /** tree pseudo-LRU sets */
  case object Plru extends CachePolicy("plru", false)
  /** the paper's level replacement policy over LRU sets */
  case object Lrp extends CachePolicy("lrp", true)
  /** breadth-first static buffer: the highest nodes, preloaded, never replaced */
  case object Bf extends CachePolicy("bf", false)
  /** direct-mapped array plus a small LRP side cache */
  case object Hybrid extends CachePolicy("hybrid", true)

  val all: Seq[CachePolicy] = Seq(Dm, Lru, Plru, Lrp, Bf, Hybrid)
  /** Policies the primitive cache can use in RTL (leaf references carry no level; bf preloads nodes). */
  val primRtl: Set[CachePolicy] = Set(Dm, Lru, Plru)

  def parse(name: String): CachePolicy = all.find(_.name == name).getOrElse(
    throw new InputError(s"unknown cache policy '$name'; use ${all.map(_.name).mkString("|")}"))
  /** 0..5 as the NODE_CACHE / PRIM_CACHE registers report it */
  def code(p: CachePolicy): Int = all.indexOf(p)
}
