package rtaccel.cache

import scala.collection.mutable
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.bvh.{MemoryImage, Mbvh}
import rtaccel.cache.policy.{LevelPolicy, TreePlru}
import rtaccel.config.{CacheParams, Fit, PlatformParams}
import rtaccel.model.{AccessRecorder, AccessSink, Traversal}

/** Naive reference: Map of set -> list of (line, level), most recent first (contents only, no way numbers),
  * except PLRU, which needs way positions (slots + the exhaustively tested TreePlru state).
  */
final class RefCache(c: CacheParams, perLine: Int = 1) {
  val lines: Int = math.max(1, c.entries / perLine)
  val sets: Int = lines / c.ways
  private val lists = mutable.Map[Int, List[(Int, Int)]]().withDefaultValue(Nil)
  private val slots = mutable.Map[Int, Array[Option[(Int, Int)]]]()
  private val plruState = mutable.Map[Int, Int]().withDefaultValue(0)
  private val dmSide = mutable.Map[Int, (Int, Int)]()
  private val sideLines = math.max(1, lines / 8); private val sideWays = math.min(4, sideLines)
  private val side = mutable.Map[Int, List[(Int, Int)]]().withDefaultValue(Nil)
  var hits = 0L; var misses = 0L; var bypasses = 0L

  private def lruAccess(m: mutable.Map[Int, List[(Int, Int)]], set: Int, ways: Int, line: Int, level: Int, lrp: Boolean): Option[Boolean] = {
    val l = m(set)
    l.find(_._1 == line) match {
      case Some(e) => m(set) = e :: l.filterNot(_ == e); Some(true)
      case None =>
        if (l.size < ways) { m(set) = (line, level) :: l; Some(false) }
        else if (!lrp || LevelPolicy.allocate(l.last._2, level, c.maxLevel)) { m(set) = (line, level) :: l.init; Some(false) }
        else None // bypass
    }
  }

  def access(line: Int, level: Int): Boolean = {
    val r: Option[Boolean] = c.policy match {
      case "bf" => if (line < lines) Some(true) else None
      case "dm" | "lru" | "lrp" => lruAccess(lists, line % sets, c.ways, line, level, c.policy == "lrp")
      case "plru" =>
        val set = line % sets; val s = slots.getOrElseUpdate(set, Array.fill(c.ways)(None)); val p = TreePlru(c.ways)
        s.indexWhere(_.exists(_._1 == line)) match {
          case -1 =>
            val w = if (s.contains(None)) s.indexOf(None) else p.victim(plruState(set))
            s(w) = Some((line, level)); plruState(set) = p.touch(plruState(set), w); Some(false)
          case w => plruState(set) = p.touch(plruState(set), w); Some(true)
        }
      case "hybrid" =>
        val i = line % lines
        if (dmSide.get(i).exists(_._1 == line)) Some(true)
        else {
          val ss = line % (sideLines / sideWays)
          if (side(ss).exists(_._1 == line)) lruAccess(side, ss, sideWays, line, level, lrp = true)
          else if (dmSide.get(i).forall(v => LevelPolicy.allocate(v._2, level, c.maxLevel))) { dmSide(i) = (line, level); Some(false) }
          else lruAccess(side, ss, sideWays, line, level, lrp = true)
        }
    }
    r match {
      case Some(true) => hits += 1; true
      case Some(false) => misses += 1; false
      case None => misses += 1; bypasses += 1; false
    }
  }
}

class CacheModelSpec extends AnyFunSuite {
  private def level(id: Int): Int = { var l = 0; var n = 1L; var first = 0L; while (id >= first + n) { first += n; n *= 4; l += 1 }; l }

  private def randomTrace(seed: Long, n: Int, range: Int): Array[Int] = {
    val r = new scala.util.Random(seed)
    // skewed towards small ids (high levels), like a BVH traversal, with bursts of reuse
    Array.fill(n) { val u = r.nextDouble(); val id = (math.pow(u, 3) * range).toInt; if (r.nextInt(4) == 0) id % 16 else id }
  }

  private val configs: Seq[CacheParams] =
    (for (e <- Seq(8, 64, 256); w <- Seq(1, 2, 4, 8) if w <= e; pol <- Seq("lru", "plru", "lrp")) yield CacheParams(e, w, pol, 3)) ++
      (for (e <- Seq(8, 64, 256)) yield Seq(CacheParams(e, 1, "dm"), CacheParams(e, 1, "bf"))).flatten ++
      (for (e <- Seq(8, 64, 256); ml <- Seq(0, 3, 15)) yield Seq(CacheParams(e, 1, "hybrid", ml), CacheParams(e, 1, "lrp", ml),
        CacheParams(e, 4, "lrp", ml))).flatten

  test(s"CacheModel equals a Map-based reference on random traces (${configs.size} configurations x 3 traces)") {
    for (c <- configs; seed <- 1 to 3) {
      val m = new CacheModel(c); val ref = new RefCache(c)
      val tr = randomTrace(seed, 20000, 4 * c.entries + 50)
      for ((id, k) <- tr.zipWithIndex) assert(m.access(id, level(id)) == ref.access(id, level(id)), s"$c seed $seed access $k id $id")
      assert((m.hits, m.misses, m.bypasses) == ((ref.hits, ref.misses, ref.bypasses)), c.toString)
    }
  }

  test("primitive cache: lines = entries / MPPL, line id = first primitive slot") {
    val c = CacheParams(64, 2, "lru")
    val m = new CacheModel(c, identity, 4); val ref = new RefCache(c, 4)
    assert(m.lines == 16)
    for (id <- randomTrace(9, 20000, 400)) assert(m.access(id, 3) == ref.access(id, 3))
  }

  test("breadth-first buffer holds exactly ids < N and never changes") {
    for (n <- Seq(1, 16, 256)) {
      val m = new CacheModel(CacheParams(n, 1, "bf"))
      for (id <- randomTrace(4, 5000, 4 * n)) m.access(id, level(id))
      for (id <- 0 until 8 * n) assert(m.contains(id) == (id < n))
      assert(m.access(n - 1, 0) && !m.access(n, 0) && m.bypasses == m.misses)
    }
  }

  test("bad geometry is refused") {
    assertThrows[IllegalArgumentException](CacheParams(100, 1, "dm"))
    assertThrows[IllegalArgumentException](CacheParams(64, 1, "fifo"))
    assertThrows[IllegalArgumentException](CacheParams(64, 1, "lrp", 16))
    assertThrows[IllegalArgumentException](new CacheModel(CacheParams(64, 4, "dm")))
    assertThrows[IllegalArgumentException](new CacheModel(CacheParams(64, 16, "lru")))
  }

  // ------------------------------------------------------------- on a scene's traversal trace
  private lazy val sceneTrace: (Array[Int], Int) = {
    val s = TestScenes.soup(5, 3000); val p = PlatformParams(m = 4, mppl = 4)
    val bvh = Mbvh.build(s, p)
    val rec = new AccessRecorder
    new Traversal(MemoryImage.pack(bvh, s, Fit.fitTo(p, bvh))).traceAll(TestScenes.rays(6, 2000), rec)
    (rec.toArray, bvh.numNodes)
  }
  private def run(c: CacheParams, tus: Int = 1): CacheModel = {
    val m = new CacheModel(c)
    Replay.interleaved(sceneTrace._1, tus, new CacheSink(Some(m), None, 128, 64))
    m
  }

  test("inclusion: a bigger LRU (same ways) or more-way LRU (same sets) cache never misses more, 1 and 8 TUs") {
    for (tus <- Seq(1, 8); w <- Seq(1, 2, 4)) {
      val ms = Seq(16, 32, 64, 128, 256, 512, 1024).map(e => run(CacheParams(e, w, "lru"), tus).misses)
      assert(ms.zip(ms.tail).forall { case (a, b) => b <= a }, s"ways $w tus $tus: $ms")
    }
    for (sets <- Seq(16, 64)) {
      val ms = Seq(1, 2, 4, 8).map(w => run(CacheParams(sets * w, w, "lru")).misses)
      assert(ms.zip(ms.tail).forall { case (a, b) => b <= a }, s"sets $sets: $ms")
    }
  }

  test("DM with entries >= node count misses only compulsorily") {
    val (rows, nodes) = sceneTrace
    val e = Integer.highestOneBit(nodes) * 2
    val distinct = (0 until rows.length / 5).filter(r => rows(5 * r + 1) == 0).map(r => rows(5 * r + 2)).distinct.size
    for (tus <- Seq(1, 4)) {
      val m = run(CacheParams(e, 1, "dm"), tus)
      assert(m.misses == distinct && distinct <= nodes)
    }
  }

  test("interleaved replay with 1 TU is the traversal's own order; N TUs issue every access once") {
    val rows = sceneTrace._1
    val seen = new mutable.ArrayBuffer[(Int, Int, Int)]
    val sink = new AccessSink {
      def node(ray: Int, id: Int, level: Int): Unit = seen += ((ray, 0, id))
      def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = seen += ((ray, 1, firstPrim))
    }
    val orig = (0 until rows.length / 5).map(r => (rows(5 * r), rows(5 * r + 1), rows(5 * r + 2)))
    Replay.interleaved(rows, 1, sink); assert(seen == orig)
    seen.clear(); Replay.interleaved(rows, 7, sink)
    assert(seen.sorted == orig.sorted && seen != orig)
    assert(seen.groupBy(_._1).forall { case (ray, xs) => xs == orig.filter(_._1 == ray) }, "each ray keeps its own order")
    assert(seen.take(7).map(_._1).distinct.size == 7, "the first 7 accesses come from 7 different rays")
  }
}
