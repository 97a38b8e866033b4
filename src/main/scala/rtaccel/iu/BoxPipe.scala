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
  * that of rtaccel.model.RayBox (docs/numerics.md), so results equal the reference model bit for bit:
  *   1: a = min - o, b = max - o   2: t0 = a*inv, t1 = b*inv   3: lo/hi by NaN-propagating min/max
  *   4: tnear/tfar chains with NaN ignored, hit = tnear <= tfar and the slot is not empty.
  */
class BoxPipe(p: PlatformParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new BoxJob(p)))
    val out = Valid(new BoxResult(p))
  })
  private val f = FpFormat.fp32
  private def stage[T <: Data](x: T): T = RegNext(x)
  private val v1 = RegNext(io.in.valid, false.B); private val v2 = RegNext(v1, false.B)
  private val v3 = RegNext(v2, false.B); private val v4 = RegNext(v3, false.B)

  val j1 = stage(io.in.bits)
  val ab = stage(VecInit(Seq.tabulate(p.m, 6) { (c, k) => Fp.sub(f, io.in.bits.words(7 * c + k), io.in.bits.ray.o(k % 3)) }.flatten))
  val j2 = stage(j1)
  val t01 = stage(VecInit(Seq.tabulate(p.m, 6) { (c, k) => Fp.mul(f, ab(6 * c + k), j1.ray.inv(k % 3)) }.flatten))
  val j3 = stage(j2)
  val lohi = stage(VecInit(Seq.tabulate(p.m, 3) { (c, a) =>
    val t0 = t01(6 * c + a); val t1 = t01(6 * c + 3 + a)
    Seq(Fp.minProp(f, t0, t1), Fp.maxProp(f, t0, t1))
  }.flatten.flatten))
  io.out.valid := v4
  val res = Wire(new BoxResult(p))
  res.tu := j3.tu
  res.err := j3.err
  for (c <- 0 until p.m) {
    def lo(a: Int) = lohi(6 * c + 2 * a); def hi(a: Int) = lohi(6 * c + 2 * a + 1)
    val tnear = Fp.maxNum(f, Fp.maxNum(f, Fp.maxNum(f, j3.ray.tmin, lo(0)), lo(1)), lo(2))
    val tfar = Fp.minNum(f, Fp.minNum(f, Fp.minNum(f, j3.tmax, hi(0)), hi(1)), hi(2))
    res.tnear(c) := tnear
    res.hit(c) := Fp.le(f, tnear, tfar) && j3.words(7 * c + 6) =/= 0.U && !j3.err
    res.cref(c) := j3.words(7 * c + 6)
  }
  io.out.bits := RegNext(res)
}
