package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.config.PlatformParams
import rtaccel.fp.{Fp, FpDivPipe, FpFormat}

class TriJob(p: PlatformParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val ray = new RayData
  val tmax = UInt(32.W)
  val words = Vec(10, UInt(32.W)) // v0, v1, v2 (9 floats) and the scene triangle id
  val last = Bool()
  val err = Bool()                // read with a memory error: never a hit
}

/** Möller–Trumbore, one primitive per cycle, no stalls, in the operation order of
  * rtaccel.model.RayTriangle (docs/numerics.md):
  *   1: e1 = v1-v0, e2 = v2-v0, s = o-v0          2: the six products of d x e2 and of s x e1
  *   3: p = d x e2, q = s x e1                     4: products of e1.p, s.p, d.q, e2.q
  *   5: first sums of the four dot products        6: det, u', v', t'
  *   7..: inv = 1/det (pipelined divider)          then u = u'*inv, v = v'*inv, t = t'*inv
  *   last: u+v and the hit conditions.
  * TRI_FORMAT (p.triFormat, fp32 or wider): the fp32 inputs (o, d, vertices, tmin, tmax) are widened exactly where
  * they are used, every operation above rounds in that format (model.RayTriangleWide), the hit conditions compare
  * in it, and t, u, v are rounded to fp32 (nearest even) for the result in the last stage, beside the conditions:
  * the same stages and latency in every format; with fp32 the widening and rounding are wires.
  */
class TriPipe(p: PlatformParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new TriJob(p)))
    val out = Valid(new TriResult(p))
  })
  private val f = p.triFormat
  private val one = (BigInt(f.bias) << f.manBits).U(f.width.W)
  private val zero = 0.U(f.width.W)
  private def wide(x: UInt) = Fp.widen(FpFormat.fp32, f, x)
  private def narrow(x: UInt) = if (f == FpFormat.fp32) x else Fp.convertNearest(f, FpFormat.fp32, x)
  private def sub(a: UInt, b: UInt) = Fp.sub(f, a, b)
  private def mul(a: UInt, b: UInt) = Fp.mul(f, a, b)
  private def add(a: UInt, b: UInt) = Fp.add(f, a, b)

  // stage 1
  val in = io.in.bits
  def vtx(v: Int, a: Int) = wide(in.words(3 * v + a))
  val s1 = RegNext(VecInit((0 until 3).map(a => sub(vtx(1, a), vtx(0, a))) ++ (0 until 3).map(a => sub(vtx(2, a), vtx(0, a))) ++
    (0 until 3).map(a => sub(wide(in.ray.o(a)), vtx(0, a)))))
  val j1 = RegNext(in); val v1 = RegNext(io.in.valid, false.B)
  def e1(a: Int) = s1(a); def e2(a: Int) = s1(3 + a); def s(a: Int) = s1(6 + a)
  // stage 2: cross products as a.i*b.j - a.j*b.i, products first
  private def crossProducts(a: Int => UInt, b: Int => UInt) =
    Seq(mul(a(1), b(2)), mul(a(2), b(1)), mul(a(2), b(0)), mul(a(0), b(2)), mul(a(0), b(1)), mul(a(1), b(0)))
  val d1 = (k: Int) => wide(j1.ray.d(k))
  val s2 = RegNext(VecInit(crossProducts(d1, e2) ++ crossProducts(s, e1)))
  val e2r = RegNext(VecInit((0 until 6).map(s1(_)))) // e1, e2 carried
  val sr = RegNext(VecInit((0 until 3).map(s(_))))
  val j2 = RegNext(j1); val v2 = RegNext(v1, false.B)
  // stage 3
  val s3 = RegNext(VecInit((0 until 6).map(k => sub(s2(2 * k), s2(2 * k + 1))))) // p xyz, q xyz
  val e3 = RegNext(e2r); val sr3 = RegNext(sr)
  val j3 = RegNext(j2); val v3 = RegNext(v2, false.B)
  def pp(a: Int) = s3(a); def qq(a: Int) = s3(3 + a)
  // stage 4: products of the four dot products e1.p, s.p, d.q, e2.q
  val s4 = RegNext(VecInit(
    (0 until 3).map(a => mul(e3(a), pp(a))) ++ (0 until 3).map(a => mul(sr3(a), pp(a))) ++
      (0 until 3).map(a => mul(wide(j3.ray.d(a)), qq(a))) ++ (0 until 3).map(a => mul(e3(3 + a), qq(a)))))
  val j4 = RegNext(j3); val v4 = RegNext(v3, false.B)
  // stage 5: (p0 + p1)
  val s5 = RegNext(VecInit((0 until 4).map(k => add(s4(3 * k), s4(3 * k + 1)))))
  val s5c = RegNext(VecInit((0 until 4).map(k => s4(3 * k + 2))))
  val j5 = RegNext(j4); val v5 = RegNext(v4, false.B)
  // stage 6: + p2 -> det, u', v', t'
  val s6 = RegNext(VecInit((0 until 4).map(k => add(s5(k), s5c(k)))))
  val j6 = RegNext(j5); val v6 = RegNext(v5, false.B)
  // divider: inv = 1/det
  val div = Module(new FpDivPipe(f, p.divStages))
  div.io.in.valid := v6
  div.io.in.bits.a := one
  div.io.in.bits.b := s6(0)
  val s7 = ShiftRegister(s6, p.divStages); val j7 = ShiftRegister(j6, p.divStages)
  val v7 = div.io.out.valid
  val inv = div.io.out.bits
  // stage 8: u, v, t
  val det8 = RegNext(s7(0))
  val uvt = RegNext(VecInit((1 until 4).map(k => mul(s7(k), inv))))
  val j8 = RegNext(j7); val v8 = RegNext(v7, false.B)
  // stage 9: conditions
  val u = uvt(0); val v = uvt(1); val t = uvt(2)
  val res = Wire(new TriResult(p))
  res.tu := j8.tu
  res.hit := !Fp.eq(f, det8, zero) && Fp.ge(f, u, zero) && Fp.ge(f, v, zero) && Fp.le(f, add(u, v), one) &&
    Fp.ge(f, t, wide(j8.ray.tmin)) && Fp.lt(f, t, wide(j8.tmax)) && !j8.err
  res.t := narrow(t); res.u := narrow(u); res.v := narrow(v)
  res.prim := j8.words(9)
  res.last := j8.last
  res.err := j8.err
  io.out.bits := RegNext(res)
  io.out.valid := RegNext(v8, false.B)
}

object TriPipe {
  /** Pipelined dividers per triangle pipe (1/det), in either TRI_TEST (the cost model counts them). */
  val dividers: Int = 1
  /** Cycles from input to output. */
  def latency(p: PlatformParams): Int = 8 + p.divStages
}
