package rtaccel.cli

import java.nio.file.{Files, Path}
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes

/** make simulate as a command: exit statuses, the JSON contract, waveforms on request (Verilator). */
class SimulateSpec extends AnyFunSuite {
  private val dir = Files.createTempDirectory("simulatespec")
  private val (tris, raysPath) = TestScenes.writeInputs(dir, TestScenes.soup(41, 200), TestScenes.rays(42, 60))
  private def sim(out: Path, extra: String*): (Int, String, String) = {
    val so = new java.io.ByteArrayOutputStream(); val se = new java.io.ByteArrayOutputStream()
    // its own build folder: suites run side by side, and a circuit's folder holds the run's image and rays
    val argv = Array("--tris", tris.toString, "--rays", raysPath.toString, "--out", out.toString, "--config", "small",
      "--tus", "1", "--work", "build/sim-test/SimulateSpec") ++ extra
    val code = Console.withOut(so)(Console.withErr(se)(Cli.status(argv, Flags.simulate)(Simulate.main0)))
    (code, so.toString, se.toString)
  }
  private def last(s: String) = ujson.read(s.trim.linesIterator.toSeq.last)
  // every run but the bad-input ones asks for the same waveform window of the same (o0) build: one Verilator build
  // serves the suite; the default profile's choice is VerilatorBuildSpec's
  private val waves = Seq("--waves", "1", "--waves-from", "100", "--waves-to", "160", "--sim-build", "o0")

  test("the build key's digest changes with every circuit-shaping parameter (PIPELINE's budget too), not with the preset's name, a clock that keeps the budget or the DRAM's figures") {
    import rtaccel.config.{CacheParams, CachePolicy, PlatformParams}
    val p = PlatformParams(tus = 4)
    val d = rtaccel.sim.PlatformRun.paramsDigest(p)
    assert(d.matches("[0-9a-f]{10}"), d)
    assert(rtaccel.sim.PlatformRun.paramsDigest(PlatformParams(tus = 4)) == d) // stable: the same parameters, the same build
    // 155 MHz leaves the Virtex-5 budget of 150 MHz (6 levels); 200 MHz makes it 4: another circuit
    assert(rtaccel.sim.PlatformRun.paramsDigest(p.copy(name = "mine", clockMhz = 155, clockSource = "routed")) == d)
    // MEM_GBPS (and a board's DRAM efficiency and latency) shape no circuit: the registry sets them aside
    assert(rtaccel.sim.PlatformRun.paramsDigest(p.copy(memory = rtaccel.config.MemoryParams(12.8e9, 0.8, 60))) == d)
    assert(rtaccel.config.Knobs.all.filterNot(_.shapes).map(_.make) == Seq("MEM_GBPS"))
    // PIPELINE=auto and the budget it gives, written as a number: one circuit
    assert(rtaccel.sim.PlatformRun.paramsDigest(p.copy(pipelining = rtaccel.config.Pipelining.Levels(p.stageBudget.get))) == d)
    assert(rtaccel.sim.PlatformRun.paramsDigest(p.copy(pipelining = rtaccel.config.Pipelining.Fixed, clockMhz = 300)) ==
      rtaccel.sim.PlatformRun.paramsDigest(p.copy(pipelining = rtaccel.config.Pipelining.Fixed)))
    val changed = Seq(p.copy(rayStore = true), p.copy(tagForward = true), p.copy(nodeCache = CacheParams(64, 1, CachePolicy.Dm), respByPath = true, respTagged = true, nodeBanks = 2), p.copy(tus = 8), p.copy(hw = p.hw.copy(cacheHitQueue = 8)),
      p.copy(nodeCache = CacheParams(64, 2, CachePolicy.Lru)), p.copy(nodeCache = CacheParams(64, 2, CachePolicy.Lrp)),
      p.copy(boxFormat = rtaccel.fp.FpFormat(8, 7)), p.copy(triTest = rtaccel.config.TriTest.Watertight),
      p.copy(clockMhz = 200), p.copy(pipelining = rtaccel.config.Pipelining.Fixed), p.copy(pipelining = rtaccel.config.Pipelining.Levels(3)))
    val ds = changed.map(rtaccel.sim.PlatformRun.paramsDigest)
    assert(!ds.contains(d) && ds.distinct.length == ds.length, ds)
  }

  test("a run whose check fails (cycle limit reached) exits 3, keeps its outputs and names the failure") {
    val out = dir.resolve("timeout")
    val (code, stdout, err) = sim(out, (waves :+ "--max-cycles" :+ "2000"): _*)
    assert(code == 3, err)
    val j = last(stdout)
    assert(!j("ok").bool && j("failures").arr.map(_.str).contains("timeout") && j("timed_out").bool, ujson.write(j))
    assert(Files.exists(out.resolve("hits.npy")) && Files.exists(out.resolve("summary.json")))
    assert(err.linesIterator.exists(_.startsWith("error: check failed: ")), err)
  }

  test("a clean run exits 0 with ok and no failures; the board's status agrees; WAVES=1 writes the asked cycle window as a VCD: values at its first cycle, changes up to its last") {
    val out = dir.resolve("clean")
    val (code, stdout, err) = sim(out, waves: _*)
    assert(code == 0, err)
    val j = last(stdout)
    assert(j("ok").bool && j("failures").arr.isEmpty && j("status")("done").bool && !j("status")("busy").bool)
    assert(j("irq_done").bool && j("counters")("hits_out").num == 60 && j("counters")("rays_in").num == 60)
    assert(j("clock_mhz").num == 150 && j("clock_source").str == "board", "the preset's clock is the paper board's")
    // the roofline of the run: its own rays/s, and no run beats either bound (each is a true ceiling of the RTL)
    val r = j("roofline")
    assert(r("rays_per_s").num == j("rays_per_s_at_clock").num)
    assert(r("roofline_fraction").num > 0 && r("roofline_fraction").num <= 1.0, ujson.write(r))
    assert(r("util_memory").num <= 1.0 && r("util_iu").num <= 1.0 && r("util_tu").num <= 1.0, ujson.write(r))
    assert(Set("memory", "compute", "latency")(r("binding").str) && r("ius").num == 1 && r("mem_channels").num == 1)
    assert(j("sim_build").str == "o0" && j("sim_cycles_per_cpu_s").num > 0)
    val w = j("waves")
    val vcd = Files.readAllLines(out.resolve("waves.vcd")).toArray(Array[String]()).toSeq
    val times = vcd.filter(_.startsWith("#")).map(_.drop(1).toLong)
    assert(vcd.exists(_.contains("$enddefinitions")) && vcd.contains("$dumpvars") && w("signals").num > 100)
    val period = times.sliding(2).collect { case Seq(a, b) if b > a => b - a }.min * 2 // two edges per cycle
    assert(times.head == 100 * period, s"window starts at ${times.head}, period $period")
    assert(times.last < 161 * period && times.last >= 160 * period, s"window ends at ${times.last}")
    assert(w("changes").num > 0)
    val (c2, _, e2) = sim(dir.resolve("badwaves"), "--waves", "1", "--waves-from", "50", "--waves-to", "10")
    assert(c2 == 2 && e2.contains("WAVES_TO"), e2)
    val (c3, _, e3) = sim(dir.resolve("badbuild"), "--sim-build", "o9")
    assert(c3 == 2 && e3.contains("SIM_BUILD must be one of o1, fast"), e3)
    assert(!Files.exists(dir.resolve("badbuild").resolve("hits.npy")))
  }

  // make regress (an -O3 build of its own); make soak is the long run
  if (rtaccel.Regress.full) test("short soak: the cornell fixture's golden rays at 8 TUs with a cache, DRAM jitter and host backpressure") {
    val root = TestScenes.fixtureRoot
    assume(root.isDefined, "procedural fixtures absent: run make fixtures")
    val d = root.get.resolve("cornell")
    val out = dir.resolve("soak")
    val so = new java.io.ByteArrayOutputStream(); val se = new java.io.ByteArrayOutputStream()
    val code = Console.withOut(so)(Console.withErr(se)(Cli.status(Array("--tris", d.resolve("tris.npy").toString,
      "--rays", d.resolve("golden/rays.npy").toString, "--out", out.toString, "--config", "paper2017", "--tus", "8",
      "--node-cache", "256", "--mem-jitter", "31", "--host-stall", "35", "--sim-build", "fast", "--work", "build/sim-test/SimulateSpec"), Flags.simulate)(Simulate.main0)))
    val j = last(so.toString)
    info(f"${j("rays").num}%.0f rays, ${j("cycles").num}%.0f cycles, ${j("sim_wall_s").num}%.1f s simulated, build ${j("wall_build_s").num}%.0f s (${j("sim_build").str})")
    // the long-run build profile (Verilator -O3) is as bit-exact as the quick one, caches and their access log included
    assert(code == 0 && j("mismatch_vs_model").num == 0 && j("lost").num == 0 && j("duplicated").num == 0, se.toString)
    assert(j("sim_build").str == "fast" && j("cache_counts_match_model").bool, ujson.write(j))
    assert(j("roofline")("roofline_fraction").num <= 1.0 && j("roofline")("util_memory").num <= 1.0, ujson.write(j("roofline")))
  }
}
