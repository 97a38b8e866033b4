package rtaccel

import java.nio.file.{Files, Path, Paths}
import scala.util.Random
import rtaccel.scene.{Rays, Scene}

/** Scenes and rays for unit tests: random soups made here, procedural fixtures made by `make fixtures`
  * (Python, scenes/procedural.py) under $RTACCEL_FIXTURES.
  */
object TestScenes {
  def soup(seed: Long, n: Int, size: Float = 1f): Scene = {
    val r = new Random(seed)
    val c = new Array[Float](9 * n)
    for (t <- 0 until n) {
      val cx = r.nextFloat() * 10; val cy = r.nextFloat() * 10; val cz = r.nextFloat() * 10
      for (v <- 0 until 3) {
        c(9 * t + 3 * v) = cx + (r.nextFloat() - 0.5f) * size
        c(9 * t + 3 * v + 1) = cy + (r.nextFloat() - 0.5f) * size
        c(9 * t + 3 * v + 2) = cz + (r.nextFloat() - 0.5f) * size
      }
    }
    Scene(s"soup$seed", c)
  }

  /** Random rays from points around the soup's cube towards random points inside it. */
  /** `img` after `flips` silent bit flips (seeded), as memory that corrupts without reporting it would hold it: a
    * third in child references (the flips that can make a node name itself or an ancestor), a third in any node word,
    * a third in any primitive word. The same words, the same size.
    */
  def flipBits(img: rtaccel.bvh.MemoryImage, seed: Long, flips: Int): rtaccel.bvh.MemoryImage = {
    val p = img.p; val rnd = new Random(seed)
    val nodes = img.nodes.clone(); val prims = img.prims.clone()
    for (_ <- 0 until flips) rnd.nextInt(3) match {
      case 0 => nodes(rnd.nextInt(img.numNodes) * img.nodeWords + 7 * rnd.nextInt(p.m) + 6) ^= 1 << rnd.nextInt(p.refs.refBits)
      case 1 => nodes(rnd.nextInt(nodes.length)) ^= 1 << rnd.nextInt(32)
      case _ => prims(rnd.nextInt(prims.length)) ^= 1 << rnd.nextInt(32)
    }
    img.copy(nodes = nodes, prims = prims)
  }

  /** `img` with one corrupted reference that makes a loop (seeded): a random inner child now names its own node or
    * one of that node's ancestors (not the root, which a reference without a level field cannot name: ref 0 is an
    * empty slot). Full nodes only.
    */
  def withLoop(img: rtaccel.bvh.MemoryImage, seed: Long): rtaccel.bvh.MemoryImage = {
    val p = img.p; val rnd = new Random(seed); val codec = new rtaccel.bvh.RefCodec(p.refs)
    require(p.nodeQuantBits == 0, "full nodes: a child reference is word 7j + 6")
    def ref(n: Int, j: Int) = img.nodes(n * img.nodeWords + 7 * j + 6)
    val inner = for (n <- 0 until img.numNodes; j <- 0 until p.m if ref(n, j) != 0 && !codec.isPrim(ref(n, j))) yield (n, j)
    val parent = inner.map { case (n, j) => codec.nodeId(ref(n, j)) -> n }.toMap
    val (n, j) = inner.filter(_._1 >= 1)(rnd.nextInt(inner.count(_._1 >= 1)))
    val up = Iterator.iterate(n)(parent).takeWhile(_ >= 1).toSeq // n and its ancestors below the root
    val nodes = img.nodes.clone()
    nodes(n * img.nodeWords + 7 * j + 6) = codec.node(up(rnd.nextInt(up.length)), codec.level(ref(n, j)))
    img.copy(nodes = nodes)
  }

  def rays(seed: Long, n: Int, lo: Float = -2f, hi: Float = 12f): Rays = {
    val r = new Random(seed)
    def p() = lo + r.nextFloat() * (hi - lo)
    val d = new Array[Float](8 * n)
    for (i <- 0 until n) {
      val o = Array(p(), p(), p()); val tgt = Array(p(), p(), p())
      for (k <- 0 until 3) { d(8 * i + k) = o(k); d(8 * i + 3 + k) = tgt(k) - o(k) }
      d(8 * i + 6) = 0f; d(8 * i + 7) = Float.PositiveInfinity
    }
    Rays(d)
  }

  /** Writes a float32 .npy (C order) for entry-point tests. */
  def saveFloats(dir: Path, name: String, data: Array[Float], shape: Seq[Int]): Path = {
    val p = dir.resolve(name)
    rtaccel.io.Npy.write(p, "'<f4'", shape, bb => data.foreach(bb.putFloat), data.length * 4); p
  }

  /** tris.npy and rays.npy in `dir`, as the Makefile hands them to the entry points. */
  def writeInputs(dir: Path, scene: Scene, rays: Rays): (Path, Path) =
    (saveFloats(dir, "tris.npy", scene.coords, Seq(scene.triangles, 3, 3)), saveFloats(dir, "rays.npy", rays.data, Seq(rays.count, 8)))

  val fixtureRoot: Option[Path] = sys.env.get("RTACCEL_FIXTURES").map(Paths.get(_)).filter(Files.isDirectory(_))
  val fixtureNames: Seq[String] = Seq("cornell", "hairball", "soup", "extreme")

  /** (name, scene, golden rays) for every procedural fixture that exists. */
  def fixtures: Seq[(String, Scene, Rays)] = fixtureRoot.toSeq.flatMap { root =>
    fixtureNames.map(n => root.resolve(n)).filter(d => Files.exists(d.resolve("tris.npy"))).map { d =>
      (d.getFileName.toString, Scene.load(d.resolve("tris.npy")), Rays.load(d.resolve("golden/rays.npy")))
    }
  }
}
