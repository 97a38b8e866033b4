package rtaccel.fp

import chisel3._
import chisel3.util._

/** A value of a no-stall pipeline: valid `at` cycles after the pipeline's input, with an estimated `depth` of LUT
  * levels of logic since its last register. Operators built on [[Stager]] read their inputs at the latest of their
  * `at`s (earlier ones are delayed by shift registers) and add registers where the depth would pass the budget,
  * so a pipeline's latency follows from its budget instead of being written down by hand.
  */
final case class Timed[+T <: Data](v: T, at: Int, depth: Int) {
  def map[U <: Data](levels: Int)(fn: T => U): Timed[U] = Timed(fn(v), at, depth + levels)
}

/** A family's DSP block (boards/timing.json): the widest unsigned operands it multiplies without fabric logic
  * (`dsp_unsigned_bits`: Xilinx's DSP48, 25 x 18 signed, 24 x 17; Lattice ECP5's MULT18X18D 18 x 18) and its
  * unregistered multiply in LUT levels (`dsp_levels`, which the timing proxy counts too: area.Levels). `registered`
  * (`dsp_primitive`: MULT18X18D): with PIPELINE, each tile is the block with its own input and output registers
  * ([[DspTile]]), two cycles with no fabric logic between them.
  */
final case class DspShape(a: Int, b: Int, levels: Int = 4, registered: Boolean = false) {
  require(a >= 2 && b >= 2, s"a DSP block multiplies at least 2 x 2 bits (got $a x $b)")
  require(levels >= 0, s"a DSP block's levels must be >= 0 (got $levels)")
  require(!registered || (a <= DspTile.Bits && b <= DspTile.Bits), s"registered DSP tiles are at most ${DspTile.Bits} x ${DspTile.Bits} bits (got $a x $b)")
  override def toString: String = s"${a}x$b/$levels" + (if (registered) "/reg" else "")
}
object DspShape {
  val Dsp48: DspShape = DspShape(24, 17, 4)
}

/** Register placement of a pipelined datapath (PIPELINE=, docs/timing.md). `budget` = the most LUT levels
  * allowed between two registers; None keeps the fixed stages the design had before pipelining was a parameter
  * (no register inside an operator). Every register this places is a plain `RegNext` (the pipelines never stall),
  * so results do not depend on where the registers go: only latencies do. With a budget, multipliers are cut into
  * products of the target's DSP blocks (`dsp`), summed on carry chains with registers between the sums.
  * `delayRam` (families without shift-register LUTs, boards/timing.json `delay_ram_cycles`): a value delayed by at
  * least that many cycles goes through a ring in LUT RAM instead of a chain of flip-flops (`chain`).
  * `lutInputs` (boards/timing.json `lut_inputs`, 6 where absent): where a wide OR after a shifter takes a LUT level
  * more than Depth counts (4-input LUTs), roundPack takes its sticky bit another way (Fp.roundPackT).
  */
final class Stager(val budget: Option[Int], val dsp: DspShape = DspShape.Dsp48, val delayRam: Option[Int] = None, val lutInputs: Int = Depth.LutInputs) {
  require(delayRam.forall(_ >= 2), s"a delay in LUT RAM takes at least 2 cycles (got ${delayRam.get})")
  require(budget.forall(_ >= 1), s"a pipeline budget must be at least 1 LUT level (got ${budget.get})")
  private var placed = Stager.Census()
  /** The family's LUTs have fewer inputs than Depth counts for (ECP5's 4): the operators cut some segments apart that
    * the counts would join (Fp.roundPackT, Fp.addCore, FpDivPipe.stepLevels). */
  def smallLuts: Boolean = lutInputs < Depth.LutInputs
  /** The register bits this Stager has placed so far (a census for the cost model; synthesis may trim unused ones). */
  def census: Stager.Census = placed
  /** x delayed `cycles` by flip-flops beside a unit with registers of its own (a DSP tile), counted in the census. */
  def beside[T <: Data](x: T, cycles: Int): T = { count(x, cycles); ShiftRegister(x, cycles) }
  private def count(x: Data, cycles: Int): Unit = {
    val w = Stager.knownWidth(x).toLong
    placed = placed + (if (cycles >= Stager.ChainMin) Stager.Census(w * cycles, w * cycles, w * ((cycles + 31) / 32)) else Stager.Census(w * cycles))
  }
  // one shift register per (value, cycle) however many operators read it there
  private val delayed = new java.util.IdentityHashMap[Data, scala.collection.mutable.Map[Int, Data]]()

  /** A module input: `depth` levels of logic in front of it that this module cannot see (the driver's). */
  def in[T <: Data](x: T, depth: Int = 0): Timed[T] = Timed(x, 0, depth)

  /** A register on x, always (a stage boundary of the design); a value registered already is passed on. */
  def reg[T <: Data](x: Timed[T]): Timed[T] =
    if (budget.isDefined && x.depth == 0 && x.at > 0) x else { count(x.v, 1); Timed(RegNext(x.v), x.at + 1, 0) }

  /** x as read `at` (>= x.at): delayed by shift registers when later. */
  def delayTo[T <: Data](x: Timed[T], at: Int): Timed[T] = {
    require(at >= x.at, s"cannot read a value valid at cycle ${x.at} at cycle $at")
    if (at == x.at) x else {
      val byAt = delayed.computeIfAbsent(x.v, _ => scala.collection.mutable.Map[Int, Data]())
      Timed(byAt.getOrElseUpdate(at, { count(x.v, at - x.at); chain(x.v, at - x.at) }).asInstanceOf[T], at, 0)
    }
  }

  /** x delayed by n cycles (no reset): flip-flops, or a ring in LUT RAM from `delayRam` cycles on (a value whose
    * width is not known yet, or a constant, stays in flip-flops).
    */
  def chain[T <: Data](x: T, n: Int): T = delayRam match {
    case Some(min) if n >= min && !x.isLit && x.widthOption.contains(Stager.knownWidth(x)) => Stager.ramDelay(x, n, rowOf(n))
    case _ => ShiftRegister(x, n)
  }
  // one row counter per ring length, shared by every ring of that length (each counter is a carry chain on ECP5)
  private val rows = scala.collection.mutable.Map[Int, UInt]()
  private def rowOf(n: Int): UInt = rows.getOrElseUpdate(n, Stager.ringRow(n))

  /** The latest of xs' times and the depth there. */
  def join(xs: Timed[Data]*): (Int, Int) = {
    val at = xs.map(_.at).max
    (at, xs.filter(_.at == at).map(_.depth).max)
  }

  /** A valid bit for a value valid at `at`, from the valid of the pipeline's input (reset to false). */
  def valid(v: Bool, at: Int): Bool = { count(v, at); ShiftRegister(v, at, false.B, true.B) }

  /** One segment of `levels` LUT levels: a register goes in front of it when the path would pass the budget. */
  def step[A <: Data, B <: Data](x: Timed[A], levels: Int)(fn: A => B): Timed[B] = stepAt(x, levels)((v, _) => fn(v))

  /** [[step]] whose `fn` also takes the cycle it runs in (after the register in front of it, if one goes there). */
  def stepAt[A <: Data, B <: Data](x: Timed[A], levels: Int)(fn: (A, Int) => B): Timed[B] = {
    val cut = budget.exists(b => x.depth > 0 && x.depth + levels > b)
    val y = if (cut) { count(x.v, 1); Timed(RegNext(x.v), x.at + 1, 0) } else x
    Timed(fn(y.v, y.at), y.at, y.depth + levels)
  }

  /** x loaded into a register when `en` (a value held between loads: [[Fold]]), counted in the census. */
  def hold[T <: Data](x: T, en: Bool): T = { count(x, 1); RegEnable(x, en) }

  /** `fn` of several inputs read at the same cycle, as one segment of `levels`. */
  def op[B <: Data](xs: Seq[Timed[UInt]], levels: Int)(fn: Seq[UInt] => B): Timed[B] = {
    val (at, d) = join(xs: _*)
    val aligned = xs.map(delayTo(_, at))
    val v = VecInit(aligned.map(_.v))
    step(Timed(v, at, d), levels)(vv => fn(vv.toSeq))
  }

  /** Many values read at one cycle (a stage's operands). */
  def align[T <: Data](xs: Seq[Timed[T]]): Seq[Timed[T]] = {
    val at = xs.map(_.at).max
    xs.map(delayTo(_, at))
  }
}

object Stager {
  /** Register bits: all of them, those in delay chains of ChainMin cycles or more, and the 32-deep shift-register
    * LUTs (Xilinx SRLC32E) such chains take when synthesis maps them into LUT RAM (make area shows it does).
    */
  final case class Census(bits: Long = 0, chainBits: Long = 0, chainLuts: Long = 0) {
    def +(o: Census): Census = Census(bits + o.bits, chainBits + o.chainBits, chainLuts + o.chainLuts)
    def -(o: Census): Census = Census(bits - o.bits, chainBits - o.chainBits, chainLuts - o.chainLuts)
    def *(k: Long): Census = Census(bits * k, chainBits * k, chainLuts * k)
  }
  /** Yosys' shift-register mapping takes chains of three or more. */
  val ChainMin = 3
  /** Bits of x whose widths Chisel knows before inference (an inferred one counts 0: the census is a floor). */
  def knownWidth(x: Data): Int = x match {
    case a: Aggregate => a.getElements.map(knownWidth).sum
    case e => e.widthOption.getOrElse(0)
  }
  /** x delayed by n >= 2 cycles through a ring of n - 1 entries in LUT RAM (read before the write at the same row)
    * and a register after the read, for families whose flip-flops cost a slice each (ECP5: no shift-register LUTs).
    */
  def ramDelay[T <: Data](x: T, n: Int, row: UInt): T = {
    require(n >= 2, s"a delay in LUT RAM takes at least 2 cycles (got $n)")
    val ring = Mem(ramRows(n), chiselTypeOf(x)).suggestName("delay")
    // From 3 cycles on, two registers after the read: synthesis folds the first into the read port and, where LUT
    // RAM reads asynchronously (ECP5), moves it onto the read address, so the second is what keeps the ring's
    // output from running into the logic that reads it (TriPipe's routed critical path on ECP5: a ring's read
    // through an adder's carry chain, 7.26 ns).
    val out = if (n >= 3) RegNext(RegNext(ring(row))) else RegNext(ring(row)) // written ramRows(n) cycles ago
    ring(row) := x
    out
  }
  /** Rows of the ring of an n-cycle delay: n less its registers after the read. */
  def ramRows(n: Int): Int = if (n >= 3) n - 2 else n - 1
  /** The row of the ring of an n-cycle delay (ramRows(n) rows): counts 0 .. ramRows(n) - 1 and wraps, from reset. */
  def ringRow(n: Int): UInt = {
    val rows = ramRows(n)
    val row = RegInit(0.U(log2Ceil(rows).max(1).W))
    row := Mux(row === (rows - 1).U, 0.U, row + 1.U)
    row
  }
  /** No register inside an operator: the combinational operators of [[Fp]]. */
  def none: Stager = new Stager(None)
}

/** Estimated LUT levels (six-input LUTs) of the pieces the operators are made of; the registers [[Stager]] places
  * follow these, and make area's measured levels show how close they are (docs/timing.md).
  */
object Depth {
  /** The LUT size every count below assumes (Xilinx LUT6); a family with smaller LUTs says so in boards/timing.json. */
  val LutInputs = 6
  private def log(b: Double, n: Int): Int = math.ceil(math.log(n.toDouble max 2) / math.log(b) - 1e-9).toInt
  /** An OR (or AND) of n bits. */
  def reduce(n: Int): Int = log(6, n) max 1
  /** A shifter by up to n places: one 4:1 mux per LUT per two shift bits; on k < 6 inputs a 2:1 mux per level. */
  def shift(n: Int, k: Int = LutInputs): Int = if (k >= LutInputs) (log(2, n) + 1) / 2 max 1 else log(2, n) max 1
  /** An adder or comparator of n bits on a carry chain: a LUT into the chain and the chain itself. */
  def carry(n: Int): Int = 1 + n / 24
  /** A leading-zero count of n bits (a tree of 2:1 selections): two per LUT6; on k < 6 inputs one per level, log2(n)
    * (64 bits: 6 levels, the routed critical path of WatertightPipe on ECP5 was such a count, 7 elements there).
    */
  def lzc(n: Int, k: Int = LutInputs): Int = if (k >= LutInputs) (log(2, n) + 1) / 2 + 1 else log(2, n) max 1
  /** A product in one DSP block: the block's multiply and its post-adder (the proxy counts the same: area.Levels). */
  def dsp(d: DspShape): Int = d.levels + 1
}
