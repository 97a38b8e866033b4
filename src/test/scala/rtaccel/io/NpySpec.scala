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

  // Seeded random corruption of valid files: every damaged file is refused with an InputError (one line,
  // what is wrong), never another exception, a hang or a silently wrong array.
  test("property: random truncation, byte flips and header edits of .npy files give one InputError each") {
    val r = new scala.util.Random(20261201)
    val good = Files.readAllBytes(floats("good.npy", Seq(4, 8), Array.tabulate(32)(i => if (i % 8 == 5) 1f else 0.5f)))
    val headerEnd = good.indexOf('\n'.toByte)
    var refused = 0
    for (k <- 0 until 600) {
      val b = good.clone()
      val bad: Array[Byte] = k % 4 match {
        case 0 => b.take(r.nextInt(b.length - 1))                                  // truncated anywhere
        case 1 => val i = r.nextInt(headerEnd + 1); b(i) = (r.nextInt(256) - 128).toByte; b // header byte flipped
        case 2 => val h = new String(b, 0, headerEnd + 1, "latin1")                // shape or dtype edited
          val edits = Seq("(4, 8)" -> s"(${r.nextInt(9)}, ${r.nextInt(12)})", "'<f4'" -> Seq("'<f8'", "'>f4'", "'<i4'", "'|u1'")(r.nextInt(4)),
            "False" -> "True", "(4, 8)" -> "(4, 8, 2)")
          val (from, to) = edits(r.nextInt(edits.length))
          (h.replace(from, to).getBytes("latin1") ++ b.drop(headerEnd + 1))
        case _ => Array.fill(r.nextInt(200))((r.nextInt(256) - 128).toByte)          // junk
      }
      val f = dir.resolve(s"fuzz$k.npy"); Files.write(f, bad)
      try {
        val rays = Rays.load(f)
        // accepted: it must then be a well-formed (N, 8) float32 file whose payload is all there
        assert(rays.count * 8 * 4 <= bad.length, s"case $k accepted a short payload")
      } catch {
        case e: InputError => refused += 1; assert(!e.getMessage.contains("\n"), s"case $k: multi-line message")
      }
    }
    assert(refused > 400, s"only $refused of 600 corruptions refused")
  }
}
