package rtaccel.perf

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.cli.RooflineCmd
import rtaccel.config.Presets
import rtaccel.io.InputError

class RooflineSpec extends AnyFunSuite {
  private val p = Presets.paper2017 // 150 MHz, 1.2 GB/s peak at 50 % sustained, 256-bit bus, M = 4
  private def run(rays: Long, cycles: Long, nodes: Long, prims: Long, beats: Long, tuBusy: Long = 0) =
    Roofline.Run(rays, cycles, nodes, prims, beats, tuBusy, stallIuArbitration = 0, stallMemoryData = 0, stallMemoryRequest = 0)

  test("what one IU takes per cycle follows the node, primitive and bus sizes (one beat per cycle)") {
    assert(Roofline.iuRates(p) == Roofline.IuRates(nodeBeats = 4, primBeats = 2)) // 128 B nodes, 64 B primitives, 32 B beats
    assert(Roofline.iuRates(p.copy(m = 8)) == Roofline.IuRates(8, 2))
    assert(Roofline.iuRates(p.copy(m = 2)) == Roofline.IuRates(2, 2))
    assert(Roofline.iuRates(p.copy(axiDataBits = 512)) == Roofline.IuRates(2, 1))
    // packed leaves: 40 B records through the LeafAssembler, one per cycle at most; quantized nodes: their slot's beats
    assert(Roofline.iuRates(p.copy(primPacked = true)) == Roofline.IuRates(4, 1.25))
    assert(Roofline.iuRates(p.copy(primPacked = true, axiDataBits = 512)) == Roofline.IuRates(2, 1.0))
    assert(Roofline.iuRates(p.copy(primPacked = true, axiDataBits = 64)) == Roofline.IuRates(16, 5.0))
    // TRI_II=k with packed leaves: the LeafAssembler lets a record out every k cycles, whatever its beats
    assert(Roofline.iuRates(p.copy(primPacked = true, triInterval = 2)) == Roofline.IuRates(4, 2.0))
    assert(Roofline.iuRates(p.copy(primPacked = true, triInterval = 3, axiDataBits = 64)) == Roofline.IuRates(16, 5.0))
    assert(Roofline.iuRates(p.copy(nodeQuantBits = 8)) == Roofline.IuRates(2, 2))
    assert(Roofline.iuRates(p).nodesPerCycle == 0.25 && Roofline.iuRates(p).primsPerCycle == 0.5)
  }

  test("directed: a run at the memory roof, one at the IU roof, one far below both") {
    // 1000 rays, 4 B/cycle sustained: 128 000 B over 32 000 cycles is exactly the memory roof
    val mem = Roofline.of(p, run(1000, 32000, nodes = 1000, prims = 1000, beats = 4000))
    assert(mem.memoryBound.get == 150e6 * 1000 / 32000 && mem.raysPerS == mem.memoryBound.get)
    assert(mem.fraction.get == 1.0 && mem.binding == "memory" && mem.memUtil == 1.0)
    // all in the caches: 10 nodes + 5 primitives = 50 IU beats per ray, the run takes exactly those cycles
    val iu = Roofline.of(p, run(100, 5000, nodes = 1000, prims = 500, beats = 10))
    assert(iu.computeBound.get == 150e6 / 50 && iu.binding == "compute" && iu.iuUtil == 1.0)
    assert(iu.boxBound.get == 150e6 / 40 && iu.triBound.get == 150e6 / 10)
    // ten times slower than the nearer roof
    val lat = Roofline.of(p, run(100, 50000, nodes = 1000, prims = 500, beats = 10))
    assert(lat.binding == "latency" && math.abs(lat.fraction.get - 0.1) < 1e-12)
    assert(lat.json("nearest_roof").str == "compute" && lat.json("binding").str == "latency")
    // either side of the 80 % line: 128 000 B moved in 40 000 cycles is 80 % of the memory roof
    assert(Roofline.bindsAt == 0.8)
    assert(Roofline.of(p, run(1000, 40000, nodes = 1000, prims = 1000, beats = 4000)).binding == "memory")
    assert(Roofline.of(p, run(1000, 40001, nodes = 1000, prims = 1000, beats = 4000)).binding == "latency")
  }

  test("a ray that needs no memory has no memory bound (null in the JSON), not a division by zero") {
    val r = Roofline.of(p, run(10, 1000, nodes = 10, prims = 10, beats = 0))
    assert(r.memoryBound.isEmpty && r.json("memory_bound") == ujson.Null && r.roof.get._1 == "compute")
    assert(intercept[IllegalArgumentException](Roofline.Run(0, 10, 0, 0, 0, 0, 0, 0, 0)).getMessage.contains("rays"))
  }

  test("the compute bound scales with the IU count and the memory bound with the channels (later IUS= / MEM_CHANNELS=)") {
    val r = run(1000, 100000, nodes = 20000, prims = 8000, beats = 30000)
    val one = Roofline.of(p, r)
    assert(Roofline.resources(p) == Roofline.Resources(1, 1))
    assert(Roofline.resources(p.copy(ius = 4)) == Roofline.Resources(4, 1), "IUS= is what the compute bound scales with")
    assert(Roofline.resources(p.copy(ius = 2, memChannels = 4)) == Roofline.Resources(2, 4), "MEM_CHANNELS= is what the memory bound scales with")
    assert(intercept[IllegalArgumentException](p.copy(memChannels = 3)).getMessage.contains("MEM_CHANNELS"))
    assert(Roofline.of(p.copy(ius = 4), r).computeBound.get == 4 * one.computeBound.get)
    val four = Roofline.of(p, r, Roofline.Resources(ius = 4, memChannels = 2))
    assert(four.computeBound.get == 4 * one.computeBound.get && four.boxBound.get == 4 * one.boxBound.get)
    assert(four.memoryBound.get == 2 * one.memoryBound.get && four.memUtil == one.memUtil / 2 && four.iuUtil == one.iuUtil / 4)
    assert(intercept[IllegalArgumentException](Roofline.Resources(0, 1)).getMessage.contains("IU count"))
    // RESP_ORDER=path: a beat port per kind, so the nearer of the two kinds' bounds (here the boxes') binds
    assert(Roofline.resources(p.copy(respByPath = true)) == Roofline.Resources(1, 1, portPerKind = true))
    val path = Roofline.of(p.copy(respByPath = true), r)
    assert(path.computeBound.get == math.min(one.boxBound.get, one.triBound.get) && path.computeBound.get > one.computeBound.get)
  }

  test("randomized against the bounds written as times: bytes at the sustained rate, beats at one per cycle") {
    val rnd = new scala.util.Random(11)
    for (_ <- 0 until 2000) {
      val q = p.copy(m = Seq(2, 4, 8)(rnd.nextInt(3)), axiDataBits = Seq(128, 256, 512)(rnd.nextInt(3)), tus = 1 + rnd.nextInt(64),
        clockMhz = 50 + rnd.nextInt(300), memory = p.memory.copy(bytesPerSecond = 1e8 + rnd.nextDouble() * 2e10,
          sustainedEfficiency = 0.1 + 0.9 * rnd.nextDouble()))
      val res = Roofline.Resources(1 + rnd.nextInt(4), 1 + rnd.nextInt(4), portPerKind = rnd.nextBoolean())
      val rays = 1L + rnd.nextInt(100000)
      val (nodes, prims, beats) = (rnd.nextInt(5000000).toLong, rnd.nextInt(2000000).toLong, 1L + rnd.nextInt(1000000))
      val cycles = 1L + rnd.nextInt(50000000)
      val r = Roofline.of(q, run(rays, cycles, nodes, prims, beats, tuBusy = rnd.nextInt(q.tus) * cycles / q.tus), res)
      // independent: seconds per ray that the DRAM and the IU port need at best
      val bytesPerBeat = q.axiDataBits / 8
      val dramSecondsPerRay = beats * bytesPerBeat / (q.memory.bytesPerSecond * q.memory.sustainedEfficiency * res.memChannels) / rays
      val nodeBeats = Map(2 -> 64, 4 -> 128, 8 -> 256)(q.m) / bytesPerBeat // 28 B per child, stored in a power of two
      val primBeats = 64 / bytesPerBeat
      // one port for both kinds: their beats add up; a port per kind (RESP_ORDER=path): the busier port's beats
      val portBeats = if (res.portPerKind) math.max(nodes * nodeBeats, prims * primBeats) else nodes * nodeBeats + prims * primBeats
      val iuSecondsPerRay = portBeats.toDouble / (q.clockMhz * 1e6 * res.ius) / rays
      def close(a: Double, b: Double) = math.abs(a - b) <= 1e-9 * math.abs(b)
      assert(close(r.memoryBound.get, 1 / dramSecondsPerRay))
      if (nodes + prims > 0) assert(close(r.computeBound.get, 1 / iuSecondsPerRay)) else assert(r.computeBound.isEmpty)
      assert(close(r.raysPerS, rays / (cycles / (q.clockMhz * 1e6))))
      val nearer = math.min(1 / dramSecondsPerRay, if (nodes + prims > 0) 1 / iuSecondsPerRay else Double.PositiveInfinity)
      assert(close(r.fraction.get, r.raysPerS / nearer))
      assert(r.binding == (if (r.fraction.get < Roofline.bindsAt) "latency" else if (nearer == 1 / dramSecondsPerRay) "memory" else "compute"))
      // the utilisation of each resource is the achieved share of its own roof
      assert(close(r.memUtil, r.raysPerS / r.memoryBound.get))
      if (nodes + prims > 0) assert(close(r.iuUtil, r.raysPerS / r.computeBound.get))
      assert(r.tuUtil >= 0 && r.tuUtil <= 1)
    }
  }

  test("make roofline's TUS list and CSV cells") {
    assert(RooflineCmd.tusList("8 16  32,64") == Seq(8, 16, 32, 64) && RooflineCmd.tusList("") == Nil)
    assert(intercept[InputError](RooflineCmd.tusList("8 x")).getMessage.contains("ROOFLINE_TUS"))
    assert(intercept[InputError](RooflineCmd.tusList("0")).getMessage.contains("ROOFLINE_TUS"))
    assert(RooflineCmd.cell(ujson.Null) == "" && RooflineCmd.cell(ujson.Num(32)) == "32" && RooflineCmd.cell(ujson.Num(0.125)) == "0.125")
    assert(RooflineCmd.cell(ujson.Str("memory")) == "memory")
    assert(RooflineCmd.grid(Seq(8, 16), Seq(1, 2)) == Seq((8, 1), (8, 2), (16, 1), (16, 2)))
    val e = intercept[InputError](RooflineCmd.grid(Seq(8, 6), Seq(1, 4))).getMessage
    assert(e.contains("TUS=6") && e.contains("IUS=4") && e.contains("ROOFLINE_IUS"), e)
    assert(intercept[InputError](RooflineCmd.tusList("0", "ROOFLINE_IUS", "IU")).getMessage.contains("ROOFLINE_IUS must be IU counts"))
  }
}
