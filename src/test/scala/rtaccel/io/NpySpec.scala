package rtaccel.io

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.scene.{Hits, Rays, Scene}

class NpySpec extends AnyFunSuite {
  private val dir = Files.createTempDirectory("npyspec")
  private def floats(name: String, shape: Seq[Int], data: Array[Float], descr: String = "'<f4'") = {
    val p = dir.resolve(name)
    Npy.write(p, descr, shape, bb => data.foreach(bb.putFloat), data.length * 4); p
  }

  test("float32 arrays round-trip, header padded to 64 bytes") {
    val p = floats("a.npy", Seq(2, 3, 3), Array.tabulate(18)(_.toFloat))
    assert(Files.size(p) % 64 == 8 % 64 || (Files.size(p) - 72) % 64 == 0)
    val (d, n) = Npy.readFloats(p, "x", Seq(3, 3))
    assert(n == 2 && d.sameElements(Array.tabulate(18)(_.toFloat)))
  }

  test("hits are written in the golden record layout") {
    val h = Hits(Array(1.5f, Float.PositiveInfinity), Array(7, -1), Array(0.25f, 0f), Array(0.5f, 0f))
    val p = dir.resolve("h.npy"); h.save(p)
    val a = Npy.read(p)
    assert(a.descr.contains("('t', '<f4'), ('prim', '<i4'), ('u', '<f4'), ('v', '<f4')") && a.shape == Seq(2))
    assert(a.data.getFloat(0) == 1.5f && a.data.getInt(4) == 7 && a.data.getInt(20) == -1)
  }

  test("wrong dtype, wrong shape, bad magic, missing file: one clear error each") {
    def err(f: => Any) = intercept[InputError](f).getMessage
    assert(err(Rays.load(floats("r7.npy", Seq(3, 7), new Array[Float](21)))).contains("shape (N,8)"))
    assert(err(Rays.load(floats("rd.npy", Seq(1, 8), new Array[Float](8), "'<i4'"))).contains("float32"))
    val junk = dir.resolve("junk.npy"); Files.write(junk, "hello".getBytes)
    assert(err(Scene.load(junk)).contains("not a NumPy"))
    assert(err(Scene.load(dir.resolve("none.npy"))).contains("no such file"))
  }

  test("rays and scenes are validated: NaN, zero direction, tmin > tmax, non-finite vertex, empty scene") {
    def err(f: => Any) = intercept[InputError](f).getMessage
    def ray(vals: Float*) = floats(s"r${vals.hashCode}.npy", Seq(1, 8), vals.toArray)
    assert(err(Rays.load(ray(0, 0, 0, Float.NaN, 0, 1, 0, 1))).contains("NaN"))
    assert(err(Rays.load(ray(0, 0, 0, 0, 0, 0, 0, 1))).contains("zero direction"))
    assert(err(Rays.load(ray(0, 0, 0, 0, 0, 1, 2, 1))).contains("tmin"))
    assert(err(Rays.load(ray(Float.PositiveInfinity, 0, 0, 0, 0, 1, 0, 1))).contains("infinite origin"))
    val nan = Array.fill(9)(0f); nan(4) = Float.PositiveInfinity
    assert(err(Scene.load(floats("inf.npy", Seq(1, 3, 3), nan))).contains("non-finite"))
    assert(err(Scene.load(floats("empty.npy", Seq(0, 3, 3), Array()))).contains("no triangles"))
  }
}
