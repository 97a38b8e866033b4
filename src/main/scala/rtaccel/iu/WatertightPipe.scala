package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams
import rtaccel.fp.{Fp, FpDivPipe, FpFormat}

/** The watertight ray-triangle test (TRI_TEST=watertight; Woop, Benthin and Wald, JCGT 2013), one primitive per
  * cycle, no stalls, in the operation order of rtaccel.model.RayTriangleWatertight (docs/numerics.md):
  *   1: the shear axes from |d| and Sx, Sy (d * 1/d[kz]); A, B, C = v - o
  *   2: Sx*A[kz], Sy*A[kz], Sz*A[kz] per vertex        3: the sheared x and y of each vertex
  *   4: the six products of U, V, W in binary32 and, exactly, in binary64
  *   5: U, V, W in both formats                          6: binary64 where binary32 gave exactly 0
  *   7: the sign test, U+V and U*Az, V*Bz, W*Cz          8: det, U*Az + V*Bz
  *   then 1/det (pipelined divider) beside T = (U*Az + V*Bz) + W*Cz;  t = T/det, u = V/det, v = W/det; the hit.
  * The per-ray shear is recomputed per primitive instead of being stored with the ray, so the pipe takes the same
  * job as Möller–Trumbore's: two multipliers and a few comparators instead of a wider ray in every IU request.
  */
class WatertightPipe(p: PlatformParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new TriJob(p)))
    val out = Valid(new TriResult(p))
  })
  private val f = FpFormat.fp32
  private val wide = FpFormat.fp64 // the model's Double: the product of two binary32 values is exact there
  private val one = "h3f800000".U(32.W)
  private val zero = 0.U(32.W)
  private def sub(a: UInt, b: UInt) = Fp.sub(f, a, b)
  private def mul(a: UInt, b: UInt) = Fp.mul(f, a, b)
  private def add(a: UInt, b: UInt) = Fp.add(f, a, b)
  private def pick(k: UInt, v: Seq[UInt]): UInt = Mux(k === 0.U, v(0), Mux(k === 1.U, v(1), v(2)))

  /** What a primitive's result needs besides the arithmetic, carried down the pipe. */
  class Meta extends Bundle {
    val tu = UInt(p.tuBits.W)
    val tmin = UInt(32.W)
    val tmax = UInt(32.W)
    val prim = UInt(32.W)
    val last = Bool()
    val err = Bool()
  }
  val in = io.in.bits
  val meta = Wire(new Meta)
  meta.tu := in.tu; meta.tmin := in.ray.tmin; meta.tmax := in.tmax; meta.prim := in.words(9)
  meta.last := in.last; meta.err := in.err

  // stage 1: kz = axis of the largest |d| (ties to the lower axis), kx = kz+1, ky = kx+1 (mod 3)
  val mag = in.ray.d.map(_(30, 0))
  val kz = Mux(mag(0) >= mag(1) && mag(0) >= mag(2), 0.U(2.W), Mux(mag(1) >= mag(2), 1.U(2.W), 2.U(2.W)))
  val kx = Mux(kz === 2.U, 0.U, kz + 1.U)
  val ky = Mux(kx === 2.U, 0.U, kx + 1.U)
  val sz0 = pick(kz, in.ray.inv)
  val s1 = RegNext(VecInit(Seq(mul(pick(kx, in.ray.d), sz0), mul(pick(ky, in.ray.d), sz0), sz0) ++
    (0 until 9).map(k => sub(in.words(k), in.ray.o(k % 3)))))
  val k1 = RegNext(VecInit(kx, ky, kz))
  val m1 = RegNext(meta); val v1 = RegNext(io.in.valid, false.B)
  def rel(v: Int): Seq[UInt] = (0 until 3).map(a => s1(3 + 3 * v + a))

  // stage 2: the shear products; the x and y of each vertex chosen by kx, ky
  val s2 = RegNext(VecInit((0 until 3).flatMap { v =>
    val k = pick(k1(2), rel(v))
    Seq(pick(k1(0), rel(v)), mul(s1(0), k), pick(k1(1), rel(v)), mul(s1(1), k), mul(s1(2), k))
  }))
  val m2 = RegNext(m1); val v2 = RegNext(v1, false.B)

  // stage 3: sheared vertices (x, y, z) of A, B, C
  val s3 = RegNext(VecInit((0 until 3).flatMap(v => Seq(sub(s2(5 * v), s2(5 * v + 1)), sub(s2(5 * v + 2), s2(5 * v + 3)), s2(5 * v + 4)))))
  val m3 = RegNext(m2); val v3 = RegNext(v2, false.B)
  def x(v: Int) = s3(3 * v); def y(v: Int) = s3(3 * v + 1); def z(v: Int) = s3(3 * v + 2)

  // stage 4: U = Cx*By - Cy*Bx, V = Ax*Cy - Ay*Cx, W = Bx*Ay - By*Ax, products in both formats
  private val edges = Seq((x(2), y(1), y(2), x(1)), (x(0), y(2), y(0), x(2)), (x(1), y(0), y(1), x(0)))
  val p32 = RegNext(VecInit(edges.flatMap { case (a, b, c, d) => Seq(mul(a, b), mul(c, d)) }))
  val p64 = RegNext(VecInit(edges.flatMap { case (a, b, c, d) => Seq(Fp.mulWide(f, wide, a, b), Fp.mulWide(f, wide, c, d)) }))
  val zs4 = RegNext(VecInit((0 until 3).map(z)))
  val m4 = RegNext(m3); val v4 = RegNext(v3, false.B)

  // stage 5: the edge functions
  val e32 = RegNext(VecInit((0 until 3).map(k => sub(p32(2 * k), p32(2 * k + 1)))))
  val e64 = RegNext(VecInit((0 until 3).map(k => Fp.sub(wide, p64(2 * k), p64(2 * k + 1)))))
  val zs5 = RegNext(zs4); val m5 = RegNext(m4); val v5 = RegNext(v4, false.B)

  // stage 6: an edge function that is exactly 0 in binary32 takes its exact-sign binary64 value
  val e = RegNext(VecInit((0 until 3).map(k => Mux(Fp.eq(f, e32(k), zero), Fp.convertNearest(wide, f, e64(k)), e32(k)))))
  val zs6 = RegNext(zs5); val m6 = RegNext(m5); val v6 = RegNext(v5, false.B)

  // stage 7: mixed signs miss; U+V; the products of T
  val mixed7 = RegNext(e.map(Fp.lt(f, _, zero)).reduce(_ || _) && e.map(Fp.gt(f, _, zero)).reduce(_ || _))
  val uv7 = RegNext(add(e(0), e(1)))
  val tp7 = RegNext(VecInit((0 until 3).map(k => mul(e(k), zs6(k)))))
  val e7 = RegNext(e); val m7 = RegNext(m6); val v7 = RegNext(v6, false.B)

  // stage 8: det = (U+V)+W, U*Az + V*Bz
  val det8 = RegNext(add(uv7, e7(2)))
  val t8 = RegNext(add(tp7(0), tp7(1)))
  val wcz8 = RegNext(tp7(2))
  val mixed8 = RegNext(mixed7); val e8 = RegNext(e7); val m8 = RegNext(m7); val v8 = RegNext(v7, false.B)

  // divider: 1/det, beside T = (U*Az + V*Bz) + W*Cz
  val div = Module(new FpDivPipe(f, p.divStages))
  div.io.in.valid := v8
  div.io.in.bits.a := one
  div.io.in.bits.b := det8
  val tD = ShiftRegister(add(t8, wcz8), p.divStages)
  val detD = ShiftRegister(det8, p.divStages); val vwD = ShiftRegister(VecInit(e8(1), e8(2)), p.divStages)
  val mixedD = ShiftRegister(mixed8, p.divStages); val mD = ShiftRegister(m8, p.divStages)
  val vD = div.io.out.valid
  val rcp = div.io.out.bits

  // t, u, v
  val tuv = RegNext(VecInit(mul(tD, rcp), mul(vwD(0), rcp), mul(vwD(1), rcp)))
  val det9 = RegNext(detD); val mixed9 = RegNext(mixedD); val m9 = RegNext(mD); val v9 = RegNext(vD, false.B)

  // the hit
  val res = Wire(new TriResult(p))
  res.tu := m9.tu
  res.hit := !mixed9 && !Fp.eq(f, det9, zero) && Fp.ge(f, tuv(0), m9.tmin) && Fp.lt(f, tuv(0), m9.tmax) && !m9.err
  res.t := tuv(0); res.u := tuv(1); res.v := tuv(2)
  res.prim := m9.prim
  res.last := m9.last
  res.err := m9.err
  io.out.bits := RegNext(res)
  io.out.valid := RegNext(v9, false.B)
}

object WatertightPipe {
  /** Cycles from input to output. */
  def latency(p: PlatformParams): Int = 10 + p.divStages
}
