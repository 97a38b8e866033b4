package rtaccel.top

import chisel3._
import chisel3.util._

/** AXI4-Lite, 32-bit data, master's view (the board top's port is Flipped). */
class AxiLite(val addrBits: Int) extends Bundle {
  val aw = Decoupled(new Bundle { val addr = UInt(addrBits.W) })
  val w = Decoupled(new Bundle { val data = UInt(32.W); val strb = UInt(4.W) })
  val b = Flipped(Decoupled(new Bundle { val resp = UInt(2.W) }))
  val ar = Decoupled(new Bundle { val addr = UInt(addrBits.W) })
  val r = Flipped(Decoupled(new Bundle { val data = UInt(32.W); val resp = UInt(2.W) }))
}

object AxiLite {
  val Okay = 0; val SlvErr = 2; val DecErr = 3
}

/** What the platform tells the register file, per cycle. */
class RegEvents extends Bundle {
  val busy = Bool()       // a TU holds a ray or a hit waits for the host
  val rayIn = Bool()      // a ray was accepted from the stream
  val hitOut = Bool()     // a hit left on the stream
  val readError = Bool()  // ... flagged with a memory read error
  val overflow = Bool()   // ... flagged with a stack overflow
  val stepLimit = Bool()  // ... flagged with the step limit
}

/** The host interface of the board top (RegMap, docs/registers.md): an AXI4-Lite slave with one read and
  * one write in flight, the batch control (START gates the ray stream until RAY_COUNT rays are in; DONE when
  * as many hits are out), sticky error status, interrupts and 64-bit counter snapshots.
  * A write needs AW and W together; a partial write (WSTRB not 0xF) or a write to a read-only register is
  * answered SLVERR and changes nothing; an unmapped address is answered DECERR (reads return 0).
  * `constants`: the read-only configuration words, by register.
  */
class RegFile(constants: Seq[(RegMap.Reg, BigInt)], counterNames: Seq[String], primBaseBits: Int, maxLevelReset: Int,
              levelBits: Int, maxStepsReset: Long, stepBits: Int) extends Module {
  require(maxStepsReset >= 0 && maxStepsReset < (1L << stepBits), s"MAX_STEPS reset value $maxStepsReset does not fit $stepBits bits")
  private val addrBits = RegMap.addrBits(counterNames)
  val io = IO(new Bundle {
    val lite = Flipped(new AxiLite(addrBits))
    val irq = Output(Bool())
    val events = Input(new RegEvents)
    val counters = Input(Vec(counterNames.length, UInt(64.W)))
    val acceptRays = Output(Bool())  // the ray stream may deliver (a batch is running and not yet full)
    val running = Output(Bool())     // a batch is running (START .. DONE)
    val lastHitIndex = Output(UInt(32.W)) // RAY_COUNT - 1: the hit that ends the batch carries TLAST
    val clearCounters = Output(Bool())
    val primBase = Output(UInt(primBaseBits.W))
    val maxLevel = Output(UInt(levelBits.W))
    val maxSteps = Output(UInt(stepBits.W))
  })
  import RegMap._
  private def bit(r: Reg, f: String): Int = r.fields.find(_.name == f).get.lsb

  // ---- state
  val rayCount = RegInit(0.U(32.W))
  val primBase = RegInit(0.U(64.W))
  val maxLevel = RegInit(maxLevelReset.U(levelBits.W))
  val maxSteps = RegInit(maxStepsReset.U(stepBits.W))
  val irqEnable = RegInit(0.U(2.W))
  val irqStatus = RegInit(0.U(2.W))
  val running = RegInit(false.B)
  val done = RegInit(false.B)
  val stickyReadError = RegInit(false.B)
  val stickyOverflow = RegInit(false.B)
  val stickyStepLimit = RegInit(false.B)
  val raysIn = RegInit(0.U(32.W))
  val hitsDone = RegInit(0.U(32.W))

  // ---- write channel: AW and W accepted together, then B
  val bValid = RegInit(false.B); val bResp = RegInit(0.U(2.W))
  val wFire = io.lite.aw.valid && io.lite.w.valid && !bValid
  io.lite.aw.ready := wFire; io.lite.w.ready := wFire
  io.lite.b.valid := bValid; io.lite.b.bits.resp := bResp
  when(io.lite.b.fire) { bValid := false.B }
  val wAddr = io.lite.aw.bits.addr; val wData = io.lite.w.bits.data
  val fullWord = io.lite.w.bits.strb === "b1111".U
  private val writable = fixed.filter(r => r.access != RO)
  private val readOnly = all(counterNames).filter(_.access == RO)
  val isWritable = writable.map(r => wAddr === r.offset.U).reduce(_ || _)
  val isReadOnly = readOnly.map(r => wAddr === r.offset.U).reduce(_ || _)
  def wrote(r: Reg): Bool = wFire && fullWord && wAddr === r.offset.U
  when(wFire) {
    bValid := true.B
    bResp := Mux(isWritable && fullWord, AxiLite.Okay.U, Mux(isWritable || isReadOnly, AxiLite.SlvErr.U, AxiLite.DecErr.U))
  }
  when(wrote(RayCount)) { rayCount := wData }
  when(wrote(PrimBaseLo)) { primBase := Cat(primBase(63, 32), wData) }
  when(wrote(PrimBaseHi)) { primBase := Cat(wData, primBase(31, 0)) }
  when(wrote(MaxLevel)) { maxLevel := wData(levelBits - 1, 0) }
  when(wrote(MaxSteps)) { maxSteps := wData(stepBits - 1, 0) }
  when(wrote(IrqEnable)) { irqEnable := wData(1, 0) }
  val start = wrote(Control) && wData(bit(Control, "START"))
  val softReset = wrote(Control) && wData(bit(Control, "SOFT_RESET"))
  io.clearCounters := (wrote(Control) && wData(bit(Control, "CLEAR_COUNTERS"))) || softReset

  // ---- batch control and status
  val errorEvent = io.events.hitOut && (io.events.readError || io.events.overflow || io.events.stepLimit)
  when(io.events.rayIn) { raysIn := raysIn + 1.U }
  when(io.events.hitOut) { hitsDone := hitsDone + 1.U }
  when(io.events.hitOut && io.events.readError) { stickyReadError := true.B }
  when(io.events.hitOut && io.events.overflow) { stickyOverflow := true.B }
  when(io.events.hitOut && io.events.stepLimit) { stickyStepLimit := true.B }
  val lastHit = running && io.events.hitOut && hitsDone + 1.U === rayCount
  val doneNow = lastHit || (start && rayCount === 0.U)
  when(doneNow) { running := false.B; done := true.B }
  val irqSet = Cat(errorEvent, doneNow)
  val irqClear = Mux(wrote(IrqStatus), wData(1, 0), 0.U)
  irqStatus := (irqStatus & ~irqClear) | irqSet
  when(start && rayCount =/= 0.U) { running := true.B; done := false.B; raysIn := 0.U; hitsDone := 0.U }
  when(softReset) {
    running := false.B; done := false.B; raysIn := 0.U; hitsDone := 0.U
    stickyReadError := false.B; stickyOverflow := false.B; stickyStepLimit := false.B; irqStatus := 0.U
  }
  io.acceptRays := running && raysIn < rayCount
  io.running := running
  // a register of its own, written with RAY_COUNT: the hit stream's TLAST compares with it, not through a subtractor
  val lastHitIndex = RegInit(0.U(32.W))
  when(wrote(RayCount)) { lastHitIndex := wData - 1.U }
  io.lastHitIndex := lastHitIndex
  io.irq := (irqStatus & irqEnable).orR
  io.primBase := primBase(primBaseBits - 1, 0)
  io.maxLevel := maxLevel
  io.maxSteps := maxSteps

  // ---- read channel: the data is registered with the AR handshake, then R
  val rValid = RegInit(false.B); val rData = RegInit(0.U(32.W)); val rResp = RegInit(0.U(2.W))
  io.lite.ar.ready := !rValid
  io.lite.r.valid := rValid; io.lite.r.bits.data := rData; io.lite.r.bits.resp := rResp
  when(io.lite.r.fire) { rValid := false.B }
  val rAddr = io.lite.ar.bits.addr
  // reading LO returns the live low word and keeps the high word of that instant for the HI read
  val snapHi = RegInit(0.U(32.W)); val snapIdx = RegInit(counterNames.length.U(log2Ceil(counterNames.length + 1).W)) // none yet: HI reads live
  val status = Seq("BUSY" -> (running || io.events.busy), "DONE" -> done, "READ_ERROR" -> stickyReadError,
    "OVERFLOW" -> stickyOverflow, "RUNNING" -> running, "STEP_LIMIT" -> stickyStepLimit).map { case (f, v) => v.asUInt << bit(Status, f) }.reduce(_ | _)
  val table: Seq[(Int, UInt)] = constants.map { case (r, v) => r.offset -> v.U(32.W) } ++ Seq(
    Id.offset -> Magic.U(32.W), Version.offset -> ((VersionMajor << 16) | VersionMinor).U(32.W),
    Status.offset -> status, IrqEnable.offset -> irqEnable.pad(32), IrqStatus.offset -> irqStatus.pad(32),
    MaxLevel.offset -> maxLevel.pad(32), MaxSteps.offset -> maxSteps.pad(32), RayCount.offset -> rayCount, PrimBaseLo.offset -> primBase(31, 0),
    PrimBaseHi.offset -> primBase(63, 32), HitsDone.offset -> hitsDone, RaysIn.offset -> raysIn, Control.offset -> 0.U(32.W)) ++
    counterNames.indices.flatMap { i =>
      Seq(CounterBase + 8 * i -> io.counters(i)(31, 0),
        CounterBase + 8 * i + 4 -> Mux(snapIdx === i.U, snapHi, io.counters(i)(63, 32)))
    }
  require(table.map(_._1).distinct.length == table.length, "two registers share an address")
  require(table.forall(_._1 % 4 == 0), "a register off a word boundary")
  // The word by a tree of 2:1 muxes on the word address's bits, unmapped words 0 (an unaligned address reads 0): as
  // many muxes as a MuxLookup over the table, but as deep as the address is wide, where a MuxLookup is a chain of
  // compares as long as the table (RegFile's routed critical path on ECP5). A dynamic Vec index would be a shifter.
  val mapped = table.map(t => rAddr === t._1.U).reduce(_ || _)
  when(io.lite.ar.fire) {
    rValid := true.B
    rData := Mux(rAddr(1, 0) === 0.U, RegFile.muxTree(rAddr >> 2, table.map { case (a, v) => (a >> 2) -> v }), 0.U)
    rResp := Mux(mapped, AxiLite.Okay.U, AxiLite.DecErr.U)
    // a LO read snapshots its counter's high word (the counter's index from the address, as for the words)
    val counterLo = rAddr >= CounterBase.U && rAddr < (CounterBase + 8 * counterNames.length).U && rAddr(2, 0) === 0.U
    val counterIdx = rAddr(addrBits - 1, 3) - (CounterBase >> 3).U // CounterBase is a multiple of 8
    when(counterLo) { snapHi := RegFile.muxTree(counterIdx, io.counters.map(_(63, 32)).zipWithIndex.map(_.swap)); snapIdx := counterIdx }
  }
}

object RegFile {
  /** The value at index `sel` of a sparse table (index -> value, 0 elsewhere): a binary tree of 2:1 muxes on `sel`'s
    * bits, low bit at the leaves, with the subtrees that hold no entry left out.
    */
  def muxTree(sel: UInt, entries: Seq[(Int, UInt)]): UInt = {
    require(entries.map(_._1).distinct.length == entries.length && entries.forall(e => e._1 >= 0 && e._1 < (1 << sel.getWidth)))
    val width = entries.map(_._2.getWidth).max
    def go(bit: Int, es: Seq[(Int, UInt)]): UInt =
      if (es.isEmpty) 0.U(width.W)
      else if (bit < 0) es.head._2.pad(width)
      else {
        val (hi, lo) = es.partition(e => ((e._1 >> bit) & 1) == 1)
        Mux(sel(bit), go(bit - 1, hi), go(bit - 1, lo))
      }
    go(sel.getWidth - 1, entries)
  }
}
