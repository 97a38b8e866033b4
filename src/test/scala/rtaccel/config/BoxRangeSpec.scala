package rtaccel.config

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.fp.FpFormat
import rtaccel.io.InputError
import rtaccel.scene.{Rays, Scene}

class BoxRangeSpec extends AnyFunSuite {
  // one triangle spanning the box [0,4] x [0,2] x [0,1]
  private val scene = Scene("slab", Array(0f, 0f, 0f, 4f, 2f, 0f, 0f, 0f, 1f))
  private def rays(rs: Seq[Float]*): Rays = Rays(rs.flatten.toArray)
  private val inf = Float.PositiveInfinity

  test("depth: the farthest t at which a ray is inside the scene's box, directed cases") {
    // along +x from x = -1 at speed 0.5: leaves x = 4 at t = 10
    assert(BoxRange.depth(scene, rays(Seq(-1f, 1f, 0.5f, 0.5f, 0f, 0f, 0f, inf))) == 10.0)
    // the same ray clipped by its tmax
    assert(BoxRange.depth(scene, rays(Seq(-1f, 1f, 0.5f, 0.5f, 0f, 0f, 0f, 3f))) == 3.0)
    // a zero direction component outside the slab misses; inside, the other axes decide (diagonal: y leaves at 2)
    assert(BoxRange.depth(scene, rays(Seq(1f, 5f, 0.5f, 1f, 0f, 0f, 0f, inf))) == 0.0)
    assert(BoxRange.depth(scene, rays(Seq(0f, 0f, 0.5f, 1f, 1f, 0f, 0f, inf))) == 2.0)
    // a ray pointing away, and one whose tmin lies beyond the box, meet nothing; the farthest of several counts
    assert(BoxRange.depth(scene, rays(Seq(-1f, 1f, 0.5f, -1f, 0f, 0f, 0f, inf), Seq(-1f, 1f, 0.5f, 1f, 0f, 0f, 6f, inf))) == 0.0)
    assert(BoxRange.depth(scene, rays(Seq(-1f, 1f, 0.5f, 1f, 0f, 0f, 0f, inf), Seq(-1f, 1f, 0.5f, 0.25f, 0f, 0f, 0f, inf))) == 20.0)
  }

  test("represents: the normal range holds twice the depth and one ulp of it (fp16: 2^-14 .. 65504)") {
    val fp16 = FpFormat.parse("fp16")
    assert(BoxRange.maxFinite(fp16) == 65504.0 && BoxRange.minNormal(fp16) == math.pow(2, -14))
    assert(BoxRange.represents(fp16, 32752.0) && !BoxRange.represents(fp16, 32752.5))
    assert(BoxRange.represents(fp16, math.pow(2, -4)) && !BoxRange.represents(fp16, math.pow(2, -4) * 0.99))
    assert(BoxRange.represents(fp16, 0.0), "no ray meets the scene: nothing to represent")
  }

  test("BOX_FORMAT=m<M> fits the fewest exponent bits; a named format that cannot hold the depth is refused") {
    val p = PlatformParams()
    // depth 10, 7 fraction bits: e3 tops out at 15.9 < 20, e4 (to 255, normals from 2^-6 <= 10/128) holds it
    assert(BoxRange.fit(p, Some(7), 10.0, "s").boxFormat == FpFormat(4, 7))
    assert(BoxRange.fit(p, Some(10), 1e30, "s").boxFormat == FpFormat(8, 10))
    assert(BoxRange.fit(p, Some(10), 1e4, "s").boxFormat == FpFormat(5, 10))
    val big = intercept[InputError](BoxRange.fit(p, Some(7), 1e39, "s")).getMessage
    assert(big.contains("BOX_FORMAT=m7") && big.contains("1.00e+39"))
    val e = intercept[InputError](BoxRange.fit(p.copy(boxFormat = FpFormat.parse("fp16")), None, 1e30, "huge")).getMessage
    assert(e.contains("BOX_FORMAT=fp16 cannot represent scene 'huge'") && e.contains("1.00e+30") && e.contains("6.55e+04") &&
      e.contains("5 exponent bits") && e.contains("BOX_FORMAT=m10"), e)
    // fp32 is the reference test: never refused; a format that holds the depth passes unchanged
    assert(BoxRange.fit(p, None, 1e-40, "tiny") == p)
    val bf = p.copy(boxFormat = FpFormat.parse("bf16"))
    assert(BoxRange.fit(bf, None, 1e30, "s") == bf)
  }
}
