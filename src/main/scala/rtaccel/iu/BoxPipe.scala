package rtaccel.iu

import chisel3._
import chisel3.util._
import rtaccel.fp.{Depth, Fp, FpFormat, Timed}

class BoxJob(p: PipeParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val ray = new RayData
  val tmax = UInt(32.W)
  val words = Vec(7 * p.m, UInt(32.W)) // child j: min xyz, max xyz, ref at 7j..7j+6
  val err = Bool()                     // read with a memory error: the words are not to be trusted
}

/** What a box result needs of its job besides the arithmetic. */
class BoxMeta(p: PipeParams) extends Bundle {
  val tu = UInt(p.tuBits.W)
  val err = Bool()
  val cref = Vec(p.m, UInt(32.W))
}

/** M slab tests in parallel, one node per cycle, no stalls. The operation order is that of rtaccel.model.RayBox
  * (docs/numerics.md), so results equal the reference model bit for bit (with BOX_FORMAT narrower than fp32:
  * model.RayBoxOutward, rounded outward so that no box is lost):
  *   1: a = min - o, b = max - o   2: t0 = a*inv, t1 = b*inv   3: lo/hi by NaN-propagating min/max
  *   4: tnear/tfar chains with NaN ignored, hit = tnear <= tfar and the slot is not empty.
  * Each of the four ends in a register; PIPELINE adds registers inside them (fp.Stager), so the latency is
  * `latency` (4 with PIPELINE=none).
  */
class BoxPipe(p: PipeParams) extends Module {
  val io = IO(new Bundle {
    val in = Flipped(Valid(new BoxJob(p)))
    val out = Valid(new BoxResult(p))
  })
  private val f = FpFormat.fp32
  private val bf = p.boxFormat
  private val pipe = p.pipe
  private def stage[T <: Data](x: Timed[T]): Timed[T] = pipe.reg(x)
  private def at[T <: Data](x: Timed[T], t: Int): T = pipe.delayTo(x, t).v

  // BOX_II=k: a node every k cycles at most, each subtractor and multiplier shared by k planes of a node (fp.Fold);
  // the input is then held in a register loaded on valid, so that every value of the node stays put for k cycles
  private val ii = p.boxInterval
  private val fold = new rtaccel.fp.Fold(pipe, ii, io.in.valid)
  private val job = fold.input(io.in.bits, BoxPipe.inputDepth)
  private def word(k: Int) = job.map(0)(_.words(k))
  private def o(a: Int) = job.map(0)(_.ray.o(a))
  private def inv(a: Int) = job.map(0)(_.ray.inv(a))
  // per child: t0 x/y/z of the min planes, then t1 of the max planes (stage 2), as the model's RayBox(Reduced)
  private val (t01, tminB, tmaxB) = if (bf == f) {
    val ab = fold.batch(Seq.tabulate(p.m, 6)((c, k) => Seq(word(7 * c + k), o(k % 3))).flatten)(x => stage(Fp.subT(pipe, f, x(0), x(1))))
    (fold.batch(ab.zipWithIndex.map { case (x, i) => Seq(x, inv(i % 3)) })(x => stage(Fp.mulT(pipe, f, x(0), x(1)))),
      job.map(0)(_.ray.tmin), job.map(0)(_.tmax))
  } else outward()

  /** The conservative slab test in the narrower format (docs/numerics.md): min planes' distances rounded
    * down, max planes' up, 1/d taken at the bound that keeps each product on its side, each product rounded
    * toward its side (down for the entry of its slab, up for the exit), tmin down and tmax up.
    */
  private def outward(): (Seq[Timed[UInt]], Timed[UInt], Timed[UInt]) = {
    def const(b: Boolean) = Timed(b.B, 0, 0)
    // (with BOX_II > 1 a shared operator rounds either way: its direction is an operand, selected with the planes)
    def dir(x: Timed[UInt]) = x.map(0)(_(0))
    val ab = if (ii == 1) Seq.tabulate(p.m, 6) { (c, k) =>
      stage(Fp.subDirectedT(pipe, f, bf, word(7 * c + k), o(k % 3), const(k >= 3))) }.flatten
    else fold.batch(Seq.tabulate(p.m, 6)((c, k) => Seq(word(7 * c + k), o(k % 3), Timed((k >= 3).B.asUInt, 0, 0))).flatten)(x =>
      stage(Fp.subDirectedT(pipe, f, bf, x(0), x(1), dir(x(2)))))
    val invLo = Seq.tabulate(3)(a => stage(Fp.convertT(pipe, f, bf, inv(a), const(false))))
    val invHi = Seq.tabulate(3)(a => stage(Fp.convertT(pipe, f, bf, inv(a), const(true))))
    val tmin1 = stage(Fp.convertT(pipe, f, bf, job.map(0)(_.ray.tmin), const(false)))
    val tmax1 = stage(Fp.convertT(pipe, f, bf, job.map(0)(_.tmax), const(true)))
    val invSign = (0 until 3).map(a => inv(a).map(0)(_(f.width - 1))) // only the sign of 1/d is needed past stage 1
    val ops = Seq.tabulate(p.m, 6) { (c, k) =>
      val a = k % 3
      val d = ab(6 * c + k)
      // a min plane bounds the entry (down) unless 1/d < 0 swaps the planes; 1/d taken at the bound that keeps the
      // product on its side: one selection in front of the multiplier
      val Seq(lo, hi, dd) = pipe.align(Seq(invLo(a), invHi(a), d))
      val iv = pipe.delayTo(invSign(a), dd.at)
      val invNeg = iv.v
      val up = if (k < 3) invNeg else !invNeg
      val useHi = dd.v(bf.width - 1) ^ up
      val pick = Timed(Mux(useHi, hi.v, lo.v), dd.at, Seq(lo, hi, dd, iv).map(_.depth).max + 1)
      Seq(dd, pick, Timed(up.asUInt, dd.at, iv.depth))
    }.flatten
    val t = fold.batch(ops)(x => stage(Fp.mulDirectedT(pipe, bf, x(0), x(1), dir(x(2)))))
    (t, tmin1, tmax1)
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

  private val lohi = Seq.tabulate(p.m, 3) { (c, a) =>
    val t0 = t01(6 * c + a); val t1 = t01(6 * c + 3 + a)
    Seq(stage(Fp.selT(pipe, bf, t0, t1)(Fp.minProp)), stage(Fp.selT(pipe, bf, t0, t1)(Fp.maxProp)))
  }.flatten.flatten
  private val hits = (0 until p.m).map { c =>
    def lo(a: Int) = lohi(6 * c + 2 * a); def hi(a: Int) = lohi(6 * c + 2 * a + 1)
    def chain(start: Timed[UInt], sel: (FpFormat, UInt, UInt) => UInt, planes: Int => Timed[UInt]) =
      (0 until 3).foldLeft(start)((acc, a) => Fp.selT(pipe, bf, acc, planes(a))(sel))
    val tnear = chain(tminB, Fp.maxNum, lo)
    val tfar = chain(tmaxB, Fp.minNum, hi)
    val slack = if (p.boxSlackUlps == 0) tfar else pipe.step(tfar, Depth.carry(bf.width) + 2)(slackUp)
    val le = Fp.cmpT(pipe, bf, tnear, slack)(Fp.le)
    // the TUs rank and cull in fp32: widening is exact
    val near32 = if (bf == f) tnear else Fp.convertT(pipe, bf, f, tnear, Timed(false.B, 0, 0))
    (le, near32)
  }
  // what the result needs of the job besides the arithmetic, carried down the pipe (not the whole job)
  private val meta = job.map(0) { x =>
    val m = Wire(new BoxMeta(p)); m.tu := x.tu; m.err := x.err; m.cref := VecInit((0 until p.m).map(c => x.words(7 * c + 6))); m
  }
  private val live = (0 until p.m).map(c => meta.map(1)(BoxPipe.live(_, c)))
  // Each hit child's rank by entry distance (nearer first; an equal one in an earlier slot first), once here for every
  // TU (the TU pushes its children in this order): a compare of each pair of slots, then a count per slot
  private val nearer = for (lo <- 0 until p.m; hi <- lo + 1 until p.m) yield (lo, hi) -> Fp.cmpT(pipe, f, hits(lo)._2, hits(hi)._2)(Fp.gt)
  private val ranks = {
    val ins: Seq[Timed[UInt]] = hits.map(_._1) ++ live ++ nearer.map(_._2)
    pipe.op(ins, BoxPipe.rankLevels(p.m)) { v =>
      def hit(i: Int) = v(i)(0) && v(p.m + i)(0)
      val gt = nearer.map(_._1).zipWithIndex.map { case (k, n) => k -> v(2 * p.m + n)(0) }.toMap // tnear(lo) > tnear(hi)
      VecInit((0 until p.m).map { j =>
        PopCount((0 until p.m).filter(_ != j).map(i => if (i < j) hit(i) && !gt((i, j)) else hit(i) && gt((j, i))))
      })
    }
  }
  private val (tDone, dDone) = pipe.join(hits.flatMap { case (l, n) => Seq(l, n) } :+ ranks: _*)
  private val j = at(meta, tDone)
  val res = Wire(new BoxResult(p))
  res.tu := j.tu
  res.err := j.err
  for (c <- 0 until p.m) {
    res.tnear(c) := at(hits(c)._2, tDone)
    res.hit(c) := at(hits(c)._1, tDone) && BoxPipe.live(j, c)
    res.cref(c) := j.cref(c)
    res.rank(c) := at(ranks, tDone)(c)
  }
  private val out = stage(Timed(res, tDone, dDone + 1))
  /** Cycles from a job to its result. */
  val latency: Int = out.at
  io.out.bits := out.v
  io.out.valid := pipe.valid(io.in.valid, latency)
  // the IU delivers a node every k cycles at most (PlatformParams checks its beats per node)
  fold.assertSpacing("BoxPipe (BOX_II)")
  /** Its pipeline registers, its divider's included (a census for the cost model). */
  val census: rtaccel.fp.Stager.Census = pipe.census
}

object BoxPipe {
  /** LUT levels in front of the pipe's inputs in the IU (the collection's beat selection and node decode). */
  val inputDepth: Int = 2
  /** A slot can be hit: it holds a child and the node came without error. */
  def live(m: BoxMeta, c: Int): Bool = m.cref(c) =/= 0.U && !m.err
  /** LUT levels of the ranking's count per slot, of M - 1 terms of two bits each (an estimate: a level for each
    * doubling of its inputs past what one LUT6 takes). */
  def rankLevels(m: Int): Int = math.max(1, log2Ceil(2 * (m - 1)) - 1)
}
