package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams
import rtaccel.fp.{Fp, FpFormat}

class BoxJob(p: PlatformParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val ray = new RayData
  val tmax = UInt(32.W)
  val words = Vec(7 * p.m, UInt(32.W)) // child j: min xyz, max xyz, ref at 7j..7j+6
  val err = Bool()                     // read with a memory error: the words are not to be trusted
}

/** M slab tests in parallel, four register levels, one node per cycle, no stalls. The operation order is
  * that of rtaccel.model.RayBox (docs/numerics.md), so results equal the reference model bit for bit
  * (with BOX_FORMAT narrower than fp32: model.RayBoxOutward, rounded outward so that no box is lost):
  *   1: a = min - o, b = max - o   2: t0 = a*inv, t1 = b*inv   3: lo/hi by NaN-propagating min/max
  *   4: tnear/tfar chains with NaN ignored, hit = tnear <= tfar and the slot is not empty.
  */
class BoxPipe(p: PlatformParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new BoxJob(p)))
    val out = Valid(new BoxResult(p))
  })
  private val f = FpFormat.fp32
  private val bf = p.boxFormat
  private def stage[T <: Data](x: T): T = RegNext(x)
  private val v1 = RegNext(io.in.valid, false.B); private val v2 = RegNext(v1, false.B)
  private val v3 = RegNext(v2, false.B); private val v4 = RegNext(v3, false.B)

  val j1 = stage(io.in.bits)
  val j2 = stage(j1)
  val j3 = stage(j2)
  // per child: t0 x/y/z of the min planes, then t1 of the max planes (stage 2), as the model's RayBox(Reduced)
  val (t01, tminB, tmaxB) = if (bf == f) {
    val ab = stage(VecInit(Seq.tabulate(p.m, 6) { (c, k) => Fp.sub(f, io.in.bits.words(7 * c + k), io.in.bits.ray.o(k % 3)) }.flatten))
    (stage(VecInit(Seq.tabulate(p.m, 6) { (c, k) => Fp.mul(f, ab(6 * c + k), j1.ray.inv(k % 3)) }.flatten)), j3.ray.tmin, j3.tmax)
  } else outward()

  /** The conservative slab test in the narrower format (docs/numerics.md): min planes' distances rounded
    * down, max planes' up, 1/d taken at the bound that keeps each product on its side, each product rounded
    * toward its side (down for the entry of its slab, up for the exit), tmin down and tmax up.
    */
  private def outward(): (Vec[UInt], UInt, UInt) = {
    val in = io.in.bits
    val ab = stage(VecInit(Seq.tabulate(p.m, 6) { (c, k) =>
      Fp.subDirected(f, bf, in.words(7 * c + k), in.ray.o(k % 3), toPos = (k >= 3).B) }.flatten))
    val invLo = stage(VecInit(Seq.tabulate(3)(a => Fp.convert(f, bf, in.ray.inv(a), false.B))))
    val invHi = stage(VecInit(Seq.tabulate(3)(a => Fp.convert(f, bf, in.ray.inv(a), true.B))))
    val tmin1 = stage(Fp.convert(f, bf, in.ray.tmin, false.B)); val tmax1 = stage(Fp.convert(f, bf, in.tmax, true.B))
    val invNeg1 = stage(VecInit(in.ray.inv.map(_(f.width - 1)))) // only the sign of 1/d is needed past stage 1
    val t = stage(VecInit(Seq.tabulate(p.m, 6) { (c, k) =>
      val a = k % 3
      val invNeg = invNeg1(a)
      val up = if (k < 3) invNeg else !invNeg // a min plane bounds the entry (down) unless 1/d < 0 swaps the planes
      val d = ab(6 * c + k)
      val useHi = d(bf.width - 1) ^ up
      Fp.mulDirected(bf, d, Mux(useHi, invHi(a), invLo(a)), up)
    }.flatten))
    (t, RegNext(RegNext(tmin1)), RegNext(RegNext(tmax1)))
  }

  /** tfar moved p.boxSlackUlps ulps toward +inf on its bits (TRI_TEST=watertight; model.BoxSlack): an adder, not
    * a multiplier. Positive values grow (at most to +inf), negative ones shrink toward zero and past it.
    */
  private def slackUp(x: UInt): UInt = if (p.boxSlackUlps == 0) x else {
    val k = p.boxSlackUlps.U; val w = bf.width
    val mag = x(w - 2, 0); val inf = (BigInt(bf.maxExp) << bf.manBits).U((w - 1).W)
    val grown = mag +& k
    Mux(mag > inf, x, Mux(!x(w - 1), Cat(0.U(1.W), Mux(grown > inf, inf, grown(w - 2, 0))),
      Mux(mag > k, Cat(1.U(1.W), mag - k), Cat(0.U(1.W), k - mag))))
  }

  val lohi = stage(VecInit(Seq.tabulate(p.m, 3) { (c, a) =>
    val t0 = t01(6 * c + a); val t1 = t01(6 * c + 3 + a)
    Seq(Fp.minProp(bf, t0, t1), Fp.maxProp(bf, t0, t1))
  }.flatten.flatten))
  io.out.valid := v4
  val res = Wire(new BoxResult(p))
  res.tu := j3.tu
  res.err := j3.err
  for (c <- 0 until p.m) {
    def lo(a: Int) = lohi(6 * c + 2 * a); def hi(a: Int) = lohi(6 * c + 2 * a + 1)
    val tnear = Fp.maxNum(bf, Fp.maxNum(bf, Fp.maxNum(bf, tminB, lo(0)), lo(1)), lo(2))
    val tfar = Fp.minNum(bf, Fp.minNum(bf, Fp.minNum(bf, tmaxB, hi(0)), hi(1)), hi(2))
    // the TUs rank and cull in fp32: widening is exact
    res.tnear(c) := (if (bf == f) tnear else Fp.convert(bf, f, tnear, false.B))
    res.hit(c) := Fp.le(bf, tnear, slackUp(tfar)) && j3.words(7 * c + 6) =/= 0.U && !j3.err
    res.cref(c) := j3.words(7 * c + 6)
  }
  io.out.bits := RegNext(res)
}
