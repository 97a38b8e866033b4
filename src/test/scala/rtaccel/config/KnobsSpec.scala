package rtaccel.config

import java.nio.file.{Files, Paths}
import org.scalatest.funsuite.AnyFunSuite
import rtaccel.cli.{Args, Cli, Flags, KnobsCmd}
import rtaccel.io.InputError

/** The knob registry is the one place a knob's rule is written: its export is what the Makefile and dse/ read, the
  * entry points' flags are its, its domains agree with PlatformParams' own requirements at every bound, and the cost
  * model refuses exactly what it marks uncalibrated.
  */
class KnobsSpec extends AnyFunSuite {
  private def accepted(p: => PlatformParams): Boolean = try { p; true } catch { case _: IllegalArgumentException => false }
  private def domainOf(make: String) = Knobs.byMake(make).get.domain

  test("config/knobs.json is the registry's export as it stands (run make knobs after changing a knob)") {
    val committed = new String(Files.readAllBytes(Paths.get(KnobsCmd.defaultPath)), "UTF-8")
    assert(committed == KnobsCmd.text, "config/knobs.json differs from rtaccel.config.Knobs: run make knobs")
    val names = ujson.read(committed)("knobs").arr.map(_("make").str)
    assert(names == Knobs.all.map(_.make) && names.distinct.size == names.size)
  }

  test("the entry points' platform flags are the registry's, each once") {
    assert(Flags.platform.map(_.name).sorted == Knobs.all.map(_.flag).sorted)
    assert(Knobs.all.map(_.flag).distinct.size == Knobs.all.size)
  }

  test("the Makefile spells no knob's flag: it takes them from the export") {
    val mk = new String(Files.readAllBytes(Paths.get("Makefile")), "UTF-8")
    for (k <- Knobs.all) {
      // a mapping of the knob's variable to its flag, in any of the forms a Makefile writes one
      val own = Seq(s"$$(if $$(${k.make}),--${k.flag}", s"--${k.flag} $$(${k.make})", s"--${k.flag} $$(or $$(${k.make})")
      assert(!own.exists(mk.contains), s"the Makefile maps ${k.make} to --${k.flag} itself")
    }
  }

  test("every integer domain agrees with PlatformParams at its bounds (one below, the bound, one above)") {
    val base = Presets.paper2017
    val cases: Seq[(String, Int => PlatformParams)] = Seq(
      "TUS" -> (v => base.copy(tus = v, ius = 1)),
      "IUS" -> (v => base.copy(ius = v, tus = math.max(v, 1))),
      "MEM_CHANNELS" -> (v => base.copy(memChannels = v)),
      "SHORT_STACK" -> (v => base.copy(shortStack = v)),
      "MAX_STEPS" -> (v => base.copy(maxSteps = Some(v))),
      "MAX_LEVEL" -> (v => base.copy(nodeCache = base.nodeCache.copy(maxLevel = v))),
      "NODE_BANKS" -> (v => base.copy(nodeBanks = v, ius = 1, respByPath = true, respTagged = true)))
    for ((make, params) <- cases; d = domainOf(make).asInstanceOf[Knobs.Ints];
         v <- Seq(d.lo - 1, d.lo, d.lo + 1, d.hi - 1, d.hi, d.hi + 1, 0, 3).distinct)
      assert(d.accepts(v.toString) == accepted(params(v)), s"$make=$v: registry ${d.accepts(v.toString)}, PlatformParams ${accepted(params(v))}")
    for (v <- Seq(1, 2, 3, 4, 5, 8, 16)) assert(domainOf("M").accepts(v.toString) == accepted(base.copy(m = v)), s"M=$v")
  }

  test("format and name domains agree with the parsers behind them") {
    def parses(f: => Any) = try { f; true } catch { case _: InputError | _: IllegalArgumentException => false }
    val boxes = Seq("fp32", "fp24", "bf16", "fp16", "FP16", "e8m23", "e3m2", "e2m10", "e9m10", "e8m24", "e5m10", "m10", "m2", "m1", "m24", "fp64", "x")
    for (v <- boxes) {
      val byParser = parses {
        BoxRange.fitRequest(v).fold(rtaccel.fp.FpFormat.parse(v)) { m => require(m >= 2 && m <= 23); rtaccel.fp.FpFormat(8, m) }
      } && BoxRange.fitRequest(v).fold(accepted(Presets.paper2017.copy(boxFormat = rtaccel.fp.FpFormat.parse(v))))(_ => true)
      assert(domainOf("BOX_FORMAT").accepts(v) == byParser, s"BOX_FORMAT=$v")
    }
    for (v <- Seq("fp32", "fp64", "e8m23", "e11m52", "e8m22", "e7m30", "e12m52", "bf16", "y"))
      assert(domainOf("TRI_FORMAT").accepts(v) == parses(Numerics.parseTriFormat(v)), s"TRI_FORMAT=$v")
    for (v <- Seq("full", "q2", "q16", "q1", "q17", "q8", "qq", "fit"))
      assert(domainOf("NODE_FORMAT").accepts(v) == (v == "fit" || parses(Numerics.parseNodeFormat(v))), s"NODE_FORMAT=$v")
    for (v <- Seq("auto", "none", "1", "2", "64", "65", "x")) assert(domainOf("PIPELINE").accepts(v) == parses(Pipelining.parse(v)), s"PIPELINE=$v")
    for (v <- CachePolicy.all.map(_.name) :+ "fifo") assert(domainOf("NODE_POLICY").accepts(v) == parses(CachePolicy.parse(v)), s"NODE_POLICY=$v")
    for (v <- Seq("request", "path", "tagged", "any")) assert(domainOf("RESP_ORDER").accepts(v) == parses(RespOrder.parse(v)))
    for (v <- Seq("mt", "watertight", "plucker")) assert(domainOf("TRI_TEST").accepts(v) == parses(TriTest.parse(v)))
    for (v <- Seq("fit", "paper2017", "paper2017-lrp", "small", "big"))
      assert(domainOf("CONFIG").accepts(v) == (v == "fit" || parses(Presets.byName(v))), s"CONFIG=$v")
  }

  test("a value outside its knob's domain is refused by every entry point with the registry's rule, before anything else") {
    for ((flag, v, msg) <- Seq(("tus", "0", "TUS=0: TUS takes an integer 1..1024"), ("node-cache", "48", "NODE_CACHE=48: NODE_CACHE takes 0 or a power of two"),
        ("box-format", "e9m4", "BOX_FORMAT=e9m4: BOX_FORMAT takes fp32, fp24, bf16 or fp16, or e<3..8>m<2..23>, or m<2..23>"),
        ("mem-gbps", "-1", "MEM_GBPS=-1: MEM_GBPS takes a number > 0"), ("clock-mhz", "fast", "CLOCK_MHZ=fast"))) {
      val e = intercept[InputError](Cli.request(Args(Map(flag -> v))))
      assert(e.getMessage.startsWith(msg), e.getMessage)
    }
    assert(Cli.request(Args(Map("tus" -> "8", "node-cache" -> "1024", "box-format" -> "bf16"))).base.tus == 8)
  }

  test("the cost model's refusal is the registry's: every preset is calibrated, each uncalibrated value is named") {
    for (p <- Presets.all.values) assert(Knobs.uncalibrated(p).isEmpty, p.name)
    val base = Presets.paper2017
    for ((p, make) <- Seq(base.copy(memChannels = 2) -> "MEM_CHANNELS", base.copy(rayStore = true) -> "RAY_STORE",
        base.copy(boxFormat = rtaccel.fp.FpFormat(8, 7)) -> "BOX_FORMAT", base.copy(nodeQuantBits = 8) -> "NODE_FORMAT",
        base.copy(nodeBanks = 2, ius = 2, respByPath = true, respTagged = true) -> "NODE_BANKS"))
      assert(Knobs.uncalibrated(p).map(_._1.make).contains(make), make)
    // tag forwarding has no circuit without a cache: calibrated then
    assert(Knobs.uncalibrated(base.copy(tagForward = true, nodeCache = CacheParams())).isEmpty)
    assert(Knobs.uncalibrated(base.copy(tagForward = true)).map(_._1.make) == Seq("TAG_FORWARD"))
  }

  test("every knob a command reads is echoed by the registry, from the resolved platform, under one key everywhere") {
    for (k <- Knobs.all if k.make != "CATALOG") assert(k.echo(Presets.paper2017).nonEmpty, s"${k.make} has no JSON key")
    val p = Presets.paper2017.copy(tus = 8, boxFormat = rtaccel.fp.FpFormat(6, 9), memRetries = 2,
      nodeCache = CacheParams(1024, 2, CachePolicy.Lru), clockMhz = 123, clockSource = "given")
    val e = Knobs.echo(p, "simulate").toMap
    assert(e("tus").num == 8 && e("box_format").str == "e6m9" && e("numerics")("box_format").str == "e6m9" && e("mem_retry_limit").num == 2)
    assert(e("caches")("node")("ways").num == 2 && e("caches")("node")("policy").str == "lru" && e("caches")("prim")("entries").num == 0)
    assert(e("clock_mhz").num == 123 && e("clock_source").str == "given" && e("config").str == "paper2017")
    // a command echoes exactly the knobs it reads: trace reads no TUS, no cache and no clock
    val t = Knobs.echo(p, "trace").map(_._1)
    assert(!t.contains("tus") && !t.contains("caches") && !t.contains("clock_mhz") && t.contains("stack_depth"), t)
    for (cmd <- Seq("trace", "cachesim", "simulate", "analyze", "bench", "verilog", "area", "timing"))
      assert(Knobs.echo(p, cmd).map(_._1).toSet == Knobs.all.filter(_.commands(cmd)).flatMap(_.echo(p).map(_._1)).toSet, cmd)
    // the export names each knob's keys, for dse/ and scripts reading the JSON lines
    assert(Knobs.json("knobs").arr.find(_("make").str == "NODE_WAYS").get("json_keys").arr.map(_.str) == Seq("caches"))
  }
}
