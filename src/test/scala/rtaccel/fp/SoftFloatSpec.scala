package rtaccel.fp

import org.scalatest.flatspec.AnyFlatSpec
import org.scalatest.matchers.should.Matchers

/** The pure-Scala model: against Java float for fp32, and against a brute-force nearest-value oracle
  * (exact rationals, every representable value enumerated) exhaustively for tiny formats.
  */
class SoftFloatSpec extends AnyFlatSpec with Matchers {
  private val fp32 = FpFormat.fp32
  // make test: two million (one million per thread, the coverage's sample); make regress ten million
  private val nRandom = if (rtaccel.Regress.full) 10000000 else 2000000

  "SoftFloat(fp32)" should "equal Java float on every pair of edge values" in {
    val g = new FpTestGen(fp32, 1)
    val sf = new SoftFloat(fp32)
    val chk = new FpCheck("soft32-edges")
    for ((a, b) <- g.edgePairs; op <- 0 until FpOps.n) chk.check(op, a, b, FpRef.soft(sf)(op, a, b), FpRef.java32(op, a, b))
    info(chk.report)
    chk.totalFailed shouldBe 0
    chk.minChecked should be >= 5000L
  }

  it should s"equal Java float on $nRandom random pairs per op (uniform, nearby exponents, cancellation, ties, range edges)" in {
    val t0 = System.nanoTime()
    // two threads (the machine has 2 cores); each checks every op on its half of the pairs
    val parts = (0 until 2).map { t =>
      val chk = new FpCheck(s"soft32-random-$t")
      val cov = new FpCoverage32
      val th = new Thread(() => {
        val g = new FpTestGen(fp32, 100 + t)
        val sf = new SoftFloat(fp32)
        var i = 0
        while (i < nRandom / 2) {
          val (a, b) = g.mixed()
          var op = 0
          while (op < FpOps.n) { chk.check(op, a, b, FpRef.soft(sf)(op, a, b), FpRef.java32(op, a, b)); op += 1 }
          if (t == 0 && i < 1000000) { var k = 0; while (k < 4) { cov.add(k, a, b); k += 1 } }
          i += 1
        }
      })
      th.start()
      (th, chk, cov)
    }
    parts.foreach(_._1.join())
    val secs = (System.nanoTime() - t0) / 1e9
    parts.foreach(p => info(p._2.report))
    info(parts.head._3.report)
    info(f"SoftFloat: ${nRandom.toLong * FpOps.n / secs}%.0f checked ops/s over 2 threads, ${secs}%.1f s")
    parts.map(_._2.totalFailed).sum shouldBe 0
    parts.map(_._2.minChecked).sum shouldBe nRandom.toLong
    parts.head._3.missing shouldBe empty
  }

  "SoftFloat(fp64)" should "equal Java double on every pair of edge values and 1,000,000 random pairs per op" in {
    val f = FpFormat.fp64
    val g = new FpTestGen(f, 3)
    val sf = new SoftFloat(f)
    val chk = new FpCheck("soft64")
    val pairs = g.edgePairs.iterator ++ Iterator.fill(1000000)(g.mixed())
    var n = 0L
    for ((a, b) <- pairs) {
      var op = 0
      while (op < FpOps.n) { chk.check(op, a, b, FpRef.soft(sf)(op, a, b), FpRef.java64(op, a, b)); op += 1 }
      n += 1
    }
    info(chk.report)
    chk.totalFailed shouldBe 0
    chk.minChecked shouldBe n
    n should be > 1000000L
  }

  // ---------- brute-force oracle for tiny formats

  /** Exact rational n/d (d > 0). */
  private final case class Q(n: BigInt, d: BigInt) {
    def cmp(o: Q): Int = (n * o.d).compare(o.n * d)
  }
  private def valueOf(f: FpFormat, x: Long): Q = { // finite x only
    val m = f.manBits
    val ef = ((x >> m) & f.maxExp).toInt
    val frac = x & ((1L << m) - 1)
    val (mant, e) = if (ef == 0) (BigInt(frac), 1 - f.bias - m) else (BigInt(frac) + (BigInt(1) << m), ef - f.bias - m)
    val s = if ((x >> (f.width - 1)) != 0) -mant else mant
    if (e >= 0) Q(s << e, 1) else Q(s, BigInt(1) << -e)
  }

  private val candCache = scala.collection.mutable.Map[FpFormat, IndexedSeq[(Long, Q)]]()

  /** Round an exact rational to the nearest representable value by searching all of them (ties: even fraction). */
  private def oracleRound(f: FpFormat, q: Q, zeroNeg: Boolean): Long = {
    val signBit = 1L << (f.width - 1)
    if (q.n == 0) return if (zeroNeg) signBit else 0L
    val neg = q.n < 0
    val t = Q(q.n.abs, q.d)
    val maxFinite = ((f.maxExp.toLong - 1) << f.manBits) | ((1L << f.manBits) - 1)
    // candidate magnitudes 0..maxFinite plus the next power of two (2^(emax+1), rounding there means overflow)
    val cands = candCache.getOrElseUpdate(f,
      (0L to maxFinite).map(c => (c, valueOf(f, c))) :+ ((f.maxExp.toLong << f.manBits, Q(BigInt(1) << (f.maxExp - f.bias), 1))))
    // binary search: last candidate <= t (candidate 0 is zero, t > 0)
    var lo0 = 0; var hi0 = cands.length - 1
    while (lo0 < hi0) { val mid = (lo0 + hi0 + 1) / 2; if (cands(mid)._2.cmp(t) <= 0) lo0 = mid else hi0 = mid - 1 }
    val k = lo0
    val pick =
      if (cands(k)._2.cmp(t) == 0 || k == cands.length - 1) cands(k)._1
      else {
        val lo = cands(k); val hi = cands(k + 1)
        val mid = Q(lo._2.n * hi._2.d + hi._2.n * lo._2.d, lo._2.d * hi._2.d * 2)
        val c = t.cmp(mid)
        if (c < 0) lo._1 else if (c > 0) hi._1 else if ((lo._1 & 1) == 0) lo._1 else hi._1
      }
    (if (neg) signBit else 0L) | pick // pick == maxExp << m is infinity
  }

  private def oracle(f: FpFormat, op: Int, a: Long, b: Long): Long = {
    val sf = new SoftFloat(f) // only for NaN/inf classification of operands, not the arithmetic
    val m = f.manBits
    def isInf(x: Long) = ((x >> m) & f.maxExp) == f.maxExp && (x & ((1L << m) - 1)) == 0
    val nan = f.canonicalNaN.toLong
    val sa = (a >> (f.width - 1)) != 0
    val sb0 = (b >> (f.width - 1)) != 0
    if (sf.isNaN(a) || sf.isNaN(b) || isInf(a) || isInf(b)) return FpRef.soft(sf)(op, a, b) // specials: covered elsewhere
    val x = valueOf(f, a); val y = valueOf(f, b)
    op match {
      case 0 => oracleRound(f, Q(x.n * y.d + y.n * x.d, x.d * y.d), sa && sb0)
      case 1 => oracleRound(f, Q(x.n * y.d - y.n * x.d, x.d * y.d), sa && !sb0)
      case 2 => oracleRound(f, Q(x.n * y.n, x.d * y.d), sa != sb0)
      case _ =>
        if (y.n == 0) { if (x.n == 0) nan else ((if (sa != sb0) 1L << (f.width - 1) else 0L) | (f.maxExp.toLong << m)) }
        else { val n = x.n * y.d; val d = x.d * y.n; oracleRound(f, if (d < 0) Q(-n, -d) else Q(n, d), sa != sb0) }
    }
  }

  for (f <- Seq(FpFormat(3, 2), FpFormat(4, 3), FpFormat(3, 4))) {
    "SoftFloat" should s"equal a brute-force nearest-value oracle on all pairs of FpFormat(${f.expBits}, ${f.manBits})" in {
      val sf = new SoftFloat(f)
      val chk = new FpCheck(s"oracle(${f.expBits},${f.manBits})")
      val n = 1L << f.width
      for (a <- 0L until n; b <- 0L until n; op <- 0 until 4) chk.check(op, a, b, FpRef.soft(sf)(op, a, b), oracle(f, op, a, b))
      info(chk.report)
      chk.totalFailed shouldBe 0
      chk.checked(0) shouldBe n * n
    }
  }
}
