package rtaccel.cache

import rtaccel.config.CachePolicy
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.cache.policy._

object PolicySpec {
  /** PLRU as an explicit tree of bits: a node is a leaf (way) or a branch with a mutable bit. */
  sealed trait T
  final case class Leaf(way: Int) extends T
  final class Br(var bit: Int, val l: T, val r: T) extends T
}

/** Every policy, all reachable states x all ways, against an independent plain reading of its rule. */
class PolicySpec extends AnyFunSuite {
  /** LRU as an explicit list, most recent first. Decoding the state is the only shared knowledge (the encoding). */
  private def decodeLru(ways: Int, s: Int): List[Int] = {
    val w = if (ways <= 1) 0 else 32 - Integer.numberOfLeadingZeros(ways - 1)
    List.tabulate(ways)(i => (s >>> (i * w)) & ((1 << w) - 1))
  }

  for (ways <- Seq(2, 4, 8)) test(s"true LRU, $ways ways: every permutation x every way against a list") {
    val p = TrueLru(ways)
    val states = p.states
    val stateSet = states.toSet
    assert(states.size == (1 to ways).product && states.forall(s => s >= 0 && s < (1L << p.stateBits)))
    assert(decodeLru(ways, p.init) == (ways - 1 to 0 by -1).toList)
    for (s <- states) {
      val order = decodeLru(ways, s)
      assert(order.sorted == (0 until ways).toList)
      assert(p.victim(s) == order.last, s"victim of $order")
      for (w <- 0 until ways) {
        val expect = w :: order.filterNot(_ == w)
        assert(decodeLru(ways, p.touch(s, w)) == expect, s"touch $w of $order")
        assert(stateSet.contains(p.touch(s, w)))
      }
    }
    // the init order evicts ways 0,1,2,... when filled in that order
    var s = p.init
    for (w <- 0 until ways) { assert(p.victim(s) == w); s = p.touch(s, w) }
  }

  import PolicySpec._
  private def mkTree(lo: Int, n: Int): T = if (n == 1) Leaf(lo) else new Br(0, mkTree(lo, n / 2), mkTree(lo + n / 2, n / 2))
  private def branches(t: T): List[Br] = t match { // heap order (breadth-first): root, then left/right level by level
    case _: Leaf => Nil
    case b: Br => Iterator.iterate(List[T](b))(_.flatMap { case x: Br => List(x.l, x.r); case _ => Nil })
        .takeWhile(_.nonEmpty).flatten.collect { case x: Br => x }.toList
  }
  private def contains(t: T, w: Int): Boolean = t match { case Leaf(x) => x == w; case b: Br => contains(b.l, w) || contains(b.r, w) }
  private def treeTouch(t: T, w: Int): Unit = t match {
    case b: Br => if (contains(b.l, w)) { b.bit = 1; treeTouch(b.l, w) } else { b.bit = 0; treeTouch(b.r, w) }
    case _ =>
  }
  private def treeVictim(t: T): Int = t match { case Leaf(x) => x; case b: Br => treeVictim(if (b.bit == 0) b.l else b.r) }

  for (ways <- Seq(2, 4, 8)) test(s"tree PLRU, $ways ways: all 2^${ways - 1} states x every way against an explicit tree") {
    val p = TreePlru(ways)
    assert(p.stateBits == ways - 1 && p.init == 0)
    for (s <- 0 until (1 << (ways - 1))) {
      def load(): T = { val t = mkTree(0, ways); branches(t).zipWithIndex.foreach { case (b, i) => b.bit = (s >>> i) & 1 }; t }
      assert(p.victim(s) == treeVictim(load()), s"victim of state $s")
      for (w <- 0 until ways) {
        val t = load(); treeTouch(t, w)
        val expect = branches(t).zipWithIndex.map { case (b, i) => b.bit << i }.sum
        assert(p.touch(s, w) == expect, s"touch $w of state $s")
        assert(p.victim(p.touch(s, w)) != w, "the touched way is never the next victim")
      }
    }
  }

  test("direct-mapped: one way, no state") {
    assert(DirectMapped.ways == 1 && DirectMapped.stateBits == 0 && DirectMapped.touch(0, 0) == 0 && DirectMapped.victim(0) == 0)
  }

  test("LevelPolicy on all (victimLevel, incomingLevel, maxLevel) in 0..15^3") {
    var n = 0
    for (v <- 0 to 15; i <- 0 to 15; m <- 0 to 15) {
      // plain reading: both at or below maxLevel -> compare levels; both deeper -> same class (LRU decides);
      // incoming deeper than maxLevel, victim not -> refuse; victim deeper, incoming not -> allow.
      val expect =
        if (v > m && i > m) true
        else if (i > m) false
        else if (v > m) true
        else i <= v
      assert(LevelPolicy.allocate(v, i, m) == expect, s"victim $v incoming $i max $m")
      n += 1
    }
    assert(n == 4096)
    assert(LevelPolicy.allocate(40, 16, 15) && LevelPolicy.allocate(15, 40, 15), "levels beyond 15 encode as 15")
  }

  test("Policies.of and CachePolicy.parse") {
    import CachePolicy._
    assert(Policies.of(Lru, 4) == TrueLru(4) && Policies.of(Plru, 8) == TreePlru(8) && Policies.of(Dm, 1) == DirectMapped)
    assert(Policies.of(Lrp, 2) == TrueLru(2) && Policies.of(Lru, 1) == DirectMapped)
    assert(CachePolicy.all.forall(p => CachePolicy.parse(p.name) == p) && CachePolicy.all.map(CachePolicy.code) == (0 to 5))
    assertThrows[rtaccel.io.InputError](CachePolicy.parse("fifo"))
    assertThrows[IllegalArgumentException](Policies.of(Dm, 2))
    assertThrows[IllegalArgumentException](Policies.of(Plru, 6))
  }
}
