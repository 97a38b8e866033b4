package rtaccel.iu

import chisel3._
import rtaccel.config.PlatformParams
import rtaccel.fp.{FpDivPipe, FpFormat, Stager}

/** Cycles from input to result of the fixed-latency pipes a configuration builds (they follow PIPELINE's budget):
  * the box test, the triangle test of TRI_TEST and the TC's ray preparation (1/d of the three axes on one divider). The register map reports them
  * (RegMap.Pipeline), so a host or a waveform reader knows the build's depths.
  * `census`: the three pipes' registers (box, tri with its divider, one ray-preparation divider) as their Stagers
  * counted them (`of` fills it in; the board top, which needs only the latencies, leaves it empty).
  */
final case class PipeLatencies(box: Int, tri: Int, prep: Int, census: Seq[Stager.Census] = Nil)

object PipeLatencies {
  private val memo = scala.collection.concurrent.TrieMap[PipeParams, PipeLatencies]()

  /** The latencies of p's pipes, from an elaboration of the pipes alone (seconds; memoized on the pipes' view, PipeParams).
    * Inside the board top's own elaboration, take them from its instances instead (RtAccelTop does).
    */
  def of(p: PlatformParams): PipeLatencies = {
    // the pipes' own view (PipeParams): the TUs enter only through the width of the TU tag they carry, so make
    // max-tus elaborates once per width, not per TU count
    val key = p.pipes
    memo.getOrElseUpdate(key, {
      val annos = new chisel3.stage.ChiselGeneratorAnnotation(() => new Probe(key)).elaborate
      annos.collectFirst { case d: chisel3.stage.DesignAnnotation[_] => d.design.asInstanceOf[Probe].latencies }.get
    })
  }

  /** Cycles PIPELINE (and the shared operators of TRI_II and BOX_II) add to a node test and to a leaf's triangle tests
    * over the fixed stages of a job per cycle (0, 0 at none and intervals of 1): what the throughput model
    * (cache.Throughput), calibrated there, adds to a ray's latency.
    */
  def extraOverFixed(p: PlatformParams): (Int, Int) = if (p.stageBudget.isEmpty && p.triInterval == 1 && p.boxInterval == 1) (0, 0) else {
    val l = of(p); val f = of(p.copy(pipelining = rtaccel.config.Pipelining.Fixed, triInterval = 1, boxInterval = 1))
    (l.box - f.box, l.tri - f.tri)
  }

  /** The three pipes side by side, inputs left open: elaborated for their latencies only, never emitted. */
  private class Probe(p: PipeParams) extends Module {
    private val box = Module(new BoxPipe(p))
    private val (tri, triBits) = p.triTest match {
      case rtaccel.config.TriTest.Mt => val t = Module(new TriPipe(p)); (t.latency, t.census)
      case rtaccel.config.TriTest.Watertight => val t = Module(new WatertightPipe(p)); (t.latency, t.census)
    }
    private val prep = Module(new FpDivPipe(FpFormat.fp32, p.divStages, p.stageBudget, p.lutInputs))
    val latencies: PipeLatencies = PipeLatencies(box.latency, tri, rtaccel.tc.TraversalController.prepLatency(prep.latency), Seq(box.census, triBits, prep.census))
  }
}
