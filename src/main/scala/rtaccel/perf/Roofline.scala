package rtaccel.perf

import rtaccel.config.PlatformParams
import rtaccel.mc.{AxiParams, McGeometry}

/** The roofline of one RTL run (docs/roofline.md): the rays/s it achieved against the two ceilings that no
  * number of TUs can lift, each from the run's own per-ray work.
  *
  * Memory bound: the DRAM's sustained bandwidth (MemoryParams.bytesPerSecond x sustainedEfficiency, what the
  * DRAM model delivers) over the DRAM bytes per ray that reached memory after the caches.
  * Compute bound: what the intersection units can take. The IU assembles a node or a primitive from memory
  * beats that the MC delivers one per cycle (cache hits too), and its box and triangle pipelines accept one
  * whole node / primitive per cycle, so the beat port is its limit: a node costs nodeBeats cycles, a primitive
  * primBeats cycles. Boxes and triangles share the port, so the combined bound is the harmonic sum of the two.
  * RESP_ORDER=path: the MC has a node stream and a primitive stream, each one beat per cycle into its own
  * collection, so each kind has its own port and the combined bound is the smaller of the two.
  */
object Roofline {
  /** The replicated resources each bound scales with: IUS= and MEM_CHANNELS= (this is the one place that reads them),
    * and whether each IU has one beat port for both kinds or one per kind (RESP_ORDER=path). */
  final case class Resources(ius: Int, memChannels: Int, portPerKind: Boolean = false) {
    require(ius >= 1 && memChannels >= 1, s"IU count and memory channels must be >= 1 (got $ius, $memChannels)")
  }
  def resources(p: PlatformParams): Resources = Resources(ius = p.ius, memChannels = p.memChannels, portPerKind = p.respByPath)

  /** What one IU does per cycle, from the RTL's geometry (IntersectionUnit: one beat per cycle). */
  final case class IuRates(nodeBeats: Int, primBeats: Double) {
    def nodesPerCycle: Double = 1.0 / nodeBeats
    def primsPerCycle: Double = 1.0 / primBeats
  }
  def iuRates(p: PlatformParams): IuRates = {
    val g = McGeometry(p, AxiParams.of(p))
    // PRIM_FORMAT=packed: the LeafAssembler cuts one 40 B record per TRI_II cycles out of the beats, so a primitive
    // costs its share of beats but at least TRI_II cycles; the padding of a leaf's last beat is left out, which keeps
    // the bound a ceiling (the RTL can only be slower). slot64's TRI_II is at most its beats
    val prim = if (p.primPacked) math.max(p.triInterval.toDouble, rtaccel.config.Numerics.packedPrimBytes.toDouble / AxiParams.of(p).beatBytes)
      else g.primBeats.toDouble
    IuRates(g.nodeBeats, prim)
  }

  /** A run reaches a roof when it achieves at least this share of it; below, neither roof binds: the requests
    * in flight (one per TU, at most hw.iuOutstanding jobs in the IU) cannot cover the memory and pipeline
    * latency, and the run is latency-bound (docs/roofline.md: sponza stops at 78 % of its memory roof with
    * DRAM never refusing a read, which is this case; conference reaches 90 % of its memory roof).
    */
  val bindsAt: Double = 0.8

  /** The counters of one run that the roofline reads (names of RtAccelTop.counterNames). */
  final case class Run(rays: Long, cycles: Long, nodeRequests: Long, primRequests: Long, memBusyBeats: Long, tuBusyCycles: Long,
                       stallIuArbitration: Long, stallMemoryData: Long, stallMemoryRequest: Long) {
    require(rays > 0 && cycles > 0, s"a roofline needs a run with rays and cycles (got $rays rays, $cycles cycles)")
  }
  object Run {
    def fromCounters(rays: Long, c: String => Long): Run = Run(rays, c("batch_cycles"), c("node_requests"), c("prim_requests"),
      c("mem_busy_beats"), c("tu_busy_cycles"), c("stall_iu_arbitration"), c("stall_memory_data"), c("stall_memory_request"))
  }

  /** rays/s bound of `perRay` units per ray at `unitsPerSecond`; unbounded (None) when a ray needs none. */
  def of(p: PlatformParams, r: Run): Result = of(p, r, resources(p))

  private def bound(unitsPerSecond: Double, perRay: Double): Option[Double] = if (perRay > 0) Some(unitsPerSecond / perRay) else None

  final case class Result(raysPerS: Double, memoryBound: Option[Double], computeBound: Option[Double], boxBound: Option[Double],
                          triBound: Option[Double], dramBytesPerRay: Double, nodesPerRay: Double, primsPerRay: Double,
                          memUtil: Double, iuUtil: Double, tuUtil: Double, stallIuArbitration: Double, stallMemoryData: Double,
                          stallMemoryRequest: Double, res: Resources, rates: IuRates) {
    /** The nearer roof; None only if a ray needed neither memory nor the IU. */
    def roof: Option[(String, Double)] =
      (memoryBound.map("memory" -> _).toSeq ++ computeBound.map("compute" -> _)).minByOption(_._2)
    def fraction: Option[Double] = roof.map(raysPerS / _._2)
    /** "memory" or "compute" when the run reaches that roof (bindsAt), else "latency". */
    def binding: String = roof match {
      case Some((name, b)) if raysPerS >= bindsAt * b => name
      case _ => "latency"
    }
    def json: ujson.Obj = {
      def opt(v: Option[Double]): ujson.Value = v.fold[ujson.Value](ujson.Null)(ujson.Num(_))
      ujson.Obj("rays_per_s" -> raysPerS, "memory_bound" -> opt(memoryBound), "compute_bound" -> opt(computeBound),
        "roofline_fraction" -> opt(fraction), "binding" -> binding, "nearest_roof" -> roof.fold[ujson.Value](ujson.Null)(r => ujson.Str(r._1)),
        "compute_bound_box" -> opt(boxBound), "compute_bound_tri" -> opt(triBound),
        "dram_bytes_per_ray" -> dramBytesPerRay, "box_jobs_per_ray" -> nodesPerRay, "tri_jobs_per_ray" -> primsPerRay,
        "iu_nodes_per_cycle" -> rates.nodesPerCycle, "iu_prims_per_cycle" -> rates.primsPerCycle, "ius" -> res.ius, "mem_channels" -> res.memChannels,
        "util_memory" -> memUtil, "util_iu" -> iuUtil, "util_tu" -> tuUtil,
        "stall_iu_arbitration" -> stallIuArbitration, "stall_memory_data" -> stallMemoryData, "stall_memory_request" -> stallMemoryRequest,
        "binds_at" -> bindsAt)
    }
  }

  def of(p: PlatformParams, r: Run, res: Resources): Result = {
    val rates = iuRates(p); val axi = AxiParams.of(p)
    val clock = p.cyclesPerSecond
    val n = r.rays.toDouble; val cyc = r.cycles.toDouble
    val dramBytes = r.memBusyBeats.toDouble * axi.beatBytes / n
    val nodes = r.nodeRequests / n; val prims = r.primRequests / n
    // one channel's share of the platform's total, times the channels of `res` (a what-if may name other counts)
    val sustained = p.memBytesPerSecondTotal / p.memChannels * res.memChannels
    val iuBeatsPerS = clock * res.ius
    // beats per ray on the busiest IU port: both kinds share one, or each kind has its own (RESP_ORDER=path)
    def port(a: Double, b: Double) = if (res.portPerKind) math.max(a, b) else a + b
    val nodeBeats = r.nodeRequests.toDouble * rates.nodeBeats; val primBeats = r.primRequests.toDouble * rates.primBeats
    Result(
      raysPerS = n / cyc * clock,
      memoryBound = bound(sustained, dramBytes),
      computeBound = bound(iuBeatsPerS, port(nodes * rates.nodeBeats, prims * rates.primBeats)),
      boxBound = bound(iuBeatsPerS, nodes * rates.nodeBeats), triBound = bound(iuBeatsPerS, prims * rates.primBeats),
      dramBytesPerRay = dramBytes, nodesPerRay = nodes, primsPerRay = prims,
      // each utilisation is achieved / that resource's bound: the busiest resource is the nearest roof
      memUtil = r.memBusyBeats.toDouble * axi.beatBytes / (cyc * sustained / clock),
      iuUtil = port(nodeBeats, primBeats) / (cyc * res.ius),
      tuUtil = r.tuBusyCycles / (cyc * p.tus),
      // shares: of TU-cycles waiting for the IU's arbiter; of cycles the IU waits for a beat; of cycles DRAM refuses a read
      stallIuArbitration = r.stallIuArbitration / (cyc * p.tus), stallMemoryData = r.stallMemoryData / cyc,
      stallMemoryRequest = r.stallMemoryRequest / cyc, res = res, rates = rates)
  }
}
