package rtaccel.fp

import chisel3._
import chisel3.util._
import chiseltest._

/** Ports for `lanes` parallel copies of every Fp function in one format. `in` packs lane i's a at bits
  * [2Wi, 2Wi+W) and b at [2Wi+W, 2W(i+1)); `out` packs per lane (lane i at offset i*laneBits) the 8 value
  * results (FpOps order, op k at k*W) followed by 5 compare bits.
  */
class FpLanePorts(val f: FpFormat, val lanes: Int) extends Bundle {
  val in = Input(UInt((2 * f.width * lanes).W))
  val out = Output(UInt((lanes * FpLanePorts.laneBits(f)).W))
}
object FpLanePorts {
  def laneBits(f: FpFormat): Int = FpOps.numValueOps * f.width + 5
}

/** Purely combinational test module (registers nothing) for chiseltest, which wants a clocked Module. */
class FpOpsHarness(fmts: Seq[(FpFormat, Int)]) extends Module {
  val io = IO(MixedVec(fmts.map { case (f, l) => new FpLanePorts(f, l) }))
  private val core = Module(new FpOpsComb(fmts))
  io <> core.io
}

/** One FpLanePorts per (format, lanes), every Fp function on every lane; no clock. */
class FpOpsComb(fmts: Seq[(FpFormat, Int)]) extends RawModule {
  val io = IO(MixedVec(fmts.map { case (f, l) => new FpLanePorts(f, l) }))
  for (((f, lanes), p) <- fmts.zip(io)) {
    val W = f.width
    val laneOuts = (0 until lanes).map { i =>
      val a = p.in(2 * W * i + W - 1, 2 * W * i)
      val b = p.in(2 * W * (i + 1) - 1, 2 * W * i + W)
      val vals = Seq(Fp.add(f, a, b), Fp.sub(f, a, b), Fp.mul(f, a, b), Fp.div(f, a, b),
        Fp.minNum(f, a, b), Fp.maxNum(f, a, b), Fp.minProp(f, a, b), Fp.maxProp(f, a, b))
      val cmps = Seq(Fp.lt(f, a, b), Fp.le(f, a, b), Fp.gt(f, a, b), Fp.ge(f, a, b), Fp.eq(f, a, b))
      Cat((vals ++ cmps.map(_.asUInt)).reverse)
    }
    p.out := Cat(laneOuts.reverse)
  }
}

/** Drives FpLanePorts from Scala: batches of `lanes` operand pairs per poke/peek. */
object FpHarnessDriver {
  private val two64 = BigInt(1) << 64
  /** Raw bits as a nonnegative BigInt (fp64 patterns with the sign bit set are negative Longs). */
  def unsigned(x: Long): BigInt = if (x < 0) BigInt(x) + two64 else BigInt(x)

  /** Runs every pair through all ops, checking against `ref`; returns the number of pairs. */
  def run(p: FpLanePorts, pairs: Iterator[(Long, Long)], ref: (Int, Long, Long) => Long, chk: FpCheck): Long = {
    val f = p.f
    val W = f.width
    val lanes = p.lanes
    val lb = FpLanePorts.laneBits(f)
    val wMask = (BigInt(1) << W) - 1
    var count = 0L
    val buf = new Array[(Long, Long)](lanes)
    while (pairs.hasNext) {
      var k = 0
      var in = BigInt(0)
      while (k < lanes && pairs.hasNext) {
        val (a, b) = pairs.next()
        buf(k) = (a, b)
        in |= (unsigned(a) | (unsigned(b) << W)) << (2 * W * k)
        k += 1
      }
      p.in.poke(in)
      val out = p.out.peekInt()
      var i = 0
      while (i < k) {
        val (a, b) = buf(i)
        val lane = out >> (i * lb)
        var op = 0
        while (op < FpOps.numValueOps) {
          val got = ((lane >> (op * W)) & wMask).toLong
          chk.check(op, a, b, got, ref(op, a, b))
          op += 1
        }
        val cmp = ((lane >> (FpOps.numValueOps * W)) & 31).toInt
        while (op < FpOps.n) {
          chk.check(op, a, b, ((cmp >> (op - FpOps.numValueOps)) & 1).toLong, ref(op, a, b))
          op += 1
        }
        i += 1
      }
      count += k
    }
    count
  }
}

/** Inputs and packed outputs of several FpDivPipe instances (one per stage count) in one format. */
class DivPipePorts(val f: FpFormat, val stageList: Seq[Int]) extends Bundle {
  val valid = Input(Bool())
  val a = Input(UInt(f.width.W))
  val b = Input(UInt(f.width.W))
  val outValid = Output(UInt(stageList.length.W))
  val outBits = Output(UInt((stageList.length * f.width).W))
}

/** For each format, FpDivPipe instances with every stage count in stageList, fed the same stream. */
class DivPipeHarness(fmts: Seq[FpFormat], stageList: Seq[Int]) extends Module {
  val io = IO(MixedVec(fmts.map(f => new DivPipePorts(f, stageList))))
  for ((f, p) <- fmts.zip(io)) {
    val pipes = stageList.map(s => Module(new FpDivPipe(f, s)))
    for (d <- pipes) {
      d.io.in.valid := p.valid
      d.io.in.bits.a := p.a
      d.io.in.bits.b := p.b
    }
    p.outValid := Cat(pipes.map(_.io.out.valid).reverse)
    p.outBits := Cat(pipes.map(_.io.out.bits).reverse)
  }
}
