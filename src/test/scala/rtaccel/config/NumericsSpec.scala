package rtaccel.config

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.io.InputError

/** The numerics knobs' values, names and refusals; PRIM_FORMAT's bytes per leaf. */
class NumericsSpec extends AnyFunSuite {
  test("PRIM_FORMAT: 64 B slots, or 40 B records beat-aligned per leaf") {
    val slot = PlatformParams(); val packed = slot.copy(primPacked = true)
    assert((1 to 16).forall(n => slot.leafBytes(n) == 64L * n))
    assert(Seq(1, 2, 3, 4, 8, 16).map(packed.leafBytes) == Seq(64L, 96L, 128L, 160L, 320L, 640L)) // 256-bit beats
    assert(packed.copy(axiDataBits = 64).leafBytes(3) == 120L && packed.copy(axiDataBits = 512).leafBytes(4) == 192L)
    assert(Numerics.parsePrimFormat("packed") && !Numerics.parsePrimFormat("slot64"))
    assert(intercept[InputError](Numerics.parsePrimFormat("slot32")).getMessage.contains("slot64 or packed"))
    // a leaf row holds MPPL records in whole beats, so that a leaf's address is primBase + row x rowBytes
    assert(packed.leafRowBytes == 160 && packed.copy(mppl = 1, axiDataBits = 512).leafRowBytes == 64 && slot.leafRowBytes == 256)
    // every node and primitive format together is a circuit the RTL builds (iu.NodeDecode, iu.LeafAssembler)
    for (k <- Seq(0, 8); pk <- Seq(false, true)) rtaccel.cache.hw.CachePath.validate(PlatformParams(nodeQuantBits = k, primPacked = pk))
  }

  test("every JSON line's numerics name the five knobs; TRI_FORMAT and TRI_TEST refusals name what exists") {
    val j = Numerics.json(PlatformParams(triTest = TriTest.Watertight, nodeQuantBits = 8, primPacked = true,
      boxFormat = rtaccel.fp.FpFormat.parse("bf16")))
    assert(j.obj.keys.toSet == Set("box_format", "node_format", "prim_format", "tri_test", "tri_format"))
    assert(j("box_format").str == "bf16" && j("node_format").str == "q8" && j("prim_format").str == "packed" &&
      j("tri_test").str == "watertight" && j("tri_format").str == "fp32")
    assert(Numerics.parseTriFormat("fp64") == rtaccel.fp.FpFormat.fp64 && Numerics.parseTriFormat("e8m31") == rtaccel.fp.FpFormat(8, 31))
    for (v <- Seq("fp16", "bf16", "e8m22", "e7m40")) {
      val e = intercept[InputError](Numerics.parseTriFormat(v)).getMessage
      assert(e.contains(s"TRI_FORMAT=$v") && e.contains("narrower than fp32") && e.contains("fp64"), e)
    }
    assert(intercept[InputError](Numerics.parseTriFormat("fp128")).getMessage.contains("TRI_FORMAT=fp128"))
    assert(intercept[InputError](Numerics.parseTriFormat("e12m60")).getMessage.contains("TRI_FORMAT=e12m60"))
    assert(Numerics.json(PlatformParams(triFormat = rtaccel.fp.FpFormat.fp64))("tri_format").str == "fp64")
    assert(intercept[IllegalArgumentException](PlatformParams(triFormat = rtaccel.fp.FpFormat.fp64, triTest = TriTest.Watertight))
      .getMessage.contains("TRI_TEST=watertight takes TRI_FORMAT=fp32"))
    assert(intercept[InputError](TriTest.parse("pluecker")).getMessage.contains("mt or watertight"))
    rtaccel.cache.hw.CachePath.validate(PlatformParams(triTest = TriTest.Watertight)) // built in RTL: no refusal
  }
}
