package rtaccel.config

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.bvh.Mbvh
import rtaccel.io.InputError

class FitSpec extends AnyFunSuite {
  private val s = TestScenes.soup(1, 1000)

  test("fitTo gives the smallest widths that hold the scene, and the image packs with them") {
    val p = PlatformParams(m = 4, mppl = 4)
    val bvh = Mbvh.build(s, p)
    val f = Fit.fitTo(p, bvh)
    assert(f.refs.nodeIdBits == Fit.bitsFor(bvh.numNodes - 1) && (1 << (f.refs.nodeIdBits - 1)) <= bvh.numNodes - 1)
    assert(f.refs.primIndexBits == 10, "1000 primitives need indices 0..999")
    assert(f.refs.countBits == 2 && f.refs.maxLeafPrims == 4)
    assert(f.stackDepth == bvh.stackBound)
    assert(f.refs.refBits < 32)
    rtaccel.bvh.MemoryImage.pack(bvh, s, f) // packing asserts every field fits
  }

  test("the paper preset holds ordinary scenes") {
    Fit.check(Presets.paper2017, Mbvh.build(s, Presets.paper2017), "soup")
  }

  test("a scene over a preset's limits is refused with the field and both numbers") {
    val tiny = Presets.paper2017.copy(name = "tiny", refs = RefFormat(nodeIdBits = 5, primIndexBits = 27, countBits = 4, levelBits = 0))
    val e = intercept[InputError](Fit.check(tiny, Mbvh.build(s, tiny), "soup"))
    assert(e.getMessage.contains("node id field") && e.getMessage.contains("5 bits") && e.getMessage.contains("'tiny'"))
    val prims = Presets.paper2017.copy(name = "p", refs = RefFormat(31, 8, 4, 0))
    assert(intercept[InputError](Fit.check(prims, Mbvh.build(s, prims), "soup")).getMessage.contains("needs 10 bits (1000 primitives)"))
    val shallow = Presets.paper2017.copy(name = "q", stackDepth = 3)
    assert(intercept[InputError](Fit.check(shallow, Mbvh.build(s, shallow), "soup")).getMessage.contains("traversal stack"))
  }

  test("illegal parameters fail at construction with what to change") {
    def msg(f: => Any) = intercept[IllegalArgumentException](f).getMessage
    assert(msg(PlatformParams(m = 3)).contains("M (MBVH width) must be 2, 4 or 8"))
    assert(msg(PlatformParams(mppl = 17)).contains("lower MPPL or widen countBits"))
    assert(msg(PlatformParams(tus = 0)).contains("TUS"))
    assert(msg(CacheParams(entries = 100)).contains("power of two"))
    assert(intercept[rtaccel.io.InputError](CachePolicy.parse("fifo")).getMessage.contains("dm|lru|plru|lrp|bf|hybrid"))
    assert(msg(PlatformParams(hw = HwLimits(cacheOutQueue = 2))).contains("output queue must be 3..64"))
    assert(msg(PlatformParams(hw = HwLimits(levelCodeBits = 0))).contains("level code must be 1..6 bits"))
    assert(msg(PlatformParams(hw = HwLimits(iuOutstanding = 0))).contains("IU outstanding jobs"))
    assert(msg(PlatformParams(hw = HwLimits(axiAddrBits = 8))).contains("AXI address width"))
    assert(msg(PlatformParams(m = 8, nodeAccessBytesOverride = 128)).contains("smaller than a node"))
  }

  test("derived sizes: QBVH node is 896 bits in a 128-byte slot, primitive 288 bits in 64 bytes") {
    val p = Presets.paper2017
    assert(p.nodeBits == 896 && p.nodeStrideBytes == 128 && p.nodeAccessBytes == 128)
    assert(p.primBits == 288 && p.primStrideBytes == 64)
    assert(PlatformParams(m = 2).nodeStrideBytes == 64 && PlatformParams(m = 8).nodeStrideBytes == 256)
    assert(math.abs(p.memBytesPerCycle - 4.0) < 1e-9, "1.2 GB/s at 50% and 150 MHz is 4 bytes per cycle")
  }
}
