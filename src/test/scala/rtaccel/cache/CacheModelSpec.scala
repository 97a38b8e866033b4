package rtaccel.cache

import scala.collection.mutable
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.bvh.{MemoryImage, Mbvh}
import rtaccel.cache.policy.LevelPolicy
import rtaccel.config.{CacheParams, CachePolicy, Fit, HwLimits, PlatformParams}
import rtaccel.model.{AccessRecorder, AccessSink, Traversal}

/** Naive reference: Map of set -> list of (line, level), most recent first (contents only, no way numbers),
  * except PLRU, which needs way positions (slots + its own tree of ranges).
  */
final class RefCache(c: CacheParams, perLine: Int = 1) {
  // The level rule and tree PLRU written again from docs/caches.md, not taken from rtaccel.cache.policy:
  // levels 15 and deeper share code 15; class = min(code, MAX_LEVEL + 1); a fill may replace a victim of
  // the same or a numerically larger class.
  private def levelClass(l: Int) = math.min(math.min(math.max(l, 0), 15), c.maxLevel + 1)
  private def mayReplace(victim: Int, incoming: Int) = levelClass(incoming) <= levelClass(victim)
  /** PLRU as a tree of ranges: each inner node [lo, hi) remembers on which half its victim lies (left at first);
    * using a way turns every node on its path towards the other half.
    */
  private final class PlruTree(ways: Int) {
    private val victimRight = mutable.Map[(Int, Int), Boolean]().withDefaultValue(false)
    def touch(way: Int): Unit = { var lo = 0; var hi = ways
      while (hi - lo > 1) { val mid = (lo + hi) / 2; val right = way >= mid; victimRight((lo, hi)) = !right; if (right) lo = mid else hi = mid } }
    def victim: Int = { var lo = 0; var hi = ways
      while (hi - lo > 1) { val mid = (lo + hi) / 2; if (victimRight((lo, hi))) lo = mid else hi = mid }; lo }
  }
  private val plrus = mutable.Map[Int, PlruTree]()
  // whole lines of perLine entries, as many as a power of two allows (written here again, not read from CacheParams)
  val lines: Int = Iterator.iterate(1)(_ * 2).takeWhile(_ <= math.max(1, c.entries / perLine)).toSeq.last
  val sets: Int = lines / c.ways
  private val lists = mutable.Map[Int, List[(Int, Int)]]().withDefaultValue(Nil)
  private val slots = mutable.Map[Int, Array[Option[(Int, Int)]]]()
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
        else if (!lrp || mayReplace(l.last._2, level)) { m(set) = (line, level) :: l.init; Some(false) }
        else None // bypass
    }
  }

  def access(line: Int, level: Int): Boolean = {
    val r: Option[Boolean] = c.policy.name match {
      case "bf" => if (line < lines) Some(true) else None
      case "dm" | "lru" | "lrp" => lruAccess(lists, line % sets, c.ways, line, level, c.policy == CachePolicy.Lrp)
      case "plru" =>
        val set = line % sets; val s = slots.getOrElseUpdate(set, Array.fill(c.ways)(None))
        val tree = plrus.getOrElseUpdate(set, new PlruTree(c.ways))
        s.indexWhere(_.exists(_._1 == line)) match {
          case -1 =>
            val w = if (s.contains(None)) s.indexOf(None) else tree.victim
            s(w) = Some((line, level)); tree.touch(w); Some(false)
          case w => tree.touch(w); Some(true)
        }
      case "hybrid" =>
        val i = line % lines
        if (dmSide.get(i).exists(_._1 == line)) Some(true)
        else {
          val ss = line % (sideLines / sideWays)
          if (side(ss).exists(_._1 == line)) lruAccess(side, ss, sideWays, line, level, lrp = true)
          else if (dmSide.get(i).forall(v => mayReplace(v._2, level))) { dmSide(i) = (line, level); Some(false) }
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
    (for (e <- Seq(8, 64, 256); w <- Seq(1, 2, 4, 8) if w <= e; pol <- Seq(CachePolicy.Lru, CachePolicy.Plru, CachePolicy.Lrp)) yield CacheParams(e, w, pol, 3)) ++
      (for (e <- Seq(8, 64, 256)) yield Seq(CacheParams(e, 1, CachePolicy.Dm), CacheParams(e, 1, CachePolicy.Bf))).flatten ++
      (for (e <- Seq(8, 64, 256); ml <- Seq(0, 3, 15)) yield Seq(CacheParams(e, 1, CachePolicy.Hybrid, ml), CacheParams(e, 1, CachePolicy.Lrp, ml),
        CacheParams(e, 4, CachePolicy.Lrp, ml))).flatten

  test(s"CacheModel equals a Map-based reference on random traces (${configs.size} configurations x 3 traces)") {
    for (c <- configs; seed <- 1 to 3) {
      val m = new CacheModel(c, LevelPolicy.paper); val ref = new RefCache(c)
      val tr = randomTrace(seed, 20000, 4 * c.entries + 50)
      for ((id, k) <- tr.zipWithIndex) assert(m.access(id, level(id)) == ref.access(id, level(id)), s"$c seed $seed access $k id $id")
      assert((m.hits, m.misses, m.bypasses) == ((ref.hits, ref.misses, ref.bypasses)), c.toString)
    }
  }

  test("primitive cache: lines = entries / MPPL (a power of two of whole leaves), line id = first primitive slot") {
    val c = CacheParams(64, 2, CachePolicy.Lru)
    val m = new CacheModel(c, LevelPolicy.paper, identity, 4); val ref = new RefCache(c, 4)
    assert(m.lines == 16)
    for (id <- randomTrace(9, 20000, 400)) assert(m.access(id, 3) == ref.access(id, 3))
    // an MPPL that is not a power of two: whole leaves in a power of two of lines (64 entries at MPPL 3: 16 of 21)
    for ((e, mppl, want) <- Seq((64, 3, 16), (8, 3, 2), (4, 3, 1), (4096, 5, 512), (64, 16, 4))) {
      val c3 = CacheParams(e, 1, CachePolicy.Dm)
      val m3 = new CacheModel(c3, LevelPolicy.paper, identity, mppl); val r3 = new RefCache(c3, mppl)
      assert(m3.lines == want && r3.lines == want, s"$e entries at MPPL $mppl")
      for (id <- randomTrace(11, 5000, 300)) assert(m3.access(id, 3) == r3.access(id, 3))
    }
  }

  test("breadth-first buffer holds exactly ids < N and never changes") {
    for (n <- Seq(1, 16, 256)) {
      val m = new CacheModel(CacheParams(n, 1, CachePolicy.Bf), LevelPolicy.paper)
      for (id <- randomTrace(4, 5000, 4 * n)) m.access(id, level(id))
      for (id <- 0 until 8 * n) assert(m.contains(id) == (id < n))
      assert(m.access(n - 1, 0) && !m.access(n, 0) && m.bypasses == m.misses)
    }
  }

  test("bad geometry is refused") {
    assertThrows[IllegalArgumentException](CacheParams(100, 1, CachePolicy.Dm))
    assertThrows[rtaccel.io.InputError](CachePolicy.parse("fifo"))
    // MAX_LEVEL is a register of the level code's width: 16 needs more than the paper's 4 bits
    assertThrows[IllegalArgumentException](PlatformParams(nodeCache = CacheParams(64, 1, CachePolicy.Lrp, 16)))
    assert(PlatformParams(nodeCache = CacheParams(64, 1, CachePolicy.Lrp, 16), hw = HwLimits(levelCodeBits = 5)).nodeCache.maxLevel == 16)
    assertThrows[IllegalArgumentException](new CacheModel(CacheParams(64, 4, CachePolicy.Dm), LevelPolicy.paper))
    assertThrows[IllegalArgumentException](new CacheModel(CacheParams(64, 16, CachePolicy.Lru), LevelPolicy.paper))
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
    val m = new CacheModel(c, LevelPolicy.paper)
    Replay.interleaved(sceneTrace._1, tus, new CacheSink(Some(m), None, 128, c => c * 64L))
    m
  }

  test("inclusion: a bigger LRU (same ways) or more-way LRU (same sets) cache never misses more, 1 and 8 TUs") {
    for (tus <- Seq(1, 8); w <- Seq(1, 2, 4)) {
      val ms = Seq(16, 32, 64, 128, 256, 512, 1024).map(e => run(CacheParams(e, w, CachePolicy.Lru), tus).misses)
      assert(ms.zip(ms.tail).forall { case (a, b) => b <= a }, s"ways $w tus $tus: $ms")
    }
    for (sets <- Seq(16, 64)) {
      val ms = Seq(1, 2, 4, 8).map(w => run(CacheParams(sets * w, w, CachePolicy.Lru)).misses)
      assert(ms.zip(ms.tail).forall { case (a, b) => b <= a }, s"sets $sets: $ms")
    }
  }

  test("DM with entries >= node count misses only compulsorily") {
    val (rows, nodes) = sceneTrace
    val e = Integer.highestOneBit(nodes) * 2
    val distinct = (0 until rows.length / 5).filter(r => rows(5 * r + 1) == 0).map(r => rows(5 * r + 2)).distinct.size
    for (tus <- Seq(1, 4)) {
      val m = run(CacheParams(e, 1, CachePolicy.Dm), tus)
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

  test("IU clusters: each cluster's caches see exactly its own TUs' accesses; the total is the clusters' sum") {
    val rows = sceneTrace._1
    val p = rtaccel.config.Presets.paper2017.copy(tus = 8, ius = 2, nodeCache = CacheParams(64, 1, CachePolicy.Dm))
    val sinks = new ClusterSinks(p)
    // the reference: the same round-robin over 8 slots, the node ids in issue order with their slot, routed by hand
    // to cluster s / 4
    val issued = new mutable.ArrayBuffer[(Int, Int)]
    Replay.slots(rows, Array.tabulate[AccessSink](8)(s => new AccessSink {
      def node(ray: Int, id: Int, level: Int): Unit = issued += ((s, id))
      def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = ()
    }))
    val byCluster = Array.tabulate(2)(c => issued.collect { case (s, id) if s / 4 == c => id })
    Replay.clustered(rows, p, sinks)
    for (c <- 0 until 2) {
      val m = new CacheModel(p.nodeCache, CacheSink.code(p)); byCluster(c).foreach(id => m.access(id, 0))
      val got = sinks.sinks(c).nodeCache.get
      assert(got.hits == m.hits && got.misses == m.misses, s"cluster $c: ${got.hits}/${got.misses} vs ${m.hits}/${m.misses}")
      assert(byCluster(c).nonEmpty)
    }
    val t = sinks.total
    assert(t.nodeCache.get.hits == sinks.sinks.map(_.nodeCache.get.hits).sum && t.nodeCache.get.misses == sinks.sinks.map(_.nodeCache.get.misses).sum)
    assert(t.nodeAccesses == rows.length / 5 - t.leafAccesses && t.nodeDramBytes == sinks.sinks.map(_.nodeDramBytes).sum)
    // one shared cache of the same size would see a different stream: the clusters are not a relabelling
    val shared = CacheSink(p.copy(ius = 1)); Replay.interleaved(rows, 8, shared)
    assert(shared.nodeCache.get.misses != t.nodeCache.get.misses, "two private caches should miss differently from one shared")
    assert(intercept[IllegalArgumentException](p.copy(tus = 7)).getMessage.contains("multiple of IUS"))
  }

  test("banked node cache (NODE_BANKS): k banks of entries / k lines on id / k, as the RTL's banks, count like one cache") {
    val rnd = new scala.util.Random(17)
    // ids with locality (a hot top and a long tail) and levels, so that every policy hits, misses and refuses
    val seq = Seq.fill(20000) { val hot = rnd.nextInt(4) == 0; val id = if (hot) rnd.nextInt(40) else rnd.nextInt(3000); (id, math.min(15, id.toBinaryString.length / 2)) }
    val code = rtaccel.cache.policy.LevelPolicy.Code(4)
    for ((c, k) <- Seq(CacheParams(256, 1, CachePolicy.Dm) -> 4, CacheParams(256, 2, CachePolicy.Lru) -> 2, CacheParams(256, 4, CachePolicy.Plru) -> 8,
        CacheParams(256, 2, CachePolicy.Lrp, maxLevel = 3) -> 4, CacheParams(512, 1, CachePolicy.Hybrid, maxLevel = 2) -> 2)) {
      val banked = new CacheModel(c, code, identity, 1, k)
      // the reference: k separate unbanked caches of entries / k, bank id % k seeing id / k (the RTL's line)
      val bankBits = Integer.numberOfTrailingZeros(k)
      val sep = Array.fill(k)(new CacheModel(c.copy(entries = c.entries / k), code))
      val one = new CacheModel(c, code)
      for ((id, lv) <- seq) {
        val h = banked.access(id, lv)
        assert(h == sep(id % k).access(id >> bankBits, lv), s"${c.policy} x$k: id $id")
        assert(h == one.access(id, lv), s"${c.policy} x$k: id $id differs from one unbanked cache")
      }
      val tot = CacheCounts(sep.map(_.hits).sum, sep.map(_.misses).sum, sep.map(_.bypasses).sum)
      assert(CacheCounts.of(banked) == tot && CacheCounts.of(one) == tot)
      assert(tot.hits > 0 && tot.misses > 0)
      for (id <- 0 until 3000) assert(banked.contains(id) == sep(id % k).contains(id >> bankBits))
    }
    assert(intercept[IllegalArgumentException](new CacheModel(CacheParams(8, 2, CachePolicy.Lru), code, identity, 1, 8)).getMessage.contains("dividing"))
  }

  test("NODE_BANKS: the clusters share one node cache (counted once), keep their own primitive caches; bad banks refused") {
    val rows = sceneTrace._1
    val p = rtaccel.config.Presets.paper2017.copy(tus = 8, ius = 2, respByPath = true, respTagged = true, nodeBanks = 2,
      nodeCache = CacheParams(64, 1, CachePolicy.Dm), primCache = CacheParams(16, 1, CachePolicy.Dm))
    val sinks = new ClusterSinks(p)
    Replay.clustered(rows, p, sinks)
    assert(sinks.sinks.forall(_.nodeCache.get eq sinks.shared.get) && (sinks.sinks(0).primCache.get ne sinks.sinks(1).primCache.get))
    val t = sinks.total
    // the same interleaving into one unbanked cache by hand: a shared cache sees every cluster's nodes in issue order
    val m = new CacheModel(p.nodeCache, CacheSink.code(p)); Replay.interleaved(rows, 8, new CacheSink(Some(m), None, 128, c => c * 64L))
    assert(t.nodeCache.get == CacheCounts.of(m), s"${t.nodeCache} vs ${CacheCounts.of(m)}")
    assert(t.nodeAccesses == m.accesses && t.primCache.get.accesses == t.leafAccesses)
    def refused(q: => rtaccel.config.PlatformParams, what: String) = assert(intercept[IllegalArgumentException](q).getMessage.contains(what))
    refused(p.copy(respTagged = false), "RESP_ORDER=tagged")
    refused(p.copy(nodeBanks = 3), "power of two")
    refused(p.copy(nodeCache = CacheParams()), "NODE_CACHE=0")
    refused(p.copy(nodeCache = CacheParams(64, 1, CachePolicy.Bf)), "NODE_POLICY=bf")
    refused(p.copy(nodeBanks = 128), "power of two")
    refused(p.copy(nodeCache = CacheParams(64, 64, CachePolicy.Lru)), "sets")
  }
}
