package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.fp.{Depth, Fp, FpDivPipe, FpFormat, Timed}

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
class WatertightPipe(p: PipeParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new TriJob(p)))
    val out = Valid(new TriResult(p))
  })
  private val f = FpFormat.fp32
  private val wide = FpFormat.fp64 // the model's Double: the product of two binary32 values is exact there
  private val pipe = p.pipe
  private def lit(x: BigInt) = Timed(x.U(32.W), 0, 0)
  private val one = lit(0x3f800000L)
  private val zero = lit(0)
  private def stage[T <: Data](x: Timed[T]): Timed[T] = pipe.reg(x)
  private def sub(a: Timed[UInt], b: Timed[UInt]) = Fp.subT(pipe, f, a, b)
  private def mul(a: Timed[UInt], b: Timed[UInt]) = Fp.mulT(pipe, f, a, b)
  private def add(a: Timed[UInt], b: Timed[UInt]) = Fp.addT(pipe, f, a, b)
  private def cmp(a: Timed[UInt], b: Timed[UInt])(fn: (FpFormat, UInt, UInt) => Bool) = Fp.cmpT(pipe, f, a, b)(fn)
  private def pick(k: UInt, v: Seq[UInt]): UInt = Mux(k === 0.U, v(0), Mux(k === 1.U, v(1), v(2)))
  /** One of three values by an axis index, as a segment of two LUT levels. */
  private def pickT(k: Timed[UInt], v: Seq[Timed[UInt]]): Timed[UInt] = pipe.op(k +: v, 2)(x => pick(x(0), x.tail))

  // TRI_II=k: a job every k cycles at most, each multiplier and adder shared by k operations of a job (fp.Fold), the
  // input held in a register loaded on valid (TriPipe's scheme); k = 1 is the pipe of a job per cycle
  private val ii = p.triInterval
  private val fold = new rtaccel.fp.Fold(pipe, ii, io.in.valid)
  private val job = fold.input(io.in.bits, TriPipe.inputDepth)
  private def field(fn: TriJob => UInt) = job.map(0)(fn)

  // 1: kz = axis of the largest |d| (ties to the lower axis), kx = kz+1, ky = kx+1 (mod 3)
  private val axes = pipe.step(job, Depth.carry(31) + 2) { in =>
    val mag = in.ray.d.map(_(30, 0))
    val kz = Mux(mag(0) >= mag(1) && mag(0) >= mag(2), 0.U(2.W), Mux(mag(1) >= mag(2), 1.U(2.W), 2.U(2.W)))
    val kx = Mux(kz === 2.U, 0.U, kz + 1.U)
    val ky = Mux(kx === 2.U, 0.U, kx + 1.U)
    VecInit(kx, ky, kz)
  }
  private def k(i: Int) = axes.map(0)(_(i))
  private val dv = (0 until 3).map(a => field(_.ray.d(a)))
  private val sz0 = pickT(k(2), (0 until 3).map(a => field(_.ray.inv(a))))
  private val Seq(sx, sy) = fold.batch(Seq(Seq(pickT(k(0), dv), sz0), Seq(pickT(k(1), dv), sz0)))(x => stage(mul(x(0), x(1))))
  private val sz = stage(sz0)
  private val rel = fold.batch(for (v <- 0 until 3; a <- 0 until 3) yield Seq(field(_.words(3 * v + a)), field(_.ray.o(a))))(x =>
    stage(sub(x(0), x(1)))).grouped(3).toSeq
  private val k1 = (0 until 3).map(i => stage(k(i)))

  // 2, 3: the shear products and the sheared x, y, z of each vertex A, B, C
  private val kzs = (0 until 3).map(v => pickT(k1(2), rel(v)))
  private val shears = fold.batch(for (v <- 0 until 3; s <- Seq(sx, sy, sz)) yield Seq(s, kzs(v)))(x => stage(mul(x(0), x(1)))).grouped(3).toSeq
  private val xy = fold.batch(for (v <- 0 until 3; i <- 0 until 2) yield Seq(stage(pickT(k1(i), rel(v))), shears(v)(i)))(x =>
    stage(sub(x(0), x(1)))).grouped(2).toSeq
  private val zs = (0 until 3).map(v => stage(shears(v)(2)))
  private def x(v: Int) = xy(v)(0); private def y(v: Int) = xy(v)(1); private def z(v: Int) = zs(v)

  // 4, 5: U = Cx*By - Cy*Bx, V = Ax*Cy - Ay*Cx, W = Bx*Ay - By*Ax, products in both formats
  private val edges = Seq((x(2), y(1), y(2), x(1)), (x(0), y(2), y(0), x(2)), (x(1), y(0), y(1), x(0)))
  private val factors = edges.flatMap { case (a, b, c, d) => Seq(Seq(a, b), Seq(c, d)) }
  private val e32 = fold.batch(fold.batch(factors)(x => stage(mul(x(0), x(1)))).grouped(2).toSeq)(x => stage(sub(x(0), x(1))))
  private val e64 = fold.batch(fold.batch(factors)(x => stage(Fp.mulWideT(pipe, f, wide, x(0), x(1)))).grouped(2).toSeq)(x =>
    stage(Fp.subT(pipe, wide, x(0), x(1))))

  // 6: an edge function that is exactly 0 in binary32 takes its exact-sign binary64 value
  private val e = (0 until 3).map { i =>
    val isZero = cmp(e32(i), zero)(Fp.eq)
    val narrowed = Fp.convertNearestT(pipe, wide, f, e64(i))
    stage(pipe.op(Seq(isZero.map(0)(_.asUInt), narrowed, e32(i)), 1)(v => Mux(v(0)(0), v(1), v(2))))
  }

  // 7: mixed signs miss; U+V; the products of T.  8: det = (U+V)+W, U*Az + V*Bz
  private val signs = e.map(x => cmp(x, zero)(Fp.lt)) ++ e.map(x => cmp(x, zero)(Fp.gt))
  private val mixed = stage(pipe.op(signs.map(_.map(0)(_.asUInt)), 1)(v => v.take(3).reduce(_ | _)(0) && v.drop(3).reduce(_ | _)(0)))
  private val tp = fold.batch((0 until 3).map(i => Seq(e(i), z(i))))(x => stage(mul(x(0), x(1))))
  private val (det, tSum) = if (ii == 1) (stage(add(stage(add(e(0), e(1))), e(2))), add(stage(add(tp(0), tp(1))), tp(2)))
  else {
    val firsts = fold.batch(Seq(Seq(e(0), e(1)), Seq(tp(0), tp(1))))(x => stage(add(x(0), x(1))))
    val Seq(d, t) = fold.batch(Seq(Seq(firsts(0), e(2)), Seq(firsts(1), tp(2))))(x => stage(add(x(0), x(1))))
    (d, t)
  }

  // 1/det (pipelined divider) beside T = (U*Az + V*Bz) + W*Cz
  private val div = Module(new FpDivPipe(f, p.divStages, p.stageBudget, p.lutInputs))
  private val detIn = pipe.align(Seq(det, one))
  div.io.in.valid := pipe.valid(io.in.valid, detIn(0).at)
  div.io.in.bits.a := detIn(1).v
  div.io.in.bits.b := detIn(0).v
  // (registered with a budget; with PIPELINE=none the depth is not counted)
  private val rcp = Timed(div.io.out.bits, detIn(0).at + div.latency, 0)

  // t, u, v and the hit
  private val Seq(t, u, v) = fold.batch(Seq(tSum, e(1), e(2)).map(x => Seq(x, rcp)))(x => stage(mul(x(0), x(1))))
  private val conds = Seq(Fp.cmpT(pipe, f, det, zero)((g, a, b) => !Fp.eq(g, a, b)),
    cmp(t, field(_.ray.tmin))(Fp.ge), cmp(t, field(_.tmax))(Fp.lt))
  private val hit = pipe.op((conds.map(_.map(0)(_.asUInt)) :+ mixed.map(0)(_.asUInt)), 1)(c =>
    c.init.map(_.asBool).reduce(_ && _) && !c.last.asBool)
  private val out = TriPipe.finish(p, pipe, job, hit, Seq(t, u, v))
  /** Cycles from a job to its result (10 + divStages with PIPELINE=none). */
  val latency: Int = out.at
  io.out.bits := out.v
  // the divider's valid, carried on to the result
  io.out.valid := ShiftRegister(div.io.out.valid, latency - rcp.at, false.B, true.B)
  // the IU delivers a primitive every k cycles at most (PlatformParams checks its beats per primitive)
  fold.assertSpacing("WatertightPipe (TRI_II)")
  /** Its pipeline registers, its divider's included (a census for the cost model). */
  val census: rtaccel.fp.Stager.Census = pipe.census + div.census
}
