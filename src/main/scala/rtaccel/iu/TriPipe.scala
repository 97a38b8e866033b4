package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.fp.{Depth, Fp, FpDivPipe, FpFormat, Timed}

class TriJob(p: PipeParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val ray = new RayData
  val tmax = UInt(32.W)
  val words = Vec(10, UInt(32.W)) // v0, v1, v2 (9 floats) and the scene triangle id
  val last = Bool()
  val err = Bool()                // read with a memory error: never a hit
}

/** What a triangle result needs of its job besides the arithmetic, carried down the pipe (not the whole job). */
class TriMeta(p: PipeParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val prim = UInt(32.W)
  val last = Bool()
  val err = Bool()
}
object TriMeta {
  def apply(p: PipeParams, j: TriJob): TriMeta = {
    val m = Wire(new TriMeta(p)); m.tu := j.tu; m.prim := j.words(9); m.last := j.last; m.err := j.err; m
  }
}

/** Möller–Trumbore, one primitive per cycle, no stalls, in the operation order of
  * rtaccel.model.RayTriangle (docs/numerics.md):
  *   1: e1 = v1-v0, e2 = v2-v0, s = o-v0          2: the six products of d x e2 and of s x e1
  *   3: p = d x e2, q = s x e1                     4: products of e1.p, s.p, d.q, e2.q
  *   5: first sums of the four dot products        6: det, u', v', t'
  *   7..: inv = 1/det (pipelined divider)          then u = u'*inv, v = v'*inv, t = t'*inv
  *   last: u+v and the hit conditions.
  * Each ends in a register; PIPELINE adds registers inside them (fp.Stager), so the latency is `latency`
  * (8 + divStages with PIPELINE=none).
  * TRI_FORMAT (p.triFormat, fp32 or wider): the fp32 inputs (o, d, vertices, tmin, tmax) are widened exactly where
  * they are used, every operation above rounds in that format (model.RayTriangleWide), the hit conditions compare
  * in it, and t, u, v are rounded to fp32 (nearest even) for the result in the last stage, beside the conditions:
  * the same stages in every format; with fp32 the widening and rounding are wires.
  */
class TriPipe(p: PipeParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new TriJob(p)))
    val out = Valid(new TriResult(p))
  })
  private val f = p.triFormat
  private val f32 = FpFormat.fp32
  private val pipe = p.pipe
  private def stage[T <: Data](x: Timed[T]): Timed[T] = pipe.reg(x)
  private def lit(x: BigInt) = Timed(x.U(f.width.W), 0, 0)
  private val one = lit(BigInt(f.bias) << f.manBits)
  private val zero = lit(0)
  // widening fp32 into a wider exponent normalises subnormals (a leading-zero count and a shift)
  private def wide(x: Timed[UInt]) = if (f == f32) x else pipe.step(x, Depth.lzc(24) + Depth.shift(24))(Fp.widen(f32, f, _))
  private def narrow(x: Timed[UInt]) = if (f == f32) x else Fp.convertNearestT(pipe, f, f32, x)
  private def sub(a: Timed[UInt], b: Timed[UInt]) = Fp.subT(pipe, f, a, b)
  private def mul(a: Timed[UInt], b: Timed[UInt]) = Fp.mulT(pipe, f, a, b)
  private def add(a: Timed[UInt], b: Timed[UInt]) = Fp.addT(pipe, f, a, b)
  private def cmp(a: Timed[UInt], b: Timed[UInt])(fn: (FpFormat, UInt, UInt) => Bool) = Fp.cmpT(pipe, f, a, b)(fn)

  // TRI_II=k: a job every k cycles at most, each operator shared by k operations of a job (fp.Fold); its input is
  // then held in a register loaded on valid, so that every value of the job stays put for k cycles
  private val k = p.triInterval
  private val fold = new rtaccel.fp.Fold(pipe, k, io.in.valid)
  private val job = fold.input(io.in.bits, TriPipe.inputDepth)
  private def vtx(v: Int, a: Int) = wide(job.map(0)(_.words(3 * v + a)))
  private def d(a: Int) = wide(job.map(0)(_.ray.d(a)))
  // 1
  private val Seq(e1, e2, s) = fold.batch(Seq[Int => Timed[UInt]](vtx(1, _), vtx(2, _), a => wide(job.map(0)(_.ray.o(a)))).flatMap(x =>
    (0 until 3).map(a => Seq(x(a), vtx(0, a)))))(x => stage(sub(x(0), x(1)))).grouped(3).toSeq
  // 2, 3: cross products as a.i*b.j - a.j*b.i, products first
  private val crossAxes = Seq((1, 2), (2, 0), (0, 1))
  private def crossOps(a: Int => Timed[UInt], b: Int => Timed[UInt]) = crossAxes.flatMap { case (i, j) => Seq(Seq(a(i), b(j)), Seq(a(j), b(i))) }
  private val Seq(pv, qv) = fold.batch(fold.batch(crossOps(d, e2) ++ crossOps(s, e1))(x => stage(mul(x(0), x(1)))).grouped(2).toSeq)(x =>
    stage(sub(x(0), x(1)))).grouped(3).toSeq
  // 4: products of the four dot products e1.p, s.p, d.q, e2.q; 5, 6: (x0 + x1) + x2
  private val dots = Seq[(Int => Timed[UInt], Int => Timed[UInt])]((e1, pv), (s, pv), (d, qv), (e2, qv))
  private val prods = fold.batch(dots.flatMap { case (a, b) => (0 until 3).map(c => Seq(a(c), b(c))) })(x => stage(mul(x(0), x(1)))).grouped(3).toSeq
  private val firsts = fold.batch(prods.map(_.take(2)))(x => stage(add(x(0), x(1))))
  private val Seq(det, ut, vt, tt) = fold.batch(firsts.zip(prods).map { case (f0, pr) => Seq(f0, pr(2)) })(x => stage(add(x(0), x(1))))
  private val uvt = Seq(ut, vt, tt)
  // 7..: inv = 1/det
  private val div = Module(new FpDivPipe(f, p.divStages, p.stageBudget, p.lutInputs))
  private val detIn = pipe.align(Seq(det, one)) // the divider reads its operands as they come
  div.io.in.valid := pipe.valid(io.in.valid, detIn(0).at)
  div.io.in.bits.a := detIn(1).v
  div.io.in.bits.b := detIn(0).v
  // (registered with a budget; with PIPELINE=none the depth is not counted)
  private val inv = Timed(div.io.out.bits, detIn(0).at + div.latency, 0)
  // u, v, t
  private val Seq(u, v, t) = fold.batch(uvt.map(x => Seq(x, inv)))(x => stage(mul(x(0), x(1))))
  // the conditions
  private val conds = Seq(Fp.cmpT(pipe, f, det, zero)((g, a, b) => !Fp.eq(g, a, b)), cmp(u, zero)(Fp.ge), cmp(v, zero)(Fp.ge),
    cmp(add(u, v), one)(Fp.le), cmp(t, wide(job.map(0)(_.ray.tmin)))(Fp.ge), cmp(t, wide(job.map(0)(_.tmax)))(Fp.lt))
  private val hit = pipe.op(conds.map(_.map(0)(_.asUInt)), 1)(c => c.map(_.asBool).reduce(_ && _))
  private val out = TriPipe.finish(p, pipe, job, hit, Seq(t, u, v).map(narrow))
  /** Cycles from a job to its result. */
  val latency: Int = out.at
  io.out.bits := out.v
  // the divider's valid, carried on to the result
  io.out.valid := ShiftRegister(div.io.out.valid, latency - inv.at, false.B, true.B)
  // the IU delivers a primitive every k cycles at most (PlatformParams checks its beats per primitive)
  fold.assertSpacing("TriPipe (TRI_II)")
  /** Its pipeline registers, its divider's included (a census for the cost model). */
  val census: rtaccel.fp.Stager.Census = pipe.census + div.census
}

object TriPipe {
  /** What both triangle pipes end in: the hit and t, u, v (fp32) with the job's fields, read when the last of them is
    * ready, into the result register.
    */
  private[iu] def finish(p: PipeParams, pipe: rtaccel.fp.Stager, job: Timed[TriJob], hit: Timed[Bool], tuv: Seq[Timed[UInt]]): Timed[TriResult] = {
    val (tDone, dDone) = pipe.join(Seq(hit) ++ tuv: _*)
    def at[T <: Data](x: Timed[T]) = pipe.delayTo(x, tDone).v
    val j = at(job.map(0)(TriMeta(p, _)))
    val res = Wire(new TriResult(p))
    res.tu := j.tu
    res.hit := at(hit) && !j.err
    res.t := at(tuv(0)); res.u := at(tuv(1)); res.v := at(tuv(2))
    res.prim := j.prim; res.last := j.last; res.err := j.err
    pipe.reg(Timed(res, tDone, dDone + 1))
  }

  /** Pipelined dividers per triangle pipe (1/det), in either TRI_TEST (the cost model counts them). */
  val dividers: Int = 1
  /** LUT levels in front of the pipe's inputs in the IU (the collection's beat selection). */
  val inputDepth: Int = 2
}
