package rtaccel.area

import java.nio.file.{Files, Paths}
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.cli.{Area, Cli, Flags, MaxTus}
import rtaccel.config.{CacheParams, CachePolicy, Presets}

/** The fitted cost model: block RAM tiling, the least-squares fit, the split of a synthesis into units, the
  * committed coefficients (read back, instance counts, error on held-out syntheses) and FIDELITY=model /
  * make max-tus on them. No synthesis runs here.
  */
class CostModelSpec extends AnyFunSuite {
  private def run(main: rtaccel.cli.Args => Unit, flags: Seq[Flags.Flag], argv: String*): (Int, String, String) = {
    val so = new java.io.ByteArrayOutputStream(); val se = new java.io.ByteArrayOutputStream()
    val code = Console.withOut(so)(Console.withErr(se)(Cli.status(argv.toArray, flags)(main)))
    (code, so.toString, se.toString)
  }
  private def last(s: String) = ujson.read(s.trim.linesIterator.toSeq.last)
  private val dir = Files.createTempDirectory("costmodel")

  test("block RAM tiling: directed shapes as Yosys maps them, and never fewer than the bits need") {
    assert(BramMap.bram36(32768, 257) == 232) // 8 x 29 of 4K x 9 (paper2017's node cache data, synthesized: 232)
    assert(BramMap.bram36(1024, 257) == 7.5) // 15 RAMB18 of 1K x 18 (synthesized: 7.5)
    assert(BramMap.bram36(512, 72) == 1.0 && BramMap.bram36(512, 36) == 0.5 && BramMap.bram36(0, 8) == 0.0)
    val rnd = new Random(5)
    for (_ <- 0 until 500) {
      val d = 1 + rnd.nextInt(70000); val w = 1 + rnd.nextInt(600)
      val b = BramMap.bram36(d, w)
      assert(b * 36864 >= d.toLong * w, s"$d x $w: $b RAMB36 hold fewer bits than the memory")
      assert(b <= math.ceil(d / 512.0) * math.ceil(w / 72.0), s"$d x $w: $b is worse than one 512 x 72 tiling")
    }
  }

  test("least squares recovers the coefficients of exact linear data; a feature that never varies gets 0") {
    val rnd = new Random(7)
    for (_ <- 0 until 50) {
      val truth = Seq("one" -> rnd.nextInt(1000).toDouble, "tus" -> rnd.nextInt(500).toDouble, "bits" -> rnd.nextDouble())
      val rows = (0 until 6).map { _ =>
        val f = Seq("one" -> 1.0, "tus" -> (1 + rnd.nextInt(64)).toDouble, "bits" -> rnd.nextInt(100000).toDouble, "never" -> 0.0)
        (f, truth.map { case (k, c) => c * f.find(_._1 == k).get._2 }.sum)
      }
      val got = CostFit.solve(rows)
      for ((k, c) <- truth) assert(math.abs(got(k) - c) <= 1e-6 * math.max(1, math.abs(c)), s"$k: ${got(k)} vs $c")
      assert(got("never") == 0.0)
    }
  }

  test("a synthesis splits into units: own cells and non-unit submodules go to the nearest unit, counted per instance") {
    val mods = Map(
      "RtAccelTop" -> Map("TraversalController" -> 1L, "Queue8" -> 1L, "LUT6" -> 10L),
      "TraversalController" -> Map("TraversalUnit" -> 3L, "FpDivPipe" -> 2L, "RRArbiter" -> 1L, "LUT6" -> 5L),
      "TraversalUnit" -> Map("stack" -> 1L, "LUT6" -> 7L, "FDRE" -> 2L),
      "stack" -> Map("RAM64M" -> 1L), "RRArbiter" -> Map("LUT6" -> 100L), "FpDivPipe" -> Map("LUT6" -> 50L, "DSP48E1" -> 1L),
      "Queue8" -> Map("FDRE" -> 4L))
    val s = Synthesis("RtAccelTop", "xc5v", "test", dir, cached = true, Map.empty, Synthesis.countInstances(mods, "RtAccelTop"),
      Map.empty, Map.empty, Set.empty, mods)
    val u = CostModel.decompose(s)
    assert(u("TraversalUnit") == (Resources(lut = 21, lutram = 3, ff = 6), 3L))
    assert(u("TraversalController") == (Resources(lut = 105), 1L)) // its own 5 + the arbiter's 100
    assert(u("FpDivPipe") == (Resources(lut = 100, dsp = 2), 2L))
    assert(u("RtAccelTop") == (Resources(lut = 10, ff = 4), 1L))
  }

  private lazy val model = CostModel.load()

  test("the committed coefficients read back, name only features of this version, and were checked on held-out syntheses") {
    val j = ujson.read(Files.readString(CostModel.defaultPath)).obj
    val again = CostModel.fromJson(ujson.Obj.from(j))
    for (p <- Seq(Presets.paper2017, Presets.small, Presets.paper2017Lrp.copy(tus = 7, m = 8)))
      assert(again.total(p, "xc5v") == model.total(p, "xc5v"))
    assert(model.yosysVersion.nonEmpty && model.family == "xc5v")
    val v = j("validation").arr
    assert(v.length >= 8, "the model must be checked on at least 8 configurations it was not fitted on")
    val trained = j("trained_on").arr.map(_.str.takeWhile(_ != ' ')).toSet
    assert(v.forall(r => !trained(r("name").str)), "a validation configuration was also used to fit")
    assert(v.map(_("tus").num).distinct.length >= 4 && v.map(_("m").num).distinct.length >= 2)
    val lutErr = j("validation_summary")("lut")("max_abs").num
    info(f"validation: LUT error at most ${lutErr * 100}%.1f %%, BRAM at most ${j("validation_summary")("bram36")("max_abs").num * 100}%.1f %%")
    assert(lutErr < 0.15, s"the LUT error of the committed model is ${lutErr * 100} %: refit (make cost-model)")
  }

  test("the model grows with what costs: TUs, M, cache entries; a TU unit per TU; dividers 2") {
    val base = Presets.paper2017
    def t(p: rtaccel.config.PlatformParams) = model.total(p, "xc5v")
    assert(t(base.copy(tus = 16))("lut") < t(base)("lut") && t(base.copy(m = 8))("lut") > t(base)("lut"))
    assert(t(base.copy(nodeCache = base.nodeCache.copy(entries = 2048)))("bram36") < t(base)("bram36"))
    assert(math.abs(t(base)("bram36") - 232) < 232 * 0.01, "the 2^13 DM node cache data alone is 232 RAMB36 (synthesized: 232)")
    val units = model.predict(base, "xc5v").map(u => u._1 -> u._3).toMap
    assert(units("TraversalUnit") == 32 && units("FpDivPipe") == 2, "the TC's one (three axes in turn) + TriPipe's")
    // IUS clusters: the IU, its pipes, the MC and its caches once per cluster; the TUs and the TC once in all
    val two = model.predict(base.copy(ius = 2), "xc5v").map(u => u._1 -> u._2).toMap; val one = model.predict(base, "xc5v").map(u => u._1 -> u._2).toMap
    for (u <- Seq("BoxPipe", "TriPipe", "MemoryController", "CachePath"); r <- Seq("lut", "bram36"))
      assert(math.abs(two(u)(r) - 2 * one(u)(r)) <= 1e-6 * math.max(1.0, one(u)(r)), s"$u $r: ${two(u)(r)} vs 2 x ${one(u)(r)}")
    assert(two("TraversalUnit") == one("TraversalUnit") && two("TraversalController") == one("TraversalController"))
    assert(model.predict(base.copy(ius = 2), "xc5v").find(_._1 == "FpDivPipe").get._3 == 3, "the TC's divider + one per IU")
  }

  test("the throughput configuration of docs/roofline.md fits the paper's LX330T block RAM: IUS=2, q8 nodes, packed leaves") {
    // per cluster: a 4096-entry DM node cache of 64 B q8 slots (2 beats) and a 4096-primitive 4-way LRU leaf cache whose
    // 5-beat packed rows take 8-beat lines (the data RAM's line index is a shift); two clusters
    val p = Presets.paper2017.copy(ius = 2, nodeQuantBits = 8, primPacked = true, nodeCache = CacheParams(4096, 1, CachePolicy.Dm),
      primCache = CacheParams(4096, 4, CachePolicy.Lru))
    val perCluster = CostModel.cacheDataBram(p)
    info(f"cache data RAM: $perCluster%.1f RAMB36 per cluster, ${2 * perCluster}%.1f in all (LX330T: ${Boards.byName("xc5vlx330t").bram36})")
    val g = CostModel.caches(p)
    assert(g.length == 2 && g.map(c => c.dataLines.toLong << c.beatBits).sorted == Seq(8192L, 8192L),
      "data RAM words: 4096 lines x 2 node beats, 1024 lines x 5 leaf beats padded to 8")
    assert(math.abs(perCluster - 2 * BramMap.bram36(8192, 257)) < 1e-9)
    assert(2 * perCluster <= Boards.byName("xc5vlx330t").bram36)
  }

  test("make area FIDELITY=model: the pinned keys, no synthesis, a board too small refused with both numbers (exit 3)") {
    val (code, out, err) = run(Area.main0, Flags.area, "--config", "paper2017", "--fidelity", "model", "--out", dir.resolve("a").toString)
    assert(code == 0, err)
    val j = last(out)
    for (k <- Seq("config", "board", "family", "fidelity", "lut", "lutram", "ff", "dsp", "bram36", "fits", "first_overflow", "units",
        "lut_levels", "yosys_version", "wall_s")) assert(j.obj.contains(k), k)
    assert(j("fidelity").str == "model" && j("fits").bool && j("units")("TraversalUnit")("instances").num == 32)
    // the model's clock: PIPELINE's budget through the family's rule; none for the fixed stages
    val budget = rtaccel.config.Presets.paper2017.stageBudget.get
    assert(j("lut_levels_model").num == budget && j("fmax_mhz_model").num == Timing.forFamily("xc5v").fmaxMhz(budget), ujson.write(j))
    val (cn, on, en) = run(Area.main0, Flags.area, "--config", "paper2017", "--fidelity", "model", "--pipeline", "none", "--out", dir.resolve("n").toString)
    assert(cn == 0 && last(on)("fmax_mhz_model").isNull && last(on)("lut_levels_model").isNull, en)
    val (c2, o2, e2) = run(Area.main0, Flags.area, "--config", "paper2017", "--fidelity", "model", "--board", "xc7a100t",
      "--out", dir.resolve("b").toString)
    assert(c2 == 3 && !last(o2)("fits").bool && e2.contains("does not fit xc7a100t"), e2)
    val (c3, _, e3) = run(Area.main0, Flags.area, "--config", "small", "--fidelity", "model", "--unit", "BoxPipe")
    assert(c3 == 2 && e3.contains("UNIT= needs FIDELITY=yosys"), e3)
    val (c4, o4, e4) = run(Area.main0, Flags.area, "--config", "small", "--fidelity", "model", "--box-format", "bf16", "--out", dir.resolve("c").toString)
    assert(c4 == 2 && o4.isEmpty && e4.contains("BOX_FORMAT=bf16 needs FIDELITY=yosys"), e4)
    val (c5, o5, e5) = run(Area.main0, Flags.area, "--config", "small", "--fidelity", "model", "--tri-format", "fp64", "--out", dir.resolve("d").toString)
    assert(c5 == 2 && o5.isEmpty && e5.contains("TRI_FORMAT=fp64 needs FIDELITY=yosys"), e5)
    for ((flag, v, msg) <- Seq(("--node-format", "q8", "NODE_FORMAT=q8 needs FIDELITY=yosys"), ("--prim-format", "packed", "PRIM_FORMAT=packed needs FIDELITY=yosys"),
        ("--resp-order", "path", "RESP_ORDER=path needs FIDELITY=yosys"), ("--resp-order", "tagged", "RESP_ORDER=tagged needs FIDELITY=yosys"),
        ("--ray-store", "1", "RAY_STORE=1 needs FIDELITY=yosys"))) {
      val (c, o, e) = run(Area.main0, Flags.area, "--config", "small", "--fidelity", "model", flag, v, "--out", dir.resolve(s"f-${flag.drop(2)}-$v").toString)
      assert(c == 2 && o.isEmpty && e.contains(msg), e)
    }
    // TAG_FORWARD=1 changes only cache paths: refused with a cache, nothing to refuse without one
    val (c6, o6, e6) = run(Area.main0, Flags.area, "--config", "small", "--fidelity", "model", "--tag-forward", "1", "--node-cache", "64", "--out", dir.resolve("g").toString)
    assert(c6 == 2 && o6.isEmpty && e6.contains("TAG_FORWARD=1 needs FIDELITY=yosys"), e6)
  }

  test("make max-tus (model only): the answer fits, one more does not, a bigger board holds more; none fitting is exit 3") {
    val cat = dir.resolve("cat.json")
    val k7 = Boards.byName("xc7k325t")
    Files.writeString(cat, s"""{"boards": {"k7": {"part": "p", "family": "xc7", "lut": ${k7.lut}, "ff": ${k7.ff}, "dsp": ${k7.dsp},
      "bram36": ${k7.bram36}, "dram_gbps": 10, "clock_mhz": 150}, "k7x2": {"part": "p", "family": "xc7", "lut": ${2 * k7.lut},
      "ff": ${2 * k7.ff}, "dsp": ${2 * k7.dsp}, "bram36": ${2 * k7.bram36}, "dram_gbps": 10, "clock_mhz": 150}}}""")
    def maxTus(board: String) = run(MaxTus.main0, Flags.maxTus, "--config", "paper2017", "--board", board, "--catalog", cat.toString, "--confirm", "0")
    val (c1, o1, e1) = maxTus("k7"); val (c2, o2, e2) = maxTus("k7x2")
    assert(c1 == 0 && c2 == 0, e1 + e2)
    val (one, two) = (last(o1), last(o2))
    val n = one("max_tus").num.toInt
    info(s"paper2017 (2^13 DM node cache): $n TUs on a Kintex-7 325T, ${two("max_tus").num.toInt} on twice its resources")
    assert(n >= 1 && two("max_tus").num > n && one("confirmed").isNull)
    val b = Boards.byName("k7", cat)
    // as make max-tus builds it: the board's family and clock (PIPELINE=auto's budget follows them)
    val at = (t: Int) => Area.fits(ujson.Obj.from(model.total(Presets.paper2017.copy(tus = t, family = b.family, clockMhz = b.clockMhz), b.family)
      .map { case (k, v) => k -> ujson.Num(v) }), b)
    assert(at(n).isEmpty && at(n + 1).nonEmpty && one("limit")("tus").num == n + 1)
    val (c3, _, e3) = run(MaxTus.main0, Flags.maxTus, "--config", "paper2017", "--board", "xc7a100t", "--confirm", "0")
    assert(c3 == 3 && e3.contains("not even 1 TU"), e3)
    // IUS=2: TUS moves in steps of 2 (each cluster has the same TUs); the answer fits, two more do not
    val (c4, o4, e4) = run(MaxTus.main0, Flags.maxTus, "--config", "paper2017", "--ius", "2", "--board", "k7x2", "--catalog", cat.toString, "--confirm", "0")
    assert(c4 == 0, e4)
    val n2 = last(o4)("max_tus").num.toInt
    val b2 = Boards.byName("k7x2", cat)
    val at2 = (t: Int) => Area.fits(ujson.Obj.from(model.total(Presets.paper2017.copy(tus = t, ius = 2, family = b2.family, clockMhz = b2.clockMhz), b.family)
      .map { case (k, v) => k -> ujson.Num(v) }), b2)
    info(s"IUS=2: $n2 TUs on twice a Kintex-7 325T")
    assert(n2 % 2 == 0 && n2 >= 2 && at2(n2).isEmpty && at2(n2 + 2).nonEmpty && last(o4)("limit")("tus").num == n2 + 2)
  }
}
