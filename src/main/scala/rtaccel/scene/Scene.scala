package rtaccel.scene

import java.nio.file.Path
import rtaccel.io.{InputError, Npy}

/** Triangles as flat float32 coordinates: triangle i is v0,v1,v2 at 9*i .. 9*i+8 (x,y,z each).
  * Meshes are parsed on the Python side (scenes/load.py, trimesh) and handed over as tris.npy, so that
  * Embree and the model see exactly the same triangle order and float values.
  */
final case class Scene(name: String, coords: Array[Float]) {
  require(coords.length % 9 == 0, "triangle coordinates must come in groups of 9")
  val triangles: Int = coords.length / 9
  def v(tri: Int, vertex: Int, axis: Int): Float = coords(9 * tri + 3 * vertex + axis)
}

object Scene {
  def load(path: Path): Scene = {
    val (c, n) = Npy.readFloats(path, "triangle array", Seq(3, 3))
    if (n == 0) throw new InputError(s"$path: the scene has no triangles; give a mesh with at least one face")
    val bad = c.indexWhere(x => x.isNaN || x.isInfinite)
    if (bad >= 0)
      throw new InputError(s"$path: triangle ${bad / 9} has a non-finite coordinate (${c(bad)}); fix the mesh")
    Scene(path.getFileName.toString.stripSuffix(".npy").stripSuffix(".tris"), c)
  }
}

/** Rays as in rays.npy: ox,oy,oz,dx,dy,dz,tmin,tmax per row. */
final case class Rays(data: Array[Float]) {
  val count: Int = data.length / 8
  def apply(i: Int, k: Int): Float = data(8 * i + k)
}

object Rays {
  def load(path: Path): Rays = {
    val (d, n) = Npy.readFloats(path, "rays file", Seq(8))
    var i = 0
    while (i < n) {
      val row = d.slice(8 * i, 8 * i + 8)
      if (row.exists(_.isNaN))
        throw new InputError(s"$path: ray $i has a NaN component; rays must be numeric")
      if (row.take(3).exists(_.isInfinite))
        throw new InputError(s"$path: ray $i has an infinite origin; origins must be finite")
      if (row(3) == 0f && row(4) == 0f && row(5) == 0f)
        throw new InputError(s"$path: ray $i has a zero direction; give a non-zero direction")
      if (!(row(6) <= row(7)))
        throw new InputError(s"$path: ray $i has tmin ${row(6)} > tmax ${row(7)}")
      i += 1
    }
    Rays(d)
  }
}

/** Closest-hit results in the hits.npy record layout: t (f4), prim (i4), u (f4), v (f4); prim -1 = miss. */
final case class Hits(t: Array[Float], prim: Array[Int], u: Array[Float], v: Array[Float]) {
  def count: Int = t.length
  def save(path: Path): Unit = {
    val descr = "[('t', '<f4'), ('prim', '<i4'), ('u', '<f4'), ('v', '<f4')]"
    Npy.write(path, descr, Seq(count), bb => (0 until count).foreach { i =>
      bb.putFloat(t(i)).putInt(prim(i)).putFloat(u(i)).putFloat(v(i))
    }, count * 16)
  }
}

object Hits {
  /** Hit-record codes of a ray that has no valid result (hits.npy keeps its dtype; t = +inf). */
  val Miss: Int = -1
  val ReadError: Int = -2
  val Overflow: Int = -3
  /** The ray needed more fetches than MAX_STEPS (a loop through a corrupted image): it ended there. */
  val StepLimit: Int = -4

  /** hits.npy as Hits.save writes it (and make golden). */
  def load(path: java.nio.file.Path): Hits = {
    val a = rtaccel.io.Npy.read(path)
    if (!a.descr.contains("'t'") || !a.descr.contains("'prim'") || a.shape.length != 1)
      throw new rtaccel.io.InputError(s"$path: not a hits file (want dtype [t f4, prim i4, u f4, v f4], got ${a.descr})")
    a.requireBytes(path, 16)
    val h = empty(a.count); val bb = a.data
    for (i <- 0 until a.count) { h.t(i) = bb.getFloat(16 * i); h.prim(i) = bb.getInt(16 * i + 4); h.u(i) = bb.getFloat(16 * i + 8); h.v(i) = bb.getFloat(16 * i + 12) }
    h
  }

  def empty(n: Int): Hits =
    Hits(Array.fill(n)(Float.PositiveInfinity), Array.fill(n)(-1), new Array[Float](n), new Array[Float](n))
}
