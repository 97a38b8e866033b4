package rtaccel.iu

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.config.{Pipelining, Presets}

/** PipeLatencies.of memoizes per circuit: two circuits that differ only in what the family puts in them (its DSP
  * tile, its delay chains) must not share an entry.
  */
class PipeLatenciesSpec extends AnyFunSuite {
  test("one budget, two families: the latencies of each family's own pipes, whichever is asked first") {
    val xc = Presets.paper2017.copy(pipelining = Pipelining.Levels(5), family = "xc5v")
    val ecp5 = xc.copy(family = "ecp5")
    assert(xc.stageBudget == ecp5.stageBudget && xc.dspShape != ecp5.dspShape)
    val (a, b) = (PipeLatencies.of(xc), PipeLatencies.of(ecp5))
    // ecp5's multipliers are registered tiles of their own (fp.DspTile, three cycles): the box and triangle
    // pipes are longer there than on the Virtex-5 at the same budget
    assert(b.box > a.box && b.tri > a.tri, s"xc5v $a, ecp5 $b")
    assert(PipeLatencies.of(ecp5.copy(name = "again")) == b && PipeLatencies.of(xc.copy(name = "again")) == a)
  }
}
