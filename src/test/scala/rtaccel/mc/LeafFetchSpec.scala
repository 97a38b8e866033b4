package rtaccel.mc

import scala.util.Random
import chisel3._
import chiseltest._
import org.scalatest.flatspec.AnyFlatSpec

/** LeafFetch.plusConstTimes: base + x * c by compressors, against BigInt arithmetic on the extremes (zero, all ones)
  * and random operands, for the packed row sizes the presets use and constants with one, two and many set bits. */
class LeafFetchSpec extends AnyFlatSpec with ChiselScalatestTester {
  private class Dut(bw: Int, xw: Int, c: Int) extends Module {
    val io = IO(new Bundle { val base = Input(UInt(bw.W)); val x = Input(UInt(xw.W)); val y = Output(UInt()) })
    io.y := LeafFetch.plusConstTimes(io.base, io.x, c)
  }
  behavior of "LeafFetch.plusConstTimes"
  for (c <- Seq(1, 32, 160, 200, 255, 320, 1000)) it should s"equal base + x * $c bit for bit" in {
    val (bw, xw) = (32, 27)
    test(new Dut(bw, xw, c)).withAnnotations(rtaccel.TestSim.cached(s"LeafFetchSpec/c$c")) { dut =>
      val rnd = new Random(c)
      val ones = Seq(BigInt(0), BigInt(1))
      val bases = ones ++ Seq((BigInt(1) << bw) - 1) ++ Seq.fill(200)(BigInt(bw, rnd))
      val xs = ones ++ Seq((BigInt(1) << xw) - 1) ++ Seq.fill(200)(BigInt(xw, rnd))
      for ((b, x) <- bases.zip(xs) ++ (for (b <- bases.take(3); x <- xs.take(3)) yield (b, x))) {
        dut.io.base.poke(b.U); dut.io.x.poke(x.U)
        assert(dut.io.y.peek().litValue == b + x * c, s"base $b + x $x * $c")
      }
    }
  }
}
