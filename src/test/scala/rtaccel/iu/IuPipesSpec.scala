package rtaccel.iu

import chisel3._
import chisel3.util.Valid
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.config.{PlatformParams, Pipelining, TriTest}
import rtaccel.fp.FpFormat
import rtaccel.model.{PreparedRay, RayBox, RayBoxOutward, RayTriangle}

/** The IU's box and triangle pipelines against the reference model's RayBox / RayTriangle, bit for bit,
  * one job per cycle: random jobs mixed with the edge classes of docs/numerics.md; TriPipe in a wider TRI_FORMAT
  * against its SoftFloat twin (model.RayTriangleWide).
  */
class IuPipesSpec extends AnyFunSuite with ChiselScalatestTester {
  private def bits(f: Float): BigInt = BigInt(java.lang.Float.floatToRawIntBits(f)) & 0xffffffffL
  private val p = PlatformParams(tus = 4, m = 4)
  private val rnd = new Random(42)
  private val specials = Array(0f, -0f, 1f, -1f, Float.MinPositiveValue, -Float.MinPositiveValue, 1e-30f, 1e30f,
    Float.PositiveInfinity, Float.NegativeInfinity, java.lang.Float.MIN_NORMAL, Float.MaxValue)
  private def coord(): Float = rnd.nextInt(10) match {
    case 0 => specials(rnd.nextInt(specials.length))
    case 1 => rnd.nextInt(5) - 2f                          // small integers: exact ties, shared planes
    case _ => (rnd.nextFloat() - 0.5f) * math.pow(2, rnd.nextInt(12) - 4).toFloat
  }
  private def ray(): (Array[Float], PreparedRay, Float) = {
    val o = Array.fill(3)(if (rnd.nextInt(8) == 0) rnd.nextInt(3) - 1f else (rnd.nextFloat() - 0.5f) * 4)
    val d = Array.fill(3)(if (rnd.nextInt(6) == 0) (if (rnd.nextBoolean()) 0f else -0f) else rnd.nextFloat() - 0.5f)
    if (d.forall(_ == 0f)) d(0) = 1f
    val tmin = if (rnd.nextInt(4) == 0) rnd.nextFloat() else 0f
    val tmax = if (rnd.nextInt(3) == 0) tmin + rnd.nextFloat() * 3 else Float.PositiveInfinity
    val r = new PreparedRay(o(0), o(1), o(2), d(0), d(1), d(2), tmin, tmax)
    (o ++ d ++ Array(r.ix, r.iy, r.iz, tmin), r, tmax)
  }
  private def pokeRay(rd: RayData, f: Array[Float]): Unit = {
    for (k <- 0 until 3) { rd.o(k).poke(bits(f(k)).U); rd.d(k).poke(bits(f(3 + k)).U); rd.inv(k).poke(bits(f(6 + k)).U) }
    rd.tmin.poke(bits(f(9)).U)
  }

  // BOX_FORMAT: fp32 against RayBox, narrower formats against RayBoxOutward (the same job stream)
  // (make regress adds fp16 and fp24; each format is one Verilator build of about a minute, and FpDirectedSpec
  // checks fp16's operators in make test)
  // TRI_TEST=watertight adds the exit-distance slack (PlatformParams.boxSlackUlps) to the same pipe
  private val regress = rtaccel.Regress.full
  // random jobs per pipe beside the directed ones: about 40 % of a 20000-job case was its peeks and pokes, so make
  // test drives 8000 and make regress 20000
  private val randoms = if (regress) 20000 else 8000
  // (make test: fp32 and bf16 here; the watertight slack in PlatformSpec's all-formats circuit)
  // PIPELINE: the default (auto: 6 LUT levels at 150 MHz on Virtex-5), the fixed stages (none) and a deep one (3)
  private val auto = Pipelining.Auto; private val fixed = Pipelining.Fixed; private val deep = Pipelining.Levels(3)
  // (make test: the directed-rounding operators of the narrow formats at the deep budget; PlatformSpec has none)
  private val boxFormats = Seq((FpFormat.fp32, TriTest.Mt, randoms, auto), (FpFormat.parse("bf16"), TriTest.Mt, 3000, deep)) ++
    (if (regress) Seq((FpFormat(4, 7), TriTest.Mt, 1500, auto), // what BOX_FORMAT=m7 fits to a unit-scale scene: a 4-bit exponent that overflows
      (FpFormat.fp32, TriTest.Watertight, 5000, deep), (FpFormat.parse("fp16"), TriTest.Mt, 6000, auto), (FpFormat.parse("fp24"), TriTest.Mt, 6000, deep),
      (FpFormat.parse("bf16"), TriTest.Watertight, 6000, auto), (FpFormat.fp32, TriTest.Mt, 5000, fixed), (FpFormat.parse("bf16"), TriTest.Mt, 3000, fixed)) else Nil)
  // BOX_II=k: the subtractors and multipliers shared by k planes of a node (fp.Fold), a node every k or k + 1 cycles
  // with other words between them (make test: 4 at bf16 and none; make regress: 2 at fp32 and auto, 3 at the deep budget)
  private val boxIntervals = Seq((4, FpFormat.parse("bf16"), TriTest.Mt, 1500, fixed)) ++
    (if (regress) Seq((2, FpFormat.fp32, TriTest.Mt, 2000, auto), (3, FpFormat.fp32, TriTest.Watertight, 3000, deep)) else Nil)
  for ((ii, bf, tt, n, pl) <- boxFormats.map { case (b, t, n, l) => (1, b, t, n, l) } ++ boxIntervals)
  test(s"box pipeline (BOX_FORMAT=${bf.name}, TRI_TEST=${tt.name}, PIPELINE=${pl.name}${if (ii > 1) s", BOX_II=$ii" else ""}) == " +
    s"${if (bf == FpFormat.fp32) "RayBox" else "RayBoxOutward"} on $n random and edge-case nodes (M=4), " + (if (ii == 1) "one per cycle" else s"$ii or ${ii + 1} cycles apart")) {
    val pb = p.copy(boxFormat = bf, triTest = tt, pipelining = pl, boxInterval = ii)
    val outward = if (bf == FpFormat.fp32) None else Some(new RayBoxOutward(bf, pb.boxSlackUlps))
    val box = rtaccel.TestSim.firtool(s"IuPipesSpec/box-${bf.name}-${tt.name}-${pl.name}-ii$ii")(new BoxPipe(pb.pipes))(_.io)
    test(box.gen()).withAnnotations(box.annotations) { dut =>
      val lat = box.module.latency
      if (pl == fixed && ii == 1) assert(lat == 4, s"PIPELINE=none keeps the four stages (latency $lat)")
      else assert(lat > 4, s"PIPELINE=${pl.name} adds registers (latency $lat)")
      info(s"latency $lat cycles")
      val expected = scala.collection.mutable.Queue[(Seq[Boolean], Seq[BigInt])]()
      val issued = (1 until n).scanLeft(0)((c, _) => c + ii + (if (ii > 1) rnd.nextInt(2) else 0)).toSet
      for (cycle <- 0 until issued.max + 1 + lat) {
        if (!issued(cycle)) for (i <- 0 until 7 * p.m) dut.io.in.bits.words(i).poke(BigInt(32, rnd).U)
        if (issued(cycle)) {
          val (rf, r, tmax) = ray()
          val words = (0 until p.m).flatMap { c =>
            val a = Array.fill(3)(coord()); val b = Array.fill(3)(coord())
            val lo = a.zip(b).map(x => if (rnd.nextInt(10) == 0) x._1 else math.min(x._1, x._2))
            val hi = a.zip(b).map(x => if (rnd.nextInt(10) == 0) x._2 else math.max(x._1, x._2))
            (lo ++ hi).map(bits) :+ (if (rnd.nextInt(5) == 0) BigInt(0) else BigInt(c + 1))
          }
          dut.io.in.valid.poke(true.B); dut.io.in.bits.tu.poke(1.U); pokeRay(dut.io.in.bits.ray, rf)
          dut.io.in.bits.tmax.poke(bits(tmax).U)
          words.zipWithIndex.foreach { case (w, i) => dut.io.in.bits.words(i).poke(w.U) }
          val res = (0 until p.m).map { c =>
            def w(k: Int) = java.lang.Float.intBitsToFloat(words(7 * c + k).toInt)
            val t = outward.fold(RayBox.test(r, tmax, w(0), w(1), w(2), w(3), w(4), w(5), pb.boxSlackUlps))(_.test(r, tmax, w(0), w(1), w(2), w(3), w(4), w(5)))
            (!t.isNaN && words(7 * c + 6) != 0, bits(if (t.isNaN) 0f else t))
          }
          expected.enqueue((res.map(_._1), res.map(_._2)))
        } else dut.io.in.valid.poke(false.B)
        dut.io.out.valid.expect(issued(cycle - lat).B)
        if (issued(cycle - lat)) {
          val (hit, tn) = expected.dequeue()
          for (c <- 0 until p.m) {
            dut.io.out.bits.hit(c).expect(hit(c).B, s"cycle $cycle child $c")
            if (hit(c)) dut.io.out.bits.tnear(c).expect(tn(c).U, s"cycle $cycle child $c tnear")
          }
          // each hit child's rank: the hit children nearer than it, or as near in an earlier slot (IEEE compare)
          val near = tn.map(b => java.lang.Float.intBitsToFloat(b.toInt))
          for (c <- 0 until p.m if hit(c)) {
            val rank = (0 until p.m).count(i => i != c && hit(i) && (near(i) < near(c) || (near(i) == near(c) && i < c)))
            dut.io.out.bits.rank(c).expect(rank.U, s"cycle $cycle child $c rank")
          }
        }
        dut.clock.step()
      }
    }
  }

  /** Vertices whose edge-function products round to the same binary32 value while their exact values differ
    * (coordinates 1 + k ulp): the watertight test's binary64 recomputation decides these. `z` keeps the
    * ray's shear exact (a ray along z from the z axis sees the vertices' own x and y).
    */
  private def nearTie(): Array[Float] = Array.tabulate(9)(k => if (k % 3 == 2) rnd.nextFloat() * 4 - 2
    else java.lang.Float.intBitsToFloat(java.lang.Float.floatToRawIntBits(if (rnd.nextBoolean()) 1f else -1f) + rnd.nextInt(4)))
  private def zRay(): (Array[Float], PreparedRay, Float) = {
    val dz = if (rnd.nextBoolean()) 1f else -1f
    val r = new PreparedRay(0f, 0f, -5f * dz, 0f, if (rnd.nextBoolean()) 0f else -0f, dz, 0f, Float.PositiveInfinity)
    (Array(0f, 0f, -5f * dz, 0f, r.dy, dz, r.ix, r.iy, r.iz, 0f), r, Float.PositiveInfinity)
  }

  /** One triangle pipe against its model, `n` jobs back to back: random and degenerate primitives, and (for the
    * watertight test) near ties that take the binary64 path.
    */
  private type TriPorts = Bundle { val in: Valid[TriJob]; val out: Valid[TriResult] }
  private def triPipeTest[T <: Module](name: String, n: Int, pipe: => T, latency: T => Int, io: T => TriPorts,
                                      model: (PreparedRay, Float, Array[Float], RayTriangle.Result) => Boolean, ties: Boolean,
                                      wide: Boolean = false, build: rtaccel.sim.VerilatorBuild = rtaccel.sim.VerilatorBuild.quick,
                                      interval: Int = 1): Unit =
    test(s"$name == its model on $n random and degenerate primitives, " +
      (if (interval == 1) "one per cycle" else s"$interval or ${interval + 1} cycles apart, other words between them")) {
      val built = rtaccel.TestSim.firtool(s"IuPipesSpec/${name.filter(_.isLetterOrDigit)}", build)(pipe)(io)
      test(built.gen()).withAnnotations(built.annotations) { dut =>
        val (in, outIo) = (dut.io.in, dut.io.out)
        val lat = latency(built.module)
        info(s"latency $lat cycles")
        val expected = scala.collection.mutable.Queue[(Boolean, Seq[BigInt], Boolean)]()
        val out = new RayTriangle.Result
        var hits = 0; var tieJobs = 0
        // TRI_II=k: a job every k or k + 1 cycles (no fixed phase), the inputs changing between jobs
        val issued = (1 until n).scanLeft(0)((c, _) => c + interval + (if (interval > 1) rnd.nextInt(2) else 0)).toSet
        for (cycle <- 0 until issued.max + 1 + lat) {
          if (issued(cycle)) {
            val tie = ties && rnd.nextInt(4) == 0
            val (rf, r, tmax) = if (tie) zRay() else ray()
            val v = if (tie) { tieJobs += 1; nearTie() } else Array.fill(9)((rnd.nextFloat() - 0.5f) * 3)
            if (!tie) rnd.nextInt(8) match {
              case 0 => System.arraycopy(v, 0, v, 3, 3)                               // repeated vertex
              case 1 => for (k <- 0 until 3) v(6 + k) = 2 * v(3 + k) - v(k)           // collinear
              case 2 => for (k <- 0 until 9) v(k) = v(k) * 1e-20f                      // underflowing products
              case 3 => for (k <- 0 until 9) v(k) = v(k) * 1e13f                       // overflowing products
              case 4 => for (k <- 0 until 3) v(k) = rf(k)                              // a vertex at the origin
              case _ if wide => rnd.nextInt(6) match { // what a wider format changes: range, subnormals, specials
                case 0 => for (k <- 0 until 9) v(k) = v(k) * 1e30f                      // fp32 det overflows
                case 1 => for (k <- 0 until 9) v(k) = v(k) * 1e-30f                     // fp32 det underflows
                case 2 => for (k <- 0 until 9) v(k) = v(k) * 1e-38f                     // subnormal coordinates
                case 3 => v(rnd.nextInt(9)) = specials(rnd.nextInt(specials.length))
                case 4 => v(rnd.nextInt(9)) = Float.NaN
                case _ =>
              }
              case _ =>
            }
            in.valid.poke(true.B); in.bits.tu.poke(2.U); pokeRay(in.bits.ray, rf)
            in.bits.tmax.poke(bits(tmax).U); in.bits.last.poke((cycle % 3 == 0).B); in.bits.err.poke((cycle % 97 == 5).B)
            for (k <- 0 until 9) in.bits.words(k).poke(bits(v(k)).U)
            in.bits.words(9).poke(cycle.U)
            val hit = cycle % 97 != 5 && model(r, tmax, v, out)
            if (hit) hits += 1
            expected.enqueue((hit, Seq(bits(out.t), bits(out.u), bits(out.v)), cycle % 3 == 0))
          } else {
            in.valid.poke(false.B)
            for (k <- 0 until 10) in.bits.words(k).poke(BigInt(32, rnd).U)
          }
          if (issued(cycle - lat)) {
            outIo.valid.expect(true.B)
            val (hit, tuv, last) = expected.dequeue()
            outIo.bits.hit.expect(hit.B, s"cycle $cycle")
            outIo.bits.last.expect(last.B)
            outIo.bits.prim.expect((cycle - lat).U)
            if (hit) {
              outIo.bits.t.expect(tuv(0).U, s"cycle $cycle t"); outIo.bits.u.expect(tuv(1).U, s"cycle $cycle u")
              outIo.bits.v.expect(tuv(2).U, s"cycle $cycle v")
            }
          } else outIo.valid.expect(false.B)
          dut.clock.step()
        }
        assert(hits > n / 50, s"only $hits of $n jobs hit: the comparison would not see the hit path")
        info(s"$hits hits; $tieJobs near-tie jobs")
      }
    }

  triPipeTest[TriPipe]("Möller–Trumbore pipe (TriPipe, PIPELINE=auto)", randoms, new TriPipe(p.pipes), _.latency, _.io,
    (r, tmax, v, o) => RayTriangle.test(r, tmax, v, o), ties = false)
  // TRI_II=k: the operators shared by k operations of a primitive (fp.Fold), the same results at every depth; k > 2
  // needs a primitive of k beats or more (a 128-bit bus)
  // (make test: 2 at auto; make regress: 2 at none, 3 at the deep budget and at none, 4 at auto)
  for ((k, pl, jobs) <- Seq((2, auto, 3000)) ++ (if (regress) Seq((2, fixed, 5000), (3, deep, 5000), (3, fixed, 1500), (4, auto, 5000)) else Nil)) {
    val pk = p.copy(triInterval = k, axiDataBits = if (k > 2) 128 else p.axiDataBits, pipelining = pl)
    triPipeTest[TriPipe](s"Möller–Trumbore pipe at TRI_II=$k, PIPELINE=${pl.name}", jobs, new TriPipe(pk.pipes), _.latency, _.io,
      (r, tmax, v, o) => RayTriangle.test(r, tmax, v, o), ties = false, interval = k)
  }
  private val watertight = new rtaccel.model.RayTriangleWatertight
  // (TRI_II=2 shares its operators as TriPipe's: make test at none, make regress at auto)
  for ((pl, ii, n) <- Seq((deep, 1, randoms), (fixed, 2, 3000)) ++ (if (regress) Seq((auto, 1, randoms), (fixed, 1, randoms), (auto, 2, 5000)) else Nil)) {
    val pp = p.copy(pipelining = pl, triTest = TriTest.Watertight, triInterval = ii)
    triPipeTest[WatertightPipe](s"watertight pipe (WatertightPipe, PIPELINE=${pl.name}${if (ii > 1) s", TRI_II=$ii" else ""})", n, new WatertightPipe(pp.pipes), _.latency,
      _.io, (r, tmax, v, o) => watertight.test(r, tmax, v, o), ties = true, interval = ii)
  }
  if (regress) triPipeTest[TriPipe]("Möller–Trumbore pipe (TriPipe, PIPELINE=none)", 20000, new TriPipe(p.copy(pipelining = fixed).pipes),
    d => { assert(d.latency == 8 + p.divStages, "PIPELINE=none keeps 8 + divStages"); d.latency }, _.io,
    (r, tmax, v, o) => RayTriangle.test(r, tmax, v, o), ties = false)
  // TRI_FORMAT: the pipe in a wider format against the SoftFloat twin (fp64 in make test; e8m31, the same exponent
  // as fp32, in make regress: each is a Verilator build, compiled without C++ optimisation: the wide multipliers and
  // divider make a large model whose -O1 build takes minutes, longer than its 20000 cycles run unoptimised)
  for ((tf, pl) <- Seq((FpFormat.fp64, fixed)) ++ (if (regress) Seq((FpFormat(8, 31), auto), (FpFormat.fp64, auto)) else Nil)) {
    val pw = p.copy(triFormat = tf, pipelining = pl); val twin = new rtaccel.model.RayTriangleWide(tf)
    triPipeTest[TriPipe](s"Möller–Trumbore pipe at TRI_FORMAT=${tf.name}, PIPELINE=${pl.name}", randoms, new TriPipe(pw.pipes), _.latency,
      _.io, (r, tmax, v, o) => twin.testSoft(r, tmax, v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8), o),
      ties = false, wide = true, build = rtaccel.sim.VerilatorBuild("o0", Nil, Seq("-O0"), Some("-O0"), jobs = 1))
  }
}
