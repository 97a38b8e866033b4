package rtaccel.fp

import chisel3._
import chisel3.util._

/** Combinational IEEE 754 binary floating-point operators, generic in [[FpFormat]].
  *
  * All arithmetic rounds to nearest, ties to even, except the directed variants (subDirected, mulDirected,
  * convert: toward +inf or -inf, for the conservative reduced-precision box test); subnormal inputs and outputs are kept (no flush to zero);
  * overflow gives ±inf; every NaN produced by add/sub/mul/div is `f.canonicalNaN`. The min/max selectors follow
  * the comparator-select reference in `rtaccel.model.Fp32` exactly (on equal operands the second is returned).
  *
  * Structure (see docs/fp.md): each operation unpacks its operands, produces an exact or
  * guard/sticky-extended significand with a signed biased exponent, and hands it to one shared
  * normalise-round-pack stage ([[roundPack]]). Callers place pipeline registers around these functions.
  */
object Fp {

  /** Width of the signed exponent datapath: room for mul/div exponent sums plus subnormal normalisation. */
  private[fp] def expW(f: FpFormat): Int = log2Ceil(3 * f.maxExp + 2 * f.manBits + 16) + 2

  /** Fields and classes of one operand. `exp` is the effective biased exponent (1 for subnormals and zero),
    * `sig` the significand with its hidden bit (m+1 bits).
    */
  private[fp] final class Unpacked(f: FpFormat, x: UInt) {
    val m: Int = f.manBits
    val e: Int = f.expBits
    val sign: Bool = x(f.width - 1)
    val expF: UInt = x(f.width - 2, m)
    val frac: UInt = x(m - 1, 0)
    val expZero: Bool = expF === 0.U
    val expOnes: Bool = expF.andR
    val fracZero: Bool = frac === 0.U
    val isZero: Bool = expZero && fracZero
    val isInf: Bool = expOnes && fracZero
    val isNaN: Bool = expOnes && !fracZero
    val sig: UInt = Cat(!expZero, frac)
    val exp: UInt = Mux(expZero, 1.U(e.W), expF)
    /** Magnitude bits: for non-NaN values, integer order of these equals order of |x|. */
    val mag: UInt = x(f.width - 2, 0)
  }

  /** x << amt truncated to x's width, as a logarithmic shifter (no widened intermediate). */
  /** x > c for a constant c, as AND/OR logic of x's bits: at the highest bit where they differ, x has the 1.
    * Synthesis maps a comparison operator to a carry chain, which against a constant costs a chain of cells and its
    * delay in series with what follows (on ECP5 three CCU2C for a 5-bit compare) where a few LUTs do.
    */
  private[fp] def gtConst(x: UInt, c: BigInt): Bool = {
    val w = x.getWidth
    if (c < 0) true.B
    else if (c >= (BigInt(1) << w) - 1) false.B
    else (0 until w).foldLeft(false.B)((below, i) => if (c.testBit(i)) x(i) && below else x(i) || below)
  }
  private[fp] def geConst(x: UInt, c: BigInt): Bool = gtConst(x, c - 1)
  private[fp] def ltConst(x: UInt, c: BigInt): Bool = !geConst(x, c)
  /** The same for a signed x: its two's complement with the sign bit flipped orders as unsigned, offset by 2^(w-1). */
  private[fp] def gtConst(x: SInt, c: BigInt): Bool = {
    val w = x.getWidth
    gtConst(x.asUInt ^ (BigInt(1) << (w - 1)).U(w.W), c + (BigInt(1) << (w - 1)))
  }
  private[fp] def geConst(x: SInt, c: BigInt): Bool = gtConst(x, c - 1)
  private[fp] def ltConst(x: SInt, c: BigInt): Bool = !geConst(x, c)

  private[fp] def shlTrunc(x: UInt, amt: UInt): UInt = {
    val n = x.getWidth
    amt.asBools.zipWithIndex.foldLeft(x) { case (v, (bit, i)) =>
      val k = 1 << i
      if (k >= n) Mux(bit, 0.U(n.W), v) else Mux(bit, Cat(v(n - 1 - k, 0), 0.U(k.W)), v)
    }
  }

  /** The top k bits of x << amt truncated to x's width, as a logarithmic shifter that carries at each step only the
    * bits that can still rise into those k (so no stage computes a bit nothing reads). The largest step goes first:
    * what remains after each is every shift below 2^i, so the bits still needed are a contiguous top k + 2^i - 1.
    */
  private[fp] def shlTop(x: UInt, amt: UInt, k: Int): UInt = {
    val n = x.getWidth
    require(k >= 1 && k <= n)
    // v: the top bits of the value so far
    (amt.getWidth - 1 to 0 by -1).foldLeft(x) { (v, i) =>
      val s = 1 << i
      val need = math.min(n, k + s - 1)
      val vw = v.getWidth
      val keep = v(vw - 1, vw - need)
      // v's bits below its top s, then the zeros a truncating shift brings in (only when v is all of x)
      val shifted = if (s >= vw) 0.U(need.W) else {
        val hi = v(vw - 1 - s, math.max(0, vw - s - need))
        if (hi.getWidth < need) Cat(hi, 0.U((need - hi.getWidth).W)) else hi
      }
      Mux(amt(i), shifted, keep)
    }
  }

  /** Leading-zero count of x (x != 0; the result for x == 0 is unspecified), as a log-depth tree:
    * x is padded with ones to a power-of-two width, halves are combined as (hi all zero) ? hi.width + lo : hi.
    */
  private[fp] def lzc(x: UInt): UInt = lzcBlock(lzcPad(x))._2

  /** x with ones below it to a power-of-two width (the count of a nonzero x is unchanged). */
  private def lzcPad(x: UInt): UInt = {
    val n = x.getWidth
    val k = log2Ceil(n) max 1
    if ((1 << k) > n) Cat(x, Fill((1 << k) - n, 1.U(1.W))) else x
  }
  /** (all zero, leading zeros) of a block of power-of-two width: a tree of halves. */
  private def lzcBlock(v: UInt): (Bool, UInt) = {
    val w = v.getWidth
    if (w == 1) (!v(0), 0.U(0.W))
    else lzcJoin(lzcBlock(v(w - 1, w / 2)), lzcBlock(v(w / 2 - 1, 0)))
  }
  private def lzcJoin(h: (Bool, UInt), l: (Bool, UInt)): (Bool, UInt) =
    (h._1 && l._1, Mux(h._1, Cat(1.U(1.W), l._2), Cat(0.U(1.W), h._2)))
  /** lzc in two halves that a register may separate: the (all zero, count) of each block of `b` bits (a power of
    * two), most significant first, then [[lzcBlocksJoin]] over them. The same tree as lzc, cut at one level.
    */
  private[fp] def lzcBlocks(x: UInt, b: Int): Seq[(Bool, UInt)] = {
    val p = lzcPad(x)
    val bb = b min p.getWidth
    (p.getWidth / bb - 1 to 0 by -1).map(i => lzcBlock(p(i * bb + bb - 1, i * bb)))
  }
  private[fp] def lzcBlocksJoin(bs: Seq[(Bool, UInt)]): UInt = {
    def go(s: Seq[(Bool, UInt)]): (Bool, UInt) = if (s.length == 1) s.head else {
      val (h, l) = s.splitAt(s.length / 2)
      lzcJoin(go(h), go(l))
    }
    go(bs)._2
  }

  private def packInf(f: FpFormat, sign: Bool): UInt = Cat(sign, f.maxExp.U(f.expBits.W), 0.U(f.manBits.W))
  private def packZero(f: FpFormat, sign: Bool): UInt = Cat(sign, 0.U((f.width - 1).W))
  private def nan(f: FpFormat): UInt = f.canonicalNaN.U(f.width.W)

  /** A special result (NaN, ±inf, ±0) as class flags and a sign; `nan` wins over `inf` over `zero`. */
  class Special extends Bundle {
    val nan = Bool()
    val inf = Bool()
    val zero = Bool()
    val sign = Bool()
  }
  private[fp] def special(nanV: Bool, infV: Bool, zeroV: Bool, signV: Bool): Special = {
    val s = Wire(new Special); s.nan := nanV; s.inf := infV; s.zero := zeroV; s.sign := signV; s
  }
  private val noSpecial: () => Special = () => special(false.B, false.B, false.B, false.B)

  /** What [[roundPack]] takes: a finite nonzero value
    *   (-1)^sign * (sig / 2^(n-1)) * 2^(exp - bias)   (+ a positive amount below sig's LSB if sticky)
    * where n = sig width, or `sp` when the result is special. `toPos` is the direction of a directed rounding.
    */
  class RoundIn(val n: Int, val ew: Int) extends Bundle {
    val sign = Bool()
    val exp = SInt(ew.W)
    val sig = UInt(n.W)
    val sticky = Bool()
    val toPos = Bool()
    val sp = new Special
  }
  private[fp] def roundIn(sign: Bool, exp: SInt, sig: UInt, sticky: Bool, toPos: Option[Bool], sp: Special): RoundIn = {
    val r = Wire(new RoundIn(sig.getWidth, exp.getWidth))
    r.sign := sign; r.exp := exp; r.sig := sig; r.sticky := sticky; r.toPos := toPos.getOrElse(false.B); r.sp := sp
    r
  }

  /** roundPack after its shift amounts are known: the value, its significand padded and its exponent widened, with
    * the left shift, the saturated right shift and which of the two applies. After the shifts the value is a RoundIn
    * again, its exponent the output's (>= 1) and its significand's hidden bit on top unless that exponent is 1.
    */
  class NormMid(n: Int, w: Int, val slW: Int, val rW: Int, val maskW: Int = 0) extends RoundIn(n, w) {
    val sl = UInt(slW.W)
    val rSat = UInt(rW.W)
    val leftCase = Bool()
    /** Bit i set when the right shift moves bit i of the rounding's window out (i < rSat): the sticky bit is then an
      * AND-OR of the window and this mask, not an OR over the shifter's outputs (4-input LUTs only, see roundPackT). */
    val rMask = Option.when(maskW > 0)(UInt(maskW.W))
  }

  /** roundPack's first segment when its leading-zero count is cut in two (see roundPackT): the count's blocks. */
  class NormLzBlocks(n: Int, w: Int, val blocks: Int, blockBits: Int, val rW: Int, roomW: Int) extends RoundIn(n, w) {
    val zero = Vec(blocks, Bool())
    val count = Vec(blocks, UInt(blockBits.W))
    val room = UInt(roomW.W)
    val rSat = UInt(rW.W)
    val leftCase = Bool()
  }

  /** roundPack's first segment: NormMid with the leading-zero count in `sl`, not yet saturated at `room`. */
  class NormLz(n: Int, w: Int, slW: Int, rW: Int) extends NormMid(n, w, slW, rW) {
    val room = UInt(slW.W)
  }

  /** roundPack after rounding: the m+2-bit significand (a carry into its top bit moves to the next binade). */
  class Rounded(val m: Int, val e: Int) extends Bundle {
    val sign = Bool()
    val eLow = UInt(e.W)   // the exponent field before a rounding carry: exp - 1, low bits
    val bigExp = Bool()    // exp - 1 >= maxExp: overflow whatever the rounding
    /** Where LUTs have 4 inputs: overflow if the rounding's carry into the field is 0, 1 or 2 (`rounded >> m`): bigExp
      * or eLow + that >= maxExp, decided from eLow beside the increment, so the packing's overflow is one choice by the
      * carry (elsewhere unused: false). */
    val ovfIf = Vec(3, Bool())
    val rounded = UInt((m + 2).W)
    val toPos = Bool()
    val sp = new Special
  }

  /** Normalise, round (to nearest even, or directed by `toPos` when `directed`) and pack a [[RoundIn]] into fo,
    * in five segments (leading zeros; the left shift amount; shifts; rounding; packing) between which `pipe` may place registers.
    * `exp` is a signed biased exponent that may lie outside the representable range (underflow goes to
    * subnormals/zero, overflow to inf). Hardware trimming for callers that know their range: `canUnderflow = false`
    * promises exp >= 1 (drops the right shifter), `maxLeftShift` bounds sig's leading zeros that need normalising
    * (narrower shifter/LZC).
    */
  private[fp] def roundPackT(pipe: Stager, f: FpFormat, x: Timed[RoundIn], canUnderflow: Boolean = true,
                             maxLeftShift: Int = Int.MaxValue, directed: Boolean = false): Timed[UInt] = {
    val m = f.manBits
    val e = f.expBits
    val n0 = x.v.n
    val n = n0 max (m + 3)
    val w = x.v.ew max (log2Ceil(n + 2) + 2)
    val maxLs = maxLeftShift min (n - 1)
    // the rounding reads the top m+2 bits and an OR of the rest: the shifts deliver those j bits (the OR as the
    // lowest), never the whole significand (docs/fp.md)
    val j = m + 3
    val nLz = if (maxLs >= n - 1) n else maxLs + 1
    val lzLevels = Depth.lzc(nLz, pipe.lutInputs)
    // A count deeper than the budget (a product's significand on 4-input LUTs: 6 levels at 64 bits, WatertightPipe's
    // routed critical path on ECP5) is cut in two segments: the counts of 8-bit blocks, then the tree above them.
    val lzBlock = 8
    val lzSplit = pipe.budget.exists(lzLevels > _) && nLz > lzBlock
    val roomW = log2Ceil(n + 1)
    val lut4 = pipe.smallLuts
    // 1: leading zeros and, beside them, the room left above exponent 1 and the right shift into the subnormal range
    // (the count is made where it was before the cut existed: Yosys' ABC maps the unpipelined adder in 422 LUTs
    // instead of 406 on xc7 when the same logic is built in another order)
    def front[A](r: RoundIn)(count: UInt => A): (UInt, SInt, Bool, A, UInt, UInt) = {
      val sig = if (n > n0) Cat(r.sig, 0.U((n - n0).W)) else r.sig
      val ex = r.exp.pad(w)
      // Exponent >= 1: shift left to normalise, but never below exponent 1 (subnormal results stay unnormalised).
      val leftCase = if (canUnderflow) geConst(ex, 1) else true.B
      // leading zeros of sig (sig != 0), saturated at maxLs via a sentinel bit
      val lz = count(if (maxLs >= n - 1) sig else Cat(sig(n - 1, n - maxLs), 1.U(1.W)))
      val room = ex - 1.S
      val roomSat = Mux(gtConst(ex, n + 1), n.U, room.asUInt(roomW - 1, 0)) // room > n
      // Exponent < 1: shift right into the subnormal range, collecting the bits shifted out as sticky.
      val rAmt = 1.S - ex
      val rSat = Mux(ltConst(ex, -j), (j + 1).U, rAmt.asUInt(log2Ceil(j + 2) - 1, 0)) // rAmt > j + 1
      (sig, ex, leftCase, lz, roomSat, rSat)
    }
    def normLz(r: RoundIn, sig: UInt, ex: SInt, leftCase: Bool, lz: UInt, roomSat: UInt, rSat: UInt): NormLz = {
      val o = Wire(new NormLz(n, w, lz.getWidth max roomSat.getWidth, rSat.getWidth))
      o.sign := r.sign; o.exp := ex; o.sig := sig; o.sl := lz; o.room := roomSat; o.rSat := rSat; o.leftCase := leftCase
      o.sticky := r.sticky; o.toPos := r.toPos; o.sp := r.sp
      o
    }
    val lzd0 = if (!lzSplit) pipe.step(x, lzLevels max (Depth.carry(w) + 1)) { r =>
      val (sig, ex, leftCase, lz, roomSat, rSat) = front(r)(lzc)
      normLz(r, sig, ex, leftCase, lz, roomSat, rSat)
    } else {
      val blocks = pipe.step(x, Depth.lzc(lzBlock, pipe.lutInputs) max (Depth.carry(w) + 1)) { r =>
        val (sig, ex, leftCase, bs, roomSat, rSat) = front(r)(lzcBlocks(_, lzBlock))
        val o = Wire(new NormLzBlocks(n, w, bs.length, log2Ceil(lzBlock), rSat.getWidth, roomW))
        o.sign := r.sign; o.exp := ex; o.sig := sig; o.room := roomSat; o.rSat := rSat; o.leftCase := leftCase
        o.sticky := r.sticky; o.toPos := r.toPos; o.sp := r.sp
        for (((z, c), i) <- bs.zipWithIndex) { o.zero(i) := z; o.count(i) := c }
        o
      }
      pipe.step(blocks, Depth.lzc(blocks.v.blocks, pipe.lutInputs)) { r =>
        normLz(r, r.sig, r.exp, r.leftCase, lzcBlocksJoin(r.zero.zip(r.count).toSeq), r.room, r.rSat)
      }
    }
    // Where LUTs have 4 inputs the first two segments are cut apart at every budget: counted for 6-input LUTs they
    // fit 7 levels, mapped to 4-input ones they were 11 (the exponent -> the right shift's saturated amount -> the
    // sticky mask's decode: the smallest platform's routed critical path on ECP5 at 125 MHz, in TriPipe's shared
    // rounding, docs/timing.md twenty-first round). Budgets under 7 cut there anyway.
    val lzd = if (lut4 && pipe.budget.isDefined) pipe.reg(lzd0) else lzd0
    // Where LUTs have 4 inputs, an OR of the right shifter's 28 outputs below the window is a level deeper than Depth
    // counts (it was WatertightPipe's routed critical path on ECP5): the sticky bit is then an AND-OR of the window and
    // a mask decoded a segment earlier. On 6-input LUTs the mask's register and decode cost more than they save
    // (fp32 mul on xc7 at 6 levels: 406 LUTs against 360), so the OR stays there when pipelined; unpipelined (no
    // register between them) the mask is what ABC maps smaller (mul 396 against 441 LUTs).
    val stickyByMask = canUnderflow && (lut4 || pipe.budget.isEmpty)
    // 1b: the left shift, the leading zeros saturated at the room (its own segment: after a wide count, the compare
    // and its mux were the deepest step of a wide significand, WatertightPipe's routed critical path on ECP5). On
    // 4-input LUTs the compare of the count with the room takes a level more than a carry chain's estimate, so the
    // Stager cuts it from the shift after it: together they were TriPipe's routed critical path on ECP5 at seeds 1
    // and 2 (the registered room -> the saturated count -> the shifter's selects -> the significand register)
    val mid = pipe.step(lzd, Depth.carry(lzd.v.slW) + 1 + (if (lut4) 1 else 0)) { r =>
      val o = Wire(new NormMid(n, w, r.slW, r.rW, if (stickyByMask) j else 0))
      o.sign := r.sign; o.exp := r.exp; o.sig := r.sig; o.sl := Mux(r.sl < r.room, r.sl, r.room); o.rSat := r.rSat
      o.leftCase := r.leftCase; o.sticky := r.sticky; o.toPos := r.toPos; o.sp := r.sp
      for (mk <- o.rMask) mk := VecInit((0 until j).map(i => r.rSat > i.U)).asUInt
      o
    }
    // 2: the shifts, to the j bits the rounding reads: the top m+2 bits and one bit for the OR of the rest
    val norm = pipe.step(mid, Depth.shift(n) + (if (canUnderflow) 1 else 0)) { r =>
      // left: the bits that stay below the window, by mask (bit i lands at i + sl), so the shifter has m+2 outputs
      lazy val shl = shlTrunc(r.sig, r.sl)
      val leftSig = if (n > j) Cat(shlTop(r.sig, r.sl, j - 1), (0 to n - j).map(i => r.sig(i) && ltConst(r.sl, n - j + 1 - i)).reduce(_ || _)) else shl
      val o = Wire(new RoundIn(j, w))
      if (canUnderflow) {
        // right: shifted by j + 1 or more, everything lands below the window: the saturation above
        val win = if (n > j) Cat(r.sig(n - 1, n - j + 1), r.sig(n - j, 0).orR) else r.sig
        r.rMask match {
          case Some(mk) => // the bits it moves out, by the mask: bit i of win leaves when i < rSat
            o.sig := Mux(r.leftCase, leftSig, win >> r.rSat)
            o.sticky := r.sticky || (!r.leftCase && (win & mk).orR)
          case None => // the bits it moves out, from the shifter's outputs below the window
            val wideR = Cat(win, 0.U((j + 1).W)) >> r.rSat
            o.sig := Mux(r.leftCase, leftSig, wideR(2 * j, j + 1))
            o.sticky := r.sticky || (!r.leftCase && wideR(j, 0).orR)
        }
      } else { o.sig := leftSig; o.sticky := r.sticky }
      o.exp := Mux(r.leftCase, r.exp - r.sl.zext, 1.S) // >= 1; with sig's MSB clear only when it is 1 (subnormal)
      o.sign := r.sign; o.toPos := r.toPos; o.sp := r.sp
      o
    }
    // 3: round: the rounding decision and the increment
    val rnd = pipe.step(norm, Depth.reduce(j - m) + 2 + Depth.carry(m + 2)) { r =>
      val s = r.sig
      val kept = s(j - 1, j - 1 - m) // m+1 bits, hidden bit on top
      val guard = s(j - 2 - m)
      val low = s(0) // j = m + 3: the OR of everything below the guard bit
      val sticky = r.sticky || low
      // nearest even, or (directed) away from zero exactly when the direction points away from zero
      val up = if (directed) (r.toPos =/= r.sign) && (guard || sticky) else guard && (sticky || kept(0))
      val o = Wire(new Rounded(m, e))
      o.rounded := kept +& up // m+2 bits; carrying into bit m+1 moves to the next binade
      // beside the increment: the exponent field of the packing below
      val eM1 = r.exp - 1.S
      o.bigExp := geConst(r.exp, f.maxExp + 1) // eM1 >= maxExp
      o.eLow := eM1.asUInt(e - 1, 0)
      // (4-input LUTs only: on 6-input ones ABC maps the compares in the packing smaller, xc7 mul 396 against 450 LUTs
      // unpipelined, 360 against 385 at 6 levels)
      for (k <- 0 until 3) o.ovfIf(k) := (if (lut4) o.bigExp || geConst(o.eLow, BigInt(f.maxExp - k)) else false.B)
      o.sign := r.sign; o.toPos := r.toPos; o.sp := r.sp
      o
    }
    // 4: pack, overflow and the special results
    pipe.step(rnd, Depth.carry(m + e) + 3) { r =>
      val sign = r.sign
      val awayDir = if (directed) Some(r.toPos =/= sign) else None
      // Packing trick: ((exp-1) << m) + rounded. The hidden bit adds 1 to the exponent field, a subnormal
      // (hidden bit 0, exp = 1) packs with exponent field 0, and a rounding carry bumps the exponent.
      val sum = Cat(r.eLow, 0.U(m.W)) +& r.rounded
      // overflow: sum's exponent field eLow + hi >= maxExp, where hi = rounded >> m is 0, 1 or 2 (rounded <= 2^(m+1)).
      // Judged from eLow's compares (the rounding step's ovfIf) and hi beside the carry chain, not from its sum: the
      // add then feeds one mux, not a compare. With the compares here, the rounded carry ran through four LUT4 levels
      // into every bit of the result: WatertightPipe's routed critical path on ECP5 (docs/timing.md, twenty-second round)
      val hi = r.rounded(m + 1, m)
      def eLowGe(k: Int): Bool = geConst(r.eLow, BigInt(k))
      val ovf = if (lut4) Mux(hi(1), r.ovfIf(2), Mux(hi(0), r.ovfIf(1), r.ovfIf(0)))
        else r.bigExp || Mux(hi(1), eLowGe(f.maxExp - 2), Mux(hi(0), eLowGe(f.maxExp - 1), eLowGe(f.maxExp)))
      // an overflow rounded toward zero stays at the largest finite value
      val ovfValue = awayDir.fold(packInf(f, sign))(a => Mux(a, packInf(f, sign), Cat(sign, (f.maxExp - 1).U(e.W), Fill(m, 1.U(1.W)))))
      // every result but the packed sum, in the same priority (NaN, inf, zero, overflow), also beside the add
      val other = Mux(r.sp.nan, nan(f), Mux(r.sp.inf, packInf(f, r.sp.sign), Mux(r.sp.zero, packZero(f, r.sp.sign), ovfValue)))
      Mux(r.sp.nan || r.sp.inf || r.sp.zero || ovf, other, Cat(sign, sum(e + m - 1, 0)))
    }
  }

  /** The combinational roundPack of a finite nonzero value (no special case). */
  private[fp] def roundPack(f: FpFormat, sign: Bool, exp: SInt, sigIn: UInt, stickyIn: Bool,
                            canUnderflow: Boolean = true, maxLeftShift: Int = Int.MaxValue, toPos: Option[Bool] = None): UInt =
    roundPackT(Stager.none, f, Timed(roundIn(sign, exp, sigIn, stickyIn, toPos, noSpecial()), 0, 0),
      canUnderflow, maxLeftShift, toPos.isDefined).v

  /** q * 2^e in format f (q unsigned, e two's complement), +0 for q = 0 and +inf past the largest finite value.
    * Exact otherwise: q fits the significand and every e of its width keeps q * 2^e on f's subnormal grid
    * (both checked here), so the rounding of roundPack never acts. The int-to-float and the scale of a
    * quantized node's planes (iu.NodeDecode).
    */
  def fromUIntScaled(f: FpFormat, q: UInt, e: SInt): UInt = fromUIntScaledT(Stager.none, f, Timed(q, 0, 0), Timed(e, 0, 0)).v

  /** [[fromUIntScaled]] in segments between which `pipe` may place registers (roundPack's). */
  def fromUIntScaledT(pipe: Stager, f: FpFormat, q: Timed[UInt], e: Timed[SInt]): Timed[UInt] = {
    val w = q.v.getWidth
    require(w <= f.manBits + 1, s"a $w-bit integer does not fit the ${f.manBits + 1}-bit significand of ${f.name}")
    require(-(BigInt(1) << (e.v.getWidth - 1)) >= 1 - f.bias - f.manBits,
      s"a ${e.v.getWidth}-bit scale reaches below the smallest subnormal of ${f.name}: the product would round")
    val ew = (e.v.getWidth max expW(f)) + 1
    val eW = e.v.getWidth
    // (op's operands share one width: each is cut back to its own)
    val x = pipe.op(Seq(q, e.map(0)(_.asUInt)), Depth.carry(ew) max Depth.reduce(w)) { v =>
      val (qv, ev) = (v(0)(w - 1, 0), v(1)(eW - 1, 0).asSInt)
      val ex = ev.pad(ew) + (f.bias + w - 1).S(ew.W) // sig q read as q / 2^(w-1): biased exponent e + bias + w - 1
      roundIn(false.B, ex, qv, false.B, None, special(false.B, false.B, qv === 0.U, false.B)) // q = 0: +0
    }
    roundPackT(pipe, f, x)
  }

  // ---------------------------------------------------------------------------------------------------------
  // add / sub

  /** addCore after ordering the operands by magnitude, with the exponent difference xExp - yExp. */
  class AddSwap(f: FpFormat) extends Bundle {
    val xSign = Bool()
    val xExp = UInt(f.expBits.W)
    val d = UInt(f.expBits.W)
    val xSig = UInt((f.manBits + 1).W)
    val ySig = UInt((f.manBits + 1).W)
    val effSub = Bool()
    val toPos = Bool()
    val sp = new Special // nan and inf; `zero` is decided by the sum, `sign` is the sign of an infinity
    val zeroSign = Bool()
  }
  /** addCore's first segment where LUTs have 4 inputs: the magnitude compare's answer (`swap`: b is the larger) and
    * the operands as they came, swapped in the next segment (see addCore). */
  class AddCmp(f: FpFormat) extends Bundle {
    val swap = Bool()
    val xSign = Bool()
    val expA = UInt(f.expBits.W); val expB = UInt(f.expBits.W)
    val sigA = UInt((f.manBits + 1).W); val sigB = UInt((f.manBits + 1).W)
    val d = UInt(f.expBits.W)
    val effSub = Bool()
    val toPos = Bool()
    val sp = new Special
    val zeroSign = Bool()
  }
  /** addCore after aligning y: both with three extra bits (guard, round, sticky) and a carry bit on top. */
  /** The adder's alignment in two segments (4-input LUTs): y shifted by the difference's multiple of 4, the
    * difference's low bits and the mask of y's bits shifted out, beside the swapped operands. */
  class AddCoarse(f: FpFormat, g: Int) extends Bundle {
    val s = new AddSwap(f)
    val yHi = UInt((f.manBits + 1 + g).W)
    val dLow = UInt(2.W)
    val lost = UInt((f.manBits + 1).W)
  }

  class AddAligned(f: FpFormat) extends Bundle {
    val xSign = Bool()
    val xExp = UInt(f.expBits.W)
    val xExt = UInt((f.manBits + 5).W)
    val yExt = UInt((f.manBits + 5).W)
    val effSub = Bool()
    val toPos = Bool()
    val sp = new Special
    val zeroSign = Bool()
  }

  /** a ± b of format `f`, rounded to `fo` (nearest, or directed by `toPos`), in segments (order the operands,
    * align, add, then roundPack's three) between which `pipe` may place registers. The sum is formed at f's width
    * with guard/round/sticky bits, so rounding it to a narrower fo is still the correct rounding of the exact sum.
    */
  private def addCore(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt], negB: Boolean, fo: FpFormat,
                      toPos: Option[Timed[Bool]]): Timed[UInt] = {
    val m = f.manBits
    val g = 3
    val dMax = m + g + 2
    val ins = Seq(a, b) ++ toPos.map(t => t.map(0)(_.asUInt))
    // 1: order by magnitude: x is the larger operand, y the smaller
    // (and the exponent difference both ways beside the compare: the swap picks one. In the align step the
    // difference, its saturation and the shifter were one path, TriPipe's routed critical path on ECP5; the
    // saturation stays there: here it made this step deeper than its budget)
    // Where LUTs have 4 inputs the swap's muxes (the operands' 50-odd bits) go in the segment after the compare, with
    // the difference's saturation, so the Stager can put a register between the compare and them: ABC maps the 31-bit
    // compare into four LUT4 levels, and with the muxes behind it that segment was TriPipe's routed critical path on
    // ECP5 at 150 MHz (an operand bit -> the compare -> the smaller significand's register, 5 elements, 5.7 ns of
    // routing; docs/timing.md twenty-second round). The saturation has a segment of its own there anyway: counted
    // for 6-input LUTs it and the shift are 5 levels, mapped to 4-input ones they were 10-11 (the deepest paths of
    // the smallest platform on ECP5, in TriPipe's and BoxPipe's shared adders, twenty-first round). Elsewhere the
    // compare and the muxes are one segment and the saturation stays in front of the shift.
    val satApart = pipe.smallLuts && pipe.budget.isDefined
    def saturate(d: UInt): UInt = Mux(gtConst(d, dMax), dMax.U, d)
    // the operands' classes and the sum's sign rules, common to both layouts
    final case class Ops(ua: Unpacked, ub: Unpacked, sA: Bool, sB: Bool, swap: Bool, tp: Bool) {
      val effSub: Bool = sA =/= sB
      def sp: Special = special(ua.isNaN || ub.isNaN || (ua.isInf && ub.isInf && effSub), ua.isInf || ub.isInf, false.B, Mux(ua.isInf, sA, sB))
      // exact zero: -0 only for (-0) + (-0), or (IEEE) a cancellation rounded toward -inf
      def zeroSign: Bool = if (toPos.isDefined) Mux(sA === sB, sA, !tp) else sA && sB
    }
    def ops(v: Seq[UInt]): Ops = {
      val ua = new Unpacked(f, v(0))
      val ub = new Unpacked(f, v(1))
      Ops(ua, ub, ua.sign, if (negB) !ub.sign else ub.sign, ub.mag > ua.mag, if (toPos.isDefined) v(2)(0) else false.B)
    }
    val swSat = if (satApart) {
      // the exponents' own compare chooses the difference: they differ exactly where the swap follows them, and where
      // they are equal either way gives 0 (chosen by the swap, Yosys' opt_share turns the two subtracts into one of
      // swapped operands behind the compare: the magnitude compare then ran into a subtract, TriPipe's routed path)
      val cmp = pipe.op(ins, Depth.carry(f.width - 1) + 2) { v =>
        val x = ops(v)
        val o = Wire(new AddCmp(f))
        o.swap := x.swap; o.xSign := Mux(x.swap, x.sB, x.sA)
        o.expA := x.ua.exp; o.expB := x.ub.exp; o.sigA := x.ua.sig; o.sigB := x.ub.sig
        o.d := Mux(x.ub.exp > x.ua.exp, x.ub.exp - x.ua.exp, x.ua.exp - x.ub.exp)
        o.effSub := x.effSub; o.toPos := x.tp; o.sp := x.sp; o.zeroSign := x.zeroSign
        o
      }
      pipe.reg(pipe.step(cmp, 1 + Depth.carry(f.expBits) + 1) { r =>
        val o = Wire(new AddSwap(f))
        o.xSign := r.xSign; o.xExp := Mux(r.swap, r.expB, r.expA)
        o.xSig := Mux(r.swap, r.sigB, r.sigA); o.ySig := Mux(r.swap, r.sigA, r.sigB)
        o.d := saturate(r.d)
        o.effSub := r.effSub; o.toPos := r.toPos; o.sp := r.sp; o.zeroSign := r.zeroSign
        o
      })
    } else pipe.op(ins, Depth.carry(f.width - 1) + 1) { v =>
      val x = ops(v)
      // x's exponent is at least y's, so the difference taken the chosen way never wraps
      val o = Wire(new AddSwap(f))
      o.xSign := Mux(x.swap, x.sB, x.sA)
      o.xExp := Mux(x.swap, x.ub.exp, x.ua.exp)
      // pipelined, the difference both ways chosen by the swap; unpipelined, one subtract after the swap: ABC maps
      // that smaller (406 against 454 LUTs on xc7)
      o.d := (if (pipe.budget.isEmpty) o.xExp - Mux(x.swap, x.ua.exp, x.ub.exp) else Mux(x.swap, x.ub.exp - x.ua.exp, x.ua.exp - x.ub.exp))
      o.xSig := Mux(x.swap, x.ub.sig, x.ua.sig)
      o.ySig := Mux(x.swap, x.ua.sig, x.ub.sig)
      o.effSub := x.effSub; o.toPos := x.tp; o.sp := x.sp; o.zeroSign := x.zeroSign
      o
    }
    // 2: align y; shifted-out bits are ORed into the LSB
    def aligned(r: AddSwap, yAligned: UInt, yLost: Bool): AddAligned = {
      val o = Wire(new AddAligned(f))
      o.xSign := r.xSign; o.xExp := r.xExp; o.effSub := r.effSub; o.toPos := r.toPos; o.sp := r.sp; o.zeroSign := r.zeroSign
      o.yExt := Cat(0.U(1.W), yAligned | yLost)
      o.xExt := Cat(0.U(1.W), r.xSig, 0.U(g.W))
      o
    }
    // the bits shifted below the sticky position, by mask: bit i of ySig is lost when i + g < dSat (one LUT per bit
    // beside the shifter, whose low half then goes unused)
    def lostMask(dSat: UInt): UInt = VecInit((0 to m).map(i => gtConst(dSat, i + g))).asUInt
    // Where LUTs have 4 inputs the shifter is a 2:1 selection per level (5 at 27 bits) and the lost bits' mask, AND
    // and OR tree as deep, so the shift takes two segments: by the difference's multiple of 4 with the mask decoded
    // beside it, then by its two low bits with the lost bits' OR. In one they were 8 LUT4 levels, the exponent
    // difference's register to the aligned significand's: WatertightPipe's routed critical path on ECP5 at 150 MHz
    // (141.8 MHz, docs/timing.md twenty-third round). Logical right shifts compose, so the result is the same.
    val al = if (satApart && pipe.budget.exists(_ < Depth.shift(dMax, pipe.lutInputs) + 1)) {
      val coarse = pipe.step(swSat, (Depth.shift(dMax, pipe.lutInputs) - 2) max 2) { r =>
        val o = Wire(new AddCoarse(f, g))
        o.s := r
        o.yHi := Cat(r.ySig, 0.U(g.W)) >> Cat(r.d >> 2, 0.U(2.W))
        o.dLow := r.d(1, 0)
        o.lost := lostMask(r.d)
        o
      }
      pipe.step(coarse, 4) { r =>
        aligned(r.s, r.yHi >> r.dLow, (r.s.ySig & r.lost).orR)
      }
    } else pipe.step(swSat, (if (satApart) 0 else Depth.carry(f.expBits)) + Depth.shift(dMax) + 1) { r =>
      val dSat = if (satApart) r.d else saturate(r.d)
      aligned(r, Cat(r.ySig, 0.U(g.W)) >> dSat, (0 to m).map(i => r.ySig(i) && gtConst(dSat, i + g)).reduce(_ || _))
    }
    // 3: add. Without underflow (fo's range holds f's) the exponent only falls by the normalising shift, never
    // below 1: its signed datapath needs to hold xExp + 1 in fo's bias, not the products' and quotients' range
    val canUnderflow = fo.bias < f.bias
    val ew = if (canUnderflow) expW(f) max expW(fo) else log2Ceil((1 << f.expBits) - f.bias + fo.bias + 1) + 1
    val sum = pipe.step(al, Depth.carry(m + 5) + Depth.reduce(m + 5)) { r =>
      // one carry chain for both (y <= x, so the difference never wraps); the top bit is the carry's position
      val w = m + 5
      val res = addOrSub(r.xExt, r.yExt, r.effSub, w)
      // exp = xExp + 1 >= 2 in f; a narrower exponent range can underflow
      val exp = r.xExp.zext.pad(ew) + (1 - f.bias + fo.bias).S
      val isZero = res === 0.U
      roundIn(r.xSign, exp, res, false.B, toPos.map(_ => r.toPos),
        special(r.sp.nan, r.sp.inf, isZero, Mux(r.sp.inf, r.sp.sign, r.zeroSign)))
    }
    roundPackT(pipe, fo, sum, canUnderflow = canUnderflow, directed = toPos.isDefined)
  }

  private def comb(x: UInt): Timed[UInt] = Timed(x, 0, 0)
  private def combB(x: Bool): Timed[Bool] = Timed(x, 0, 0)
  private def addCore(f: FpFormat, a: UInt, b: UInt, negB: Boolean, fo: FpFormat, toPos: Option[Bool]): UInt =
    addCore(Stager.none, f, comb(a), comb(b), negB, fo, toPos.map(combB)).v

  def add(f: FpFormat, a: UInt, b: UInt): UInt = addCore(f, a, b, negB = false, f, None)
  def sub(f: FpFormat, a: UInt, b: UInt): UInt = addCore(f, a, b, negB = true, f, None)
  /** a - b of format f, rounded toward +inf (toPos) or -inf into format fo. */
  def subDirected(f: FpFormat, fo: FpFormat, a: UInt, b: UInt, toPos: Bool): UInt = addCore(f, a, b, negB = true, fo, Some(toPos))

  /** x of format f in format fo: exact when fo holds it, else rounded toward +inf (toPos) or -inf. */
  def convert(f: FpFormat, fo: FpFormat, x: UInt, toPos: Bool): UInt = convertCore(f, fo, x, Some(toPos))
  /** x of format f in format fo, rounded to nearest even (exact when fo holds it). */
  def convertNearest(f: FpFormat, fo: FpFormat, x: UInt): UInt = convertCore(f, fo, x, None)

  /** x of format f in a format fo that holds it: exact, so no rounding logic. With f's exponent width the fields are
    * padded (a subnormal stays subnormal); with a wider exponent a subnormal of f is normalised (a leading-zero
    * count and a shift), which needs fo's bias to exceed f's by f.manBits. NaN becomes fo's canonical NaN (as
    * every other operator's); an identity for fo == f.
    */
  def widen(f: FpFormat, fo: FpFormat, x: UInt): UInt = if (fo == f) x else {
    require(fo.holds(f), s"${fo.name} does not hold ${f.name}: widen needs a wider format")
    require(fo.expBits == f.expBits || fo.bias - f.bias >= f.manBits, s"${fo.name}'s exponent cannot hold ${f.name}'s subnormals as normals")
    val u = new Unpacked(f, x)
    val pad = fo.manBits - f.manBits
    val plain = if (fo.expBits == f.expBits) Cat(u.sign, u.expF, u.frac, 0.U(pad.W))
      else {
        val lz = lzc(u.frac) // frac != 0 for a subnormal: its leading 1 becomes the hidden bit
        val subFrac = shlTrunc(Cat(u.frac, 0.U(1.W)), lz)(f.manBits - 1, 0) // the bits below the leading 1
        val subExp = (fo.bias - f.bias).U(fo.expBits.W) - lz
        val normExp = u.expF.pad(fo.expBits) + (fo.bias - f.bias).U(fo.expBits.W)
        val special = Cat(u.sign, Fill(fo.expBits, 1.U(1.W)), 0.U(fo.manBits.W)) // inf (NaN below)
        Mux(u.isZero, packZero(fo, u.sign), Mux(u.expOnes, special,
          Mux(u.expZero, Cat(u.sign, subExp, subFrac, 0.U(pad.W)), Cat(u.sign, normExp, u.frac, 0.U(pad.W)))))
      }
    Mux(u.isNaN, nan(fo), plain)
  }

  private def convertCore(pipe: Stager, f: FpFormat, fo: FpFormat, x: Timed[UInt], toPos: Option[Timed[Bool]]): Timed[UInt] = {
    val ew = expW(f) max expW(fo)
    val r = pipe.op(Seq(x) ++ toPos.map(t => t.map(0)(_.asUInt)), 2) { v =>
      val u = new Unpacked(f, v(0))
      roundIn(u.sign, u.exp.zext.pad(ew) + (fo.bias - f.bias).S, u.sig, false.B, toPos.map(_ => v(1)(0)),
        special(u.isNaN, u.isInf, u.isZero, u.sign))
    }
    roundPackT(pipe, fo, r, directed = toPos.isDefined)
  }
  private def convertCore(f: FpFormat, fo: FpFormat, x: UInt, toPos: Option[Bool]): UInt =
    convertCore(Stager.none, f, fo, comb(x), toPos.map(combB)).v

  // ---------------------------------------------------------------------------------------------------------
  // mul

  def mul(f: FpFormat, a: UInt, b: UInt): UInt = mulCore(f, a, b, f, None)
  /** a * b rounded toward +inf (toPos) or -inf. */
  def mulDirected(f: FpFormat, a: UInt, b: UInt, toPos: Bool): UInt = mulCore(f, a, b, f, Some(toPos))
  /** a * b of format f in the wider format fo, rounded to nearest: exact when fo has 2m+1 fraction bits and the
    * exponent range of the product (fp32 x fp32 in binary64), with a multiplier of f's significand width only.
    */
  def mulWide(f: FpFormat, fo: FpFormat, a: UInt, b: UInt): UInt = mulCore(f, a, b, fo, None)

  /** A product's operands unpacked, with the result's sign and each operand's class: what the DSP blocks start
    * from. The classes combine into the special result a step later (`sp`), beside the blocks: the fields' OR trees
    * and that combination in one step were TriPipe's routed critical path on ECP5 (into a multiplier's NaN flag). */
  class MulIn(f: FpFormat) extends Bundle {
    val sigA = UInt((f.manBits + 1).W)
    val sigB = UInt((f.manBits + 1).W)
    val expA = UInt(f.expBits.W)
    val expB = UInt(f.expBits.W)
    val sign = Bool()
    val toPos = Bool()
    val nanA = Bool(); val infA = Bool(); val zeroA = Bool()
    val nanB = Bool(); val infB = Bool(); val zeroB = Bool()
    def sp: Special = special(nanA || nanB || (infA && zeroB) || (zeroA && infB), infA || infB, zeroA || zeroB, sign)
  }

  /** A product's pieces between the steps of its sum: piece i (at bit offset offs(i) of the product, which the
    * hardware does not carry) of width widths(i), with the rest of the result beside them.
    */
  class MulParts(widths: Seq[Int], ew: Int) extends Bundle {
    val parts = MixedVec(widths.map(w => UInt(w.W)))
    val exp = SInt(ew.W)
    val sign = Bool()
    val toPos = Bool()
    val sp = new Special
  }

  /** The tiles of an n x n significand product on `dsp`: (a's bits, b's bits) of each, low bit first. */
  private[fp] def mulTiles(n: Int, dsp: DspShape): Seq[((Int, Int), (Int, Int))] = {
    def cuts(w: Int) = (0 until n by w).map(lo => (lo, (lo + w) min n))
    // by offset in the product, so the pairwise sums join neighbours
    (for (ca <- cuts(dsp.a); cb <- cuts(dsp.b)) yield (ca, cb)).sortBy { case ((a0, _), (b0, _)) => (a0 + b0, a0) }
  }

  /** The pieces `idx` of a product (piece i at bit offs(i)) added, as the `width` bits from bit `base` up. */
  private def sumOf(x: MulParts, idx: Seq[Int], offs: Seq[Int], base: Int, width: Int): UInt =
    idx.map(i => x.parts(i).pad(width) << (offs(i) - base)).reduce(_ +& _)(width - 1, 0)

  private def mulCore(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt], fo: FpFormat, toPos: Option[Timed[Bool]]): Timed[UInt] = {
    val ew = expW(f) max expW(fo)
    val n = f.manBits + 1
    // With a budget, a significand wider than a DSP block's inputs is multiplied in tiles of that size (each maps to
    // one block, with no fabric adder inside it) and the tiles are summed pairwise, a step per level, so registers
    // can go between the sums; without one the product is one multiplier.
    val tiles = if (pipe.budget.isDefined) mulTiles(n, pipe.dsp) else Seq(((0, n), (0, n)))
    val tiled = tiles.length > 1
    var offs = tiles.map { case ((a0, _), (b0, _)) => a0 + b0 }
    var widths = tiles.map { case ((a0, a1), (b0, b1)) => (a1 - a0) + (b1 - b0) }
    // the operands' fields first (the hidden bit is an OR of the exponent field), so a register can go between
    // them and the DSP blocks: the blocks' multiply is most of a stage on its own
    val in = pipe.op(Seq(a, b) ++ toPos.map(t => t.map(0)(_.asUInt)), Depth.reduce(f.manBits) + 1) { v =>
      val ua = new Unpacked(f, v(0))
      val ub = new Unpacked(f, v(1))
      val o = Wire(new MulIn(f))
      o.sigA := ua.sig; o.sigB := ub.sig; o.expA := ua.exp; o.expB := ub.exp
      o.sign := ua.sign ^ ub.sign
      o.toPos := (if (toPos.isDefined) v(2)(0) else false.B)
      o.nanA := ua.isNaN; o.infA := ua.isInf; o.zeroA := ua.isZero
      o.nanB := ub.isNaN; o.infB := ub.isInf; o.zeroB := ub.isZero
      o
    }
    val expOf = (x: MulIn) => (x.expA.zext.pad(ew) + x.expB.zext.pad(ew)) - (2 * f.bias - fo.bias - 1).S
    var parts = if (tiled && pipe.dsp.registered) {
      // the blocks with their own operand and result registers (DspTile): the fields beside the products wait as long
      // in flip-flops, and the exponent's sum goes in front of them. The operands' classes always reach a register
      // first (pipe.reg): on ECP5's 4-input LUTs a class (a 23-bit OR) and the special result combined from the
      // classes were 7 levels in one cycle, TriPipe's routed critical path (into a product's NaN flag)
      val x = pipe.reg(pipe.step(in, Depth.carry(ew))(v => v))
      val o = Wire(new MulParts(widths, ew))
      o.sign := pipe.beside(x.v.sign, DspTile.latency); o.toPos := pipe.beside(x.v.toPos, DspTile.latency)
      o.sp := pipe.beside(x.v.sp, DspTile.latency); o.exp := pipe.beside(expOf(x.v), DspTile.latency)
      for ((((a0, a1), (b0, b1)), i) <- tiles.zipWithIndex) o.parts(i) := DspTile(x.v.sigA(a1 - 1, a0), x.v.sigB(b1 - 1, b0))
      Timed(o, x.at + DspTile.latency, 0)
    } else pipe.step(in, Depth.dsp(pipe.dsp)) { x =>
      val o = Wire(new MulParts(widths, ew))
      o.sign := x.sign; o.toPos := x.toPos; o.sp := x.sp
      o.exp := expOf(x)
      for ((((a0, a1), (b0, b1)), i) <- tiles.zipWithIndex) o.parts(i) := x.sigA(a1 - 1, a0) * x.sigB(b1 - 1, b0)
      o
    }
    // pairwise sums down to two pieces; the last sum feeds the rounding in the same step (as a single product does)
    while (offs.length > 2) {
      val pairs = offs.indices.grouped(2).toSeq
      val nOffs = pairs.map(g => g.map(offs).min)
      // a sum of pieces below bit 2n fits in the span of its highest piece plus a carry, and never passes bit 2n
      val nWidths = pairs.zip(nOffs).map { case (g, o) => ((g.map(i => offs(i) + widths(i)).max + (if (g.size > 1) 1 else 0)) min 2 * n) - o }
      val oo = offs
      parts = pipe.step(parts, Depth.carry(2 * n)) { x =>
        val o = Wire(new MulParts(nWidths, ew))
        o := DontCare
        o.exp := x.exp; o.sign := x.sign; o.toPos := x.toPos; o.sp := x.sp
        for ((g, j) <- pairs.zipWithIndex) o.parts(j) := sumOf(x, g, oo, nOffs(j), nWidths(j))
        o
      }
      offs = nOffs; widths = nWidths
    }
    val oo = offs
    val r = pipe.step(parts, if (tiled) Depth.carry(2 * n) else 0) { x =>
      // 2m+2 bits, binary point after the top bit pair
      roundIn(x.sign, x.exp, sumOf(x, oo.indices, oo, 0, 2 * n), false.B, toPos.map(_ => x.toPos), x.sp)
    }
    // A product normalised left has at most n leading zeros: with one operand normal (hidden bit set) and the other
    // z <= n - 1 leading zeros, the 2n-bit product has z or z + 1. Two subnormal operands give an exponent below 1
    // when fo's bias is below 2 f.bias - 2 (ex = 1 + 1 - (2 f.bias - fo.bias - 1) < 1): the right shift serves
    // them, so the LZC and left shifter need n + 1 positions, not 2n (a wider fo, mulWide, keeps all of them).
    val maxLs = if (fo.bias < 2 * f.bias - 2) n else Int.MaxValue
    roundPackT(pipe, fo, r, maxLeftShift = maxLs, directed = toPos.isDefined)
  }
  private def mulCore(f: FpFormat, a: UInt, b: UInt, fo: FpFormat, toPos: Option[Bool]): UInt =
    mulCore(Stager.none, f, comb(a), comb(b), fo, toPos.map(combB)).v

  // ---------------------------------------------------------------------------------------------------------
  // div: radix-2 digit recurrence (the restoring one's bits, carried non-restoring), split into pre / step / post so
  // FpDivPipe can register between them

  /** State carried between divider steps. A special result (NaN, ±inf, ±0) is three class flags plus the sign,
    * so pipeline registers don't carry a whole word for it.
    */
  class DivState(val f: FpFormat) extends Bundle {
    val resNaN = Bool()
    val resInf = Bool()
    val resZero = Bool()
    val sign = Bool()
    val exp = SInt(expW(f).W)
    val divisor = UInt((f.manBits + 1).W)
    /** The partial remainder less the divisor, two's complement in [-divisor, divisor) (divStep). */
    val rem = UInt((f.manBits + 3).W)
    val quo = UInt((f.manBits + 3).W)
  }

  /** Number of recurrence steps: m+1 significand bits, a guard bit and one bit for the quotient's range (1/2, 2). */
  def divSteps(f: FpFormat): Int = f.manBits + 3

  /** divPre after the leading-zero counts: a DivState whose rem and divisor hold the operands' significands before
    * normalising and whose exp is their exponents' difference, with the two counts.
    */
  class DivPreMid(f0: FpFormat) extends DivState(f0) {
    val lzA = UInt(log2Ceil(f0.manBits + 1).W)
    val lzB = UInt(log2Ceil(f0.manBits + 1).W)
  }

  /** divPre's first half: classes, the result's sign and the leading zeros of both significands. */
  def divPreCount(f: FpFormat, a: UInt, b: UInt): DivPreMid = {
    val ua = new Unpacked(f, a)
    val ub = new Unpacked(f, b)
    val s = Wire(new DivPreMid(f))
    val isNaN = ua.isNaN || ub.isNaN || (ua.isZero && ub.isZero) || (ua.isInf && ub.isInf)
    val isInf = ua.isInf || ub.isZero
    val isZero = ua.isZero || ub.isInf
    s.resNaN := isNaN
    s.resInf := !isNaN && isInf
    s.resZero := !isNaN && !isInf && isZero
    s.sign := ua.sign ^ ub.sign
    s.exp := ua.exp.zext.pad(expW(f)) - ub.exp.zext.pad(expW(f)) + f.bias.S
    s.rem := ua.sig; s.divisor := ub.sig; s.quo := 0.U
    s.lzA := lzc(ua.sig); s.lzB := lzc(ub.sig)
    s
  }

  /** divPre's second half: both significands normalised, the exponent corrected by their shifts, and the first
    * partial remainder less the divisor (divStep's state). */
  def divPreShift(f: FpFormat, m: DivPreMid): DivState = {
    val s = Wire(new DivState(f))
    s.resNaN := m.resNaN; s.resInf := m.resInf; s.resZero := m.resZero; s.sign := m.sign
    s.exp := m.exp - m.lzA.zext + m.lzB.zext
    val d = shlTrunc(m.divisor, m.lzB)
    s.divisor := d
    s.rem := minus(shlTrunc(m.rem(f.manBits, 0), m.lzA), d, f.manBits + 3)
    s.quo := 0.U
    s
  }

  def divPre(f: FpFormat, a: UInt, b: UInt): DivState = divPreShift(f, divPreCount(f, a, b))

  /** a - b as w bits of two's complement (a, b unsigned, narrower than w), written as a + ~b + 1: firtool 1.62.1
    * folded `(a.pad(w) - b.pad(w))` with a constant a (a reciprocal's 1.0) as if the difference's top bit were always
    * 0 (its borrow lost), and every reciprocal of the non-restoring divider came out wrong. */
  private def minus(a: UInt, b: UInt, w: Int): UInt = addOrSub(a, b, true.B, w)

  /** x + y, or x - y = x + ~y + 1 when `sub`, as w bits of two's complement (x, y unsigned, at most w bits): one carry
    * chain with the inversion in its LUTs, where Mux(sub, x - y, x + y) builds two chains and a mux behind them (the
    * adder's sum and the divider's step). */
  private def addOrSub(x: UInt, y: UInt, sub: Bool, w: Int): UInt = (x.pad(w) +& (y.pad(w) ^ Fill(w, sub)) +& sub.asUInt)(w - 1, 0)

  /** One quotient bit of the restoring recurrence (the bit is 1 when the partial remainder r >= d, and r becomes
    * 2 (r - d) or 2 r), carried non-restoring: the state holds u = r - d, whose sign is the bit, and the next
    * u = 2 r' - d is 2 u - d after a 1 and 2 u + d after a 0. One add or subtract on one carry chain (the choice in
    * the chain's LUTs, as the adder's), where the restoring form built a compare, a subtract and a mux: the same
    * bits, u staying in [-d, d). */
  def divStep(f: FpFormat, in: DivState): DivState = {
    val s = Wire(new DivState(f))
    s := in
    val w = f.manBits + 3
    val q = !in.rem(w - 1)
    val twice = Cat(in.rem(w - 2, 0), 0.U(1.W))
    s.rem := addOrSub(twice, in.divisor, q, w)
    s.quo := Cat(in.quo(f.manBits + 1, 0), q)
    s
  }

  def divPost(f: FpFormat, s: DivState): UInt = divPostT(Stager.none, f, Timed(s, 0, 0)).v

  /** Round and pack the quotient: quo / 2^(m+2) * 2^(exp - bias), quo m+3 bits with its top bit at position m+2
    * or m+1 (normalised operands: quotient in (1/2, 2), at most one leading zero).
    */
  def divPostT(pipe: Stager, f: FpFormat, x: Timed[DivState]): Timed[UInt] = {
    val r = pipe.step(x, Depth.reduce(f.manBits + 2) + 1) { s =>
      // the remainder is zero when u = -d (u = 2 r - d with r = 0)
      roundIn(s.sign, s.exp, s.quo, s.rem =/= minus(0.U, s.divisor, f.manBits + 3), None,
        special(s.resNaN, s.resInf, s.resZero, s.sign))
    }
    roundPackT(pipe, f, r, maxLeftShift = 1)
  }

  def div(f: FpFormat, a: UInt, b: UInt): UInt = {
    var s = divPre(f, a, b)
    for (_ <- 0 until divSteps(f)) s = divStep(f, s)
    divPost(f, s)
  }

  // ---------------------------------------------------------------------------------------------------------
  // comparisons and selection

  def isNaN(f: FpFormat, a: UInt): Bool = new Unpacked(f, a).isNaN

  /** a < b ignoring NaN (callers mask NaN); -0 == +0. */
  private def ltRaw(f: FpFormat, ua: Unpacked, ub: Unpacked): Bool = {
    val bothZero = ua.isZero && ub.isZero
    val diffSign = ua.sign =/= ub.sign
    Mux(diffSign, ua.sign && !bothZero, Mux(ua.sign, ua.mag > ub.mag, ua.mag < ub.mag))
  }
  private def eqRaw(f: FpFormat, ua: Unpacked, ub: Unpacked): Bool =
    (ua.sign === ub.sign && ua.mag === ub.mag) || (ua.isZero && ub.isZero)

  def lt(f: FpFormat, a: UInt, b: UInt): Bool = {
    val ua = new Unpacked(f, a); val ub = new Unpacked(f, b)
    !ua.isNaN && !ub.isNaN && ltRaw(f, ua, ub)
  }
  def gt(f: FpFormat, a: UInt, b: UInt): Bool = lt(f, b, a)
  def eq(f: FpFormat, a: UInt, b: UInt): Bool = {
    val ua = new Unpacked(f, a); val ub = new Unpacked(f, b)
    !ua.isNaN && !ub.isNaN && eqRaw(f, ua, ub)
  }
  def le(f: FpFormat, a: UInt, b: UInt): Bool = {
    val ua = new Unpacked(f, a); val ub = new Unpacked(f, b)
    !ua.isNaN && !ub.isNaN && (ltRaw(f, ua, ub) || eqRaw(f, ua, ub))
  }
  def ge(f: FpFormat, a: UInt, b: UInt): Bool = le(f, b, a)

  /** if a NaN -> b, else if b NaN -> a, else if (a < b) a else b */
  def minNum(f: FpFormat, a: UInt, b: UInt): UInt =
    Mux(isNaN(f, a), b, Mux(isNaN(f, b), a, Mux(lt(f, a, b), a, b)))
  /** if a NaN -> b, else if b NaN -> a, else if (a > b) a else b */
  def maxNum(f: FpFormat, a: UInt, b: UInt): UInt =
    Mux(isNaN(f, a), b, Mux(isNaN(f, b), a, Mux(gt(f, a, b), a, b)))
  /** if either NaN -> canonical NaN, else if (a < b) a else b */
  def minProp(f: FpFormat, a: UInt, b: UInt): UInt =
    Mux(isNaN(f, a) || isNaN(f, b), nan(f), Mux(lt(f, a, b), a, b))
  /** if either NaN -> canonical NaN, else if (a > b) a else b */
  def maxProp(f: FpFormat, a: UInt, b: UInt): UInt =
    Mux(isNaN(f, a) || isNaN(f, b), nan(f), Mux(gt(f, a, b), a, b))

  // ---------------------------------------------------------------------------------------------------------
  // the same operators on pipeline values (Timed): registers placed inside them by the pipe's budget

  def addT(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt]): Timed[UInt] = addCore(pipe, f, a, b, negB = false, f, None)
  def subT(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt]): Timed[UInt] = addCore(pipe, f, a, b, negB = true, f, None)
  def subDirectedT(pipe: Stager, f: FpFormat, fo: FpFormat, a: Timed[UInt], b: Timed[UInt], toPos: Timed[Bool]): Timed[UInt] =
    addCore(pipe, f, a, b, negB = true, fo, Some(toPos))
  def mulT(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt]): Timed[UInt] = mulCore(pipe, f, a, b, f, None)
  def mulDirectedT(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt], toPos: Timed[Bool]): Timed[UInt] =
    mulCore(pipe, f, a, b, f, Some(toPos))
  def mulWideT(pipe: Stager, f: FpFormat, fo: FpFormat, a: Timed[UInt], b: Timed[UInt]): Timed[UInt] = mulCore(pipe, f, a, b, fo, None)
  def convertT(pipe: Stager, f: FpFormat, fo: FpFormat, x: Timed[UInt], toPos: Timed[Bool]): Timed[UInt] =
    convertCore(pipe, f, fo, x, Some(toPos))
  def convertNearestT(pipe: Stager, f: FpFormat, fo: FpFormat, x: Timed[UInt]): Timed[UInt] = convertCore(pipe, f, fo, x, None)

  /** A comparison or a selection as one segment: the magnitude compare on the carry chain, the NaN and sign logic
    * and (for a selection) the multiplexer.
    */
  private def cmpLevels(f: FpFormat): Int = Depth.carry(f.width - 1) + 2
  def cmpT(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt])(fn: (FpFormat, UInt, UInt) => Bool): Timed[Bool] =
    pipe.op(Seq(a, b), cmpLevels(f))(v => fn(f, v(0), v(1)))
  def selT(pipe: Stager, f: FpFormat, a: Timed[UInt], b: Timed[UInt])(fn: (FpFormat, UInt, UInt) => UInt): Timed[UInt] =
    pipe.op(Seq(a, b), cmpLevels(f) + 1)(v => fn(f, v(0), v(1)))
}
