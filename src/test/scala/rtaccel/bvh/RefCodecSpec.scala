package rtaccel.bvh

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.config.{Presets, RefFormat}

class RefCodecSpec extends AnyFunSuite {
  test("paper2017 layout: bit 31 primitive, count-1 in 30..27, first primitive in 26..0 (Fig 2)") {
    val c = new RefCodec(Presets.paper2017.refs)
    assert(c.leaf(5, 4) == (0x80000000 | (3 << 27) | 5))
    assert(c.leaf((1 << 27) - 1, 16) == 0xffffffff)
    assert(c.node(7, 3) == 7, "no level field in the plain preset")
    assert(c.node((1 << 31) - 1, 0) == 0x7fffffff)
  }

  test("paper2017-lrp layout: level in bits 30..27, saturating at 15, node id in 26..0 (Section 7.2)") {
    val c = new RefCodec(Presets.paper2017Lrp.refs)
    assert(c.node(9, 2) == ((2 << 27) | 9))
    assert(c.level(c.node(9, 14)) == 14 && c.level(c.node(9, 15)) == 15 && c.level(c.node(9, 40)) == 15)
    assert(!c.isPrim(c.node(9, 15)) && c.nodeId(c.node(9, 15)) == 9)
  }

  test("round trip of every field at its limits, for several fitted layouts") {
    for (f <- Seq(RefFormat(1, 1, 0, 0), RefFormat(9, 12, 2, 4), RefFormat(20, 27, 4, 4), RefFormat(27, 27, 4, 4))) {
      val c = new RefCodec(f)
      for (id <- Seq(1, (1 << f.nodeIdBits) - 1).distinct; lvl <- 0 to f.maxLevelCode) {
        val r = c.node(id, lvl)
        assert(!c.isPrim(r) && !c.isEmpty(r) && c.nodeId(r) == id && c.level(r) == lvl, s"$f node $id level $lvl")
      }
      for (first <- Seq(0, (1 << f.primIndexBits) - 1); n <- 1 to f.maxLeafPrims) {
        val r = c.leaf(first, n)
        assert(c.isPrim(r) && !c.isEmpty(r) && c.firstPrim(r) == first && c.count(r) == n, s"$f leaf $first x $n")
      }
    }
  }

  test("out-of-range fields are rejected, and ref 0 (the root) is the empty slot") {
    val c = new RefCodec(RefFormat(4, 4, 2, 0))
    assert(c.isEmpty(0))
    intercept[IllegalArgumentException](c.node(0, 0))
    intercept[IllegalArgumentException](c.node(16, 0))
    intercept[IllegalArgumentException](c.leaf(16, 1))
    intercept[IllegalArgumentException](c.leaf(0, 5))
    intercept[IllegalArgumentException](RefFormat(31, 31, 4, 0))
  }
}
