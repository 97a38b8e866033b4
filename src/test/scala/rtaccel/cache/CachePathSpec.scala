package rtaccel.cache

import scala.util.Random
import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.bvh.{MemoryImage, RefCodec}
import rtaccel.cache.hw.{CachePath, PolicyTables}
import rtaccel.cache.policy.{LevelPolicy, Policies, ReplacementPolicy}
import rtaccel.config.{CacheParams, CachePolicy, RefFormat}
import rtaccel.mc.McCases
import rtaccel.sim.DramConfig

/** The policy tables the RTL indexes, exhaustively against the Scala functions they were built from. */
class PolicyTableHarness(pol: ReplacementPolicy) extends Module {
  val io = IO(new Bundle {
    val state = Input(UInt(math.max(1, pol.stateBits).W))
    val way = Input(UInt(math.max(1, chisel3.util.log2Ceil(pol.ways)).W))
    val next = Output(UInt(math.max(1, pol.stateBits).W))
    val victim = Output(UInt(8.W))
    val vLevel = Input(UInt(4.W)); val iLevel = Input(UInt(4.W)); val maxLevel = Input(UInt(4.W))
    val allocate = Output(Bool())
  })
  io.next := PolicyTables.touch(pol, io.state, io.way)
  io.victim := PolicyTables.victim(pol, io.state)
  io.allocate := PolicyTables.allocate(io.vLevel, io.iLevel, io.maxLevel)
}

class PolicyTablesSpec extends AnyFlatSpec with ChiselScalatestTester {
  behavior of "PolicyTables"
  // make regress adds the 2-way LRU and 4-way PLRU tables (the same generators at smaller sizes)
  for ((name, ways) <- Seq("lru" -> 4, "plru" -> 8) ++ (if (rtaccel.Regress.full) Seq("lru" -> 2, "plru" -> 4) else Nil)) it should s"equal $name $ways-way touch/victim in every reachable state" in {
    val pol = Policies.of(CachePolicy.parse(name), ways)
    test(new PolicyTableHarness(pol)).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut => // 8-way PLRU: ~1 min in treadle
      for (s <- pol.states) {
        dut.io.state.poke(s.U)
        assert(dut.io.victim.peek().litValue == pol.victim(s), s"victim of state $s")
        for (w <- 0 until ways) {
          dut.io.way.poke(w.U)
          assert(dut.io.next.peek().litValue == pol.touch(s, w), s"touch($s, $w)")
        }
      }
    }
  }
  it should "equal LevelPolicy.allocate for all 16 x 16 x 16 levels and MAX_LEVELs" in {
    test(new PolicyTableHarness(Policies.of(CachePolicy.Dm, 1))).withAnnotations(Seq(VerilatorBackendAnnotation)) { dut =>
      for (ml <- 0 to 15; v <- 0 to 15; i <- 0 to 15) {
        dut.io.maxLevel.poke(ml.U); dut.io.vLevel.poke(v.U); dut.io.iLevel.poke(i.U)
        assert(dut.io.allocate.peek().litToBoolean == LevelPolicy.allocate(v, i, ml), s"allocate($v, $i, $ml)")
      }
    }
  }
  it should "refuse state it cannot tabulate, saying what to change" in {
    val e = intercept[IllegalArgumentException](PolicyTables.check(Policies.of(CachePolicy.Lru, 8), rtaccel.config.HwLimits().policyStateBits))
    assert(e.getMessage.contains("fewer ways"))
  }
}

/** Caches in the MC under random traffic, DRAM jitter and host backpressure: every beat equals the image
  * (McCases checks each one in order, so a stale or wrong line fails at once), and the RTL's hit, miss and
  * bypass counts equal the trace model's on the same request order.
  */
class CachePathSpec extends McCases {
  private val withLevels = Some(RefFormat(nodeIdBits = 20, primIndexBits = 20, countBits = 2, levelBits = 4))
  /** Half the requests from the first eighth of the refs (near the root: reuse), half uniform (conflicts). */
  private val skewed: (Random, IndexedSeq[Int]) => Int = (r, pool) =>
    if (r.nextBoolean()) pool(r.nextInt(math.max(1, pool.length / 8))) else pool(r.nextInt(pool.length))

  private def modelCounts(img: MemoryImage, node: CacheParams, prim: CacheParams, refs: Seq[Int]): CacheSink = {
    val p = img.p.copy(nodeCache = node, primCache = prim)
    val sink = CacheSink(p)
    Replay.refs(refs.toArray, new RefCodec(p.refs), sink)
    sink
  }

  def cacheCase(what: String, node: CacheParams, prim: CacheParams, seed: Long, expectBypass: Boolean = false,
                jitter: Int = 15, readyProb: Double = 0.6, tagged: Int = 0, forward: Boolean = false): Unit =
    runCase(s"serve image bytes and count like the model: $what", dataBits = 256, tris = 400, nReqs = 260,
      DramConfig(12, 4, 1, randomExtraLatency = jitter, seed = seed.toInt), reqProb = 0.8, readyProb = readyProb, seed = seed,
      refFormat = withLevels, pathFactory = CachePath.factory(node, prim, 4), respBufferBeats = 16, maxCycles = 200000,
      maxLevel = node.maxLevel, pick = skewed,
      tagged = tagged, tagForward = forward,
      afterRun = (io: rtaccel.mc.McHarnessIO, refs: Seq[Int], img: MemoryImage) => {
        // tagged: hits answered under older misses, else the case does not test out-of-order answers
        if (tagged > 0) assert(overtakes > 10, s"only $overtakes answers began ahead of an older request's")
        val m = modelCounts(img, node, prim, refs)
        for ((name, stats, model) <- Seq(("node", io.counters.nodeCache, m.nodeCache), ("prim", io.counters.primCache, m.primCache))) {
          val (h, mi, b) = (stats.hits.peek().litValue, stats.misses.peek().litValue, stats.bypasses.peek().litValue)
          model match {
            case Some(c) =>
              info(s"$name cache: RTL hits $h misses $mi bypasses $b; model ${c.hits} / ${c.misses} / ${c.bypasses}")
              assert((h, mi, b) == ((BigInt(c.hits), BigInt(c.misses), BigInt(c.bypasses))), s"$name cache counts differ from the model")
              assert(h > 0 && mi > 0, s"$name cache: the traffic must both hit and miss to test anything")
              if (expectBypass && name == "node") assert(b > 0, "the level policy never refused a fill")
            case None => assert(h == 0 && mi == 0 && b == 0)
          }
        }
      })

  behavior of "CachePath in the MC"
  val none = CacheParams()
  // make test: one case per policy family (DM in the PLRU case's primitive cache and the hybrid's side cache);
  // make regress adds a lone DM node cache, the level policy on one way, and a quiet DRAM with a ready host
  if (rtaccel.Regress.full) cacheCase("direct-mapped node cache, 16 lines", CacheParams(16, 1, CachePolicy.Dm), none, seed = 31)
  cacheCase("4-way true-LRU node cache + 2-way LRU primitive cache", CacheParams(32, 4, CachePolicy.Lru), CacheParams(32, 2, CachePolicy.Lru), seed = 32)
  cacheCase("4-way tree-PLRU node cache + direct-mapped primitive cache", CacheParams(32, 4, CachePolicy.Plru), CacheParams(16, 1, CachePolicy.Dm), seed = 33)
  if (rtaccel.Regress.full) cacheCase("level policy, direct-mapped, MAX_LEVEL 2", CacheParams(16, 1, CachePolicy.Lrp, maxLevel = 2), none, seed = 34, expectBypass = true)
  cacheCase("level policy, 2-way LRU, MAX_LEVEL 1", CacheParams(16, 2, CachePolicy.Lrp, maxLevel = 1), none, seed = 35, expectBypass = true)
  cacheCase("breadth-first static buffer of 16 nodes (preloaded)", CacheParams(16, 1, CachePolicy.Bf), none, seed = 36, expectBypass = true)
  cacheCase("hybrid: DM + LRP side cache, MAX_LEVEL 3", CacheParams(32, 1, CachePolicy.Hybrid, maxLevel = 3), CacheParams(8, 1, CachePolicy.Dm), seed = 37)
  // RESP_ORDER=tagged (hits under misses): 4 requesters, each one request in flight, answers in any order on each
  // port; every beat checked against the request its tag names, each answer back to back, counts on the accepted order
  cacheCase("RESP_ORDER=tagged, 4 requesters: 2-way LRU node cache + direct-mapped primitive cache", CacheParams(32, 2, CachePolicy.Lru),
    CacheParams(64, 1, CachePolicy.Dm), seed = 39, tagged = 4)
  if (rtaccel.Regress.full) cacheCase("RESP_ORDER=tagged, 7 requesters: hybrid node cache (MAX_LEVEL 2) + 4-way PLRU primitive cache",
    CacheParams(32, 1, CachePolicy.Hybrid, maxLevel = 2), CacheParams(32, 4, CachePolicy.Plru), seed = 40, tagged = 7)
  // TAG_FORWARD=1 (one lookup per cycle, read-after-write through the write-first tag RAMs): the counts still equal
  // the model's on the accepted order; make test tagged on both arrays of the hybrid, make regress in order too
  if (rtaccel.Regress.full) cacheCase("TAG_FORWARD=1: 2-way LRU node cache + direct-mapped primitive cache", CacheParams(16, 2, CachePolicy.Lru),
    CacheParams(64, 1, CachePolicy.Dm), seed = 41, forward = true)
  cacheCase("TAG_FORWARD=1, RESP_ORDER=tagged, 4 requesters: hybrid node cache (MAX_LEVEL 3) + 2-way LRU primitive cache",
    CacheParams(32, 1, CachePolicy.Hybrid, maxLevel = 3), CacheParams(32, 2, CachePolicy.Lru), seed = 42, tagged = 4, forward = true)
  if (rtaccel.Regress.full) cacheCase("TAG_FORWARD=1: level policy, 2-way LRU (MAX_LEVEL 1) + 4-way PLRU primitive cache, host always ready",
    CacheParams(16, 2, CachePolicy.Lrp, maxLevel = 1), CacheParams(32, 4, CachePolicy.Plru), seed = 43, expectBypass = true, readyProb = 1.0, forward = true)
  if (rtaccel.Regress.full) cacheCase("DM node + primitive cache, no DRAM jitter, host always ready", CacheParams(16, 1, CachePolicy.Dm), CacheParams(16, 1, CachePolicy.Dm),
    seed = 38, jitter = 0, readyProb = 1.0)
}
