package rtaccel.top

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random
import rtaccel.top.RegMap._

/** The AXI4-Lite register file alone, driven the way a host drives it: one transaction at a time, AW and W
  * presented with random skew, B and R taken after random delays. A per-cycle hook watches the outputs
  * (clearCounters, irq, acceptRays, running) and plays the platform's events. Expected values come from the
  * register map (RegMap, the host's contract) and this file's own bookkeeping, not from the RTL.
  */
class RegFileSpec extends AnyFunSuite with ChiselScalatestTester {
  private val counterNames = RtAccelTop.counterNames
  private val addrBits = RegMap.addrBits(counterNames)
  private val primBaseBits = 40 // wider than a word, so that PRIM_BASE_HI reaches the output too
  private val maxLevelReset = 9
  private val levelBits = 4
  private val maxStepsReset = 0x12345L // the generator's MAX_STEPS (a scene's bound)
  private val stepBits = 20 // narrower than the word, so that a write's high bits are seen to drop
  // configuration words of our own choosing: whatever the generator passes must read back unchanged
  private val constants: Seq[(RegMap.Reg, BigInt)] = Seq(Config0 -> BigInt(0x00200804L), Config1 -> BigInt(0x1f400040L),
    NodeCache -> BigInt(0x0003012dL), PrimCache -> BigInt(0x00000000L), Formats -> BigInt(0x00056700L), Formats2 -> BigInt(0x00000008L),
    Pipeline -> BigInt(0x22150d06L), Intervals -> BigInt(0x00000042L))
  private def regFile = new RegFile(constants, counterNames, primBaseBits, maxLevelReset, levelBits, maxStepsReset, stepBits)
  private val Magic = 0x52544143L // 'RTAC', docs
  private def lsb(r: Reg, f: String) = r.fields.find(_.name == f).get.lsb
  private val Start = 1L << lsb(Control, "START"); private val SoftReset = 1L << lsb(Control, "SOFT_RESET")
  private val ClearCounters = 1L << lsb(Control, "CLEAR_COUNTERS")
  private def st(f: String) = 1L << lsb(Status, f)
  private val IrqDone = 1L << lsb(IrqStatus, "DONE"); private val IrqError = 1L << lsb(IrqStatus, "ERROR")
  private val regs = RegMap.all(counterNames)
  private val mapped: Set[Int] = regs.map(_.offset).toSet

  /** A host on the AXI4-Lite port; `tick` runs once per cycle, after the host has driven the port and before
    * the clock edge (it may poke the platform's events and peek outputs). `firing` is the write whose AW/W
    * handshake happens in the current cycle.
    */
  private final class Host(dut: RegFile, seed: Long) {
    val rnd = new Random(seed)
    private val l = dut.io.lite
    var tick: () => Unit = () => ()
    var firing: Option[(Int, Long, Int)] = None
    var cycle = 0L
    def step(): Unit = { tick(); dut.clock.step(); cycle += 1; firing = None }
    private def delay() = if (rnd.nextInt(3) == 0) rnd.nextInt(5) else 0
    def idle(): Unit = {
      l.aw.valid.poke(false.B); l.w.valid.poke(false.B); l.b.ready.poke(false.B); l.ar.valid.poke(false.B)
      l.r.ready.poke(false.B); l.w.bits.strb.poke(15.U)
      val e = dut.io.events
      for (b <- Seq(e.busy, e.rayIn, e.hitOut, e.readError, e.overflow, e.stepLimit)) b.poke(false.B)
    }
    private def fail(what: String) = throw new AssertionError(s"$what (host seed $seed, cycle $cycle)")

    /** One write; returns the B response. */
    def write(offset: Int, data: Long, strb: Int = 0xf): Int = {
      val awAt = delay(); val wAt = delay()
      l.aw.bits.addr.poke(offset.U); l.w.bits.data.poke((data & 0xffffffffL).U); l.w.bits.strb.poke(strb.U)
      var c = 0; var taken = false
      while (!taken) {
        l.aw.valid.poke((c >= awAt).B); l.w.valid.poke((c >= wAt).B)
        val awF = c >= awAt && l.aw.ready.peek().litToBoolean
        val wF = c >= wAt && l.w.ready.peek().litToBoolean
        if (awF != wF) fail(f"write 0x$offset%03x: AW and W must be taken together")
        if (l.b.valid.peek().litToBoolean) fail(f"write 0x$offset%03x: B valid before the write was taken")
        if (awF) firing = Some((offset, data & 0xffffffffL, strb))
        step(); c += 1; taken = awF
        if (c > 50) fail(f"write 0x$offset%03x not taken")
      }
      l.aw.valid.poke(false.B); l.w.valid.poke(false.B)
      val bAt = delay(); c = 0
      var resp = -1
      while (resp < 0) {
        l.b.ready.poke((c >= bAt).B)
        val v = l.b.valid.peek().litToBoolean
        if (c >= bAt && v) resp = l.b.bits.resp.peek().litValue.toInt
        else if (c > 0 && !v) fail(f"write 0x$offset%03x: B dropped before it was taken")
        step(); c += 1
        if (c > 50) fail(f"write 0x$offset%03x: no B")
      }
      l.b.ready.poke(false.B)
      resp
    }

    /** One read; returns (data, response). */
    def read(offset: Int): (Long, Int) = {
      val arAt = delay()
      l.ar.bits.addr.poke(offset.U)
      var c = 0; var taken = false
      while (!taken) {
        l.ar.valid.poke((c >= arAt).B)
        taken = c >= arAt && l.ar.ready.peek().litToBoolean
        step(); c += 1
        if (c > 50) fail(f"read 0x$offset%03x not taken")
      }
      l.ar.valid.poke(false.B)
      val rAt = delay(); c = 0
      var out: Option[(Long, Int)] = None
      while (out.isEmpty) {
        l.r.ready.poke((c >= rAt).B)
        val v = l.r.valid.peek().litToBoolean
        if (c >= rAt && v) out = Some((l.r.bits.data.peek().litValue.toLong, l.r.bits.resp.peek().litValue.toInt))
        else if (c > 0 && !v) fail(f"read 0x$offset%03x: R dropped before it was taken")
        step(); c += 1
        if (c > 50) fail(f"read 0x$offset%03x: no R")
      }
      l.r.ready.poke(false.B)
      out.get
    }
    def readOk(r: Reg): Long = {
      val (d, resp) = read(r.offset)
      if (resp != AxiLite.Okay) fail(s"read ${r.name}: response $resp")
      d
    }
    def writeOk(r: Reg, data: Long): Unit = {
      val resp = write(r.offset, data)
      if (resp != AxiLite.Okay) fail(s"write ${r.name}: response $resp")
    }
    /** Every register of the map, read in map order (so each counter's LO comes just before its HI). */
    def dump(): Seq[(String, Long)] = regs.map(r => r.name -> readOk(r))
  }

  // One Verilator build serves every test (the same circuit, cached in one folder): treadle took 38 s for the suite
  private val sim = rtaccel.TestSim.cached("RegFileSpec")
  private def withHost(seed: Long)(body: (RegFile, Host) => Unit): Unit =
    test(regFile).withAnnotations(sim) { dut =>
      val h = new Host(dut, seed)
      h.idle()
      body(dut, h)
    }

  private def pokeCounters(dut: RegFile, values: Seq[BigInt]): Unit =
    for ((v, i) <- values.zipWithIndex) dut.io.counters(i).poke(v.U(64.W))

  private def distinctCounters(rnd: Random): Seq[BigInt] =
    counterNames.indices.map(i => (BigInt(i + 1) << 40) | (BigInt(rnd.nextInt() & 0xffff) << 32) | BigInt(rnd.nextInt() & 0x7fffffff))

  /** Reset values of every register; a register of the map without an expectation here fails the test. */
  private def resetExpectation(counters: Seq[BigInt]): Map[String, Long] = {
    val fixed = Map[String, Long](
      "ID" -> Magic, "VERSION" -> ((VersionMajor.toLong << 16) | VersionMinor), "CONTROL" -> 0, "STATUS" -> 0,
      "IRQ_ENABLE" -> 0, "IRQ_STATUS" -> 0, "MAX_LEVEL" -> maxLevelReset, "RAY_COUNT" -> 0, "PRIM_BASE_LO" -> 0,
      "PRIM_BASE_HI" -> 0, "MAX_STEPS" -> maxStepsReset, "HITS_DONE" -> 0, "RAYS_IN" -> 0) ++ constants.map { case (r, v) => r.name -> v.toLong }
    val cnt = counterNames.zipWithIndex.flatMap { case (n, i) =>
      Seq(s"CNT_${n.toUpperCase}_LO" -> (counters(i) & 0xffffffffL).toLong, s"CNT_${n.toUpperCase}_HI" -> (counters(i) >> 32).toLong)
    }
    fixed ++ cnt
  }

  test("the register map is what the host expects: ID magic, word-aligned distinct offsets, counters after 0x100") {
    assert(RegMap.Magic == Magic)
    assert(mapped.size == regs.length, "two registers share an offset")
    assert(regs.forall(_.offset % 4 == 0))
    assert(regs.count(_.name.startsWith("CNT_")) == 2 * counterNames.length)
    assert(regs.filter(_.name.startsWith("CNT_")).forall(_.offset >= 0x100))
  }

  test("every register of RegMap.all reads its reset value (or its input) at its offset with OKAY") {
    withHost(1L) { (dut, h) =>
      val counters = distinctCounters(h.rnd)
      pokeCounters(dut, counters)
      val want = resetExpectation(counters)
      for (r <- regs) assert(want.contains(r.name), s"no expectation for register ${r.name}: extend this test")
      for ((name, got) <- h.dump()) assert(got == want(name), f"$name: read 0x$got%08x, want 0x${want(name)}%08x")
      dut.io.maxLevel.expect(maxLevelReset.U); dut.io.primBase.expect(0.U)
      dut.io.acceptRays.expect(false.B); dut.io.running.expect(false.B); dut.io.irq.expect(false.B)
    }
  }

  test("unmapped offsets (holes, unaligned, beyond the counters) answer DECERR to reads (data 0) and writes, changing nothing") {
    val seed = 2L
    withHost(seed) { (dut, h) =>
      val counters = distinctCounters(h.rnd)
      pokeCounters(dut, counters)
      val directed = Seq(0x001, 0x002, 0x003, 0x01e, 0x035, 0x04e, 0x054, 0x0fc, 0x101, 0x106,
        RegMap.CounterBase + 8 * counterNames.length, (1 << addrBits) - 4, (1 << addrBits) - 1)
      val random = Iterator.continually(h.rnd.nextInt(1 << addrBits)).filterNot(mapped).take(150).toSeq
      val offsets = directed ++ random
      assert(offsets.forall(o => !mapped(o)))
      val before = h.dump()
      for (o <- offsets) {
        val (d, resp) = h.read(o)
        assert(resp == AxiLite.DecErr && d == 0, f"read 0x$o%03x: data 0x$d%x response $resp, want DECERR (seed $seed)")
        val w = h.write(o, h.rnd.nextInt().toLong, if (h.rnd.nextBoolean()) 0xf else h.rnd.nextInt(15))
        assert(w == AxiLite.DecErr, f"write 0x$o%03x: response $w, want DECERR (seed $seed)")
      }
      assert(h.dump() == before, "an unmapped write changed a register")
      dut.io.acceptRays.expect(false.B)
    }
  }

  test("writes to read-only registers (full or partial) answer SLVERR and change nothing") {
    val seed = 3L
    withHost(seed) { (dut, h) =>
      val counters = distinctCounters(h.rnd)
      pokeCounters(dut, counters)
      // make the status non-trivial first: a finished empty batch (DONE) and values in the RW registers
      h.writeOk(RayCount, 0); h.writeOk(Control, Start); h.writeOk(PrimBaseLo, 0x1234)
      var clears = 0
      h.tick = () => if (dut.io.clearCounters.peek().litToBoolean) clears += 1
      val before = h.dump()
      val ro = regs.filter(_.access == RO)
      assert(ro.length == 13 + 2 * counterNames.length)
      for (r <- ro; data <- Seq(0xffffffffL, 0L, h.rnd.nextInt().toLong); strb <- Seq(0xf, 1 + h.rnd.nextInt(14))) {
        val resp = h.write(r.offset, data, strb)
        assert(resp == AxiLite.SlvErr, f"write 0x$data%08x strb $strb to ${r.name}: response $resp, want SLVERR (seed $seed)")
      }
      assert(h.dump() == before, "a write to a read-only register changed something")
      assert(clears == 0)
    }
  }

  test("partial writes (WSTRB != 0xF) to writable registers answer SLVERR and change nothing, pulses included") {
    val seed = 4L
    withHost(seed) { (dut, h) =>
      pokeCounters(dut, distinctCounters(h.rnd))
      // pending interrupts in both bits, so that a partial W1C write would show
      h.writeOk(RayCount, 0); h.writeOk(Control, Start)
      dut.io.events.hitOut.poke(true.B); dut.io.events.overflow.poke(true.B); h.step(); h.idle()
      h.writeOk(RayCount, 5); h.writeOk(IrqEnable, 1); h.writeOk(MaxLevel, 3)
      assert(h.readOk(IrqStatus) == (IrqDone | IrqError))
      var clears = 0; var accepted = 0
      h.tick = () => {
        if (dut.io.clearCounters.peek().litToBoolean) clears += 1
        if (dut.io.acceptRays.peek().litToBoolean) accepted += 1
      }
      val before = h.dump()
      val writable = regs.filter(_.access != RO)
      assert(writable.map(_.name).toSet == Set("CONTROL", "IRQ_ENABLE", "IRQ_STATUS", "MAX_LEVEL", "RAY_COUNT", "PRIM_BASE_LO", "PRIM_BASE_HI", "MAX_STEPS"))
      for (r <- writable; strb <- 0 until 15) {
        val resp = h.write(r.offset, 0xffffffffL, strb)
        assert(resp == AxiLite.SlvErr, s"partial write (strb $strb) to ${r.name}: response $resp, want SLVERR (seed $seed)")
      }
      assert(h.dump() == before, "a partial write changed a register")
      assert(clears == 0 && accepted == 0, s"a partial CONTROL write acted: $clears clears, $accepted cycles accepting rays")
    }
  }

  test("RW registers read back what was written; MAX_LEVEL, MAX_STEPS, PRIM_BASE and RAY_COUNT - 1 (TLAST's index) reach their outputs") {
    val seed = 5L
    withHost(seed) { (dut, h) =>
      val width = Map("IRQ_ENABLE" -> 2, "MAX_LEVEL" -> levelBits, "RAY_COUNT" -> 32, "PRIM_BASE_LO" -> 32, "PRIM_BASE_HI" -> 32,
        "MAX_STEPS" -> stepBits)
      val rw = regs.filter(_.access == RW)
      assert(rw.map(_.name).toSet == width.keySet)
      val shadow = scala.collection.mutable.Map[String, Long]("IRQ_ENABLE" -> 0, "MAX_LEVEL" -> maxLevelReset, "RAY_COUNT" -> 0,
        "PRIM_BASE_LO" -> 0, "PRIM_BASE_HI" -> 0, "MAX_STEPS" -> maxStepsReset)
      var rayCountWritten = false // TLAST's index is RAY_COUNT - 1 from the first write of RAY_COUNT on (0 before: no batch)
      for (i <- 0 until 120) {
        val r = rw(h.rnd.nextInt(rw.length))
        if (r.name == "RAY_COUNT") rayCountWritten = true
        val data = h.rnd.nextInt(4) match { case 0 => 0xffffffffL; case 1 => 0L; case _ => h.rnd.nextInt().toLong & 0xffffffffL }
        h.writeOk(r, data)
        shadow(r.name) = data & ((1L << width(r.name)) - 1)
        val q = rw(h.rnd.nextInt(rw.length))
        assert(h.readOk(q) == shadow(q.name), s"op $i: ${q.name} reads ${h.readOk(q)}, want ${shadow(q.name)} (seed $seed)")
        dut.io.maxLevel.expect(shadow("MAX_LEVEL").U, s"op $i (seed $seed)")
        dut.io.maxSteps.expect(shadow("MAX_STEPS").U, s"op $i (seed $seed)")
        val base = (BigInt(shadow("PRIM_BASE_HI")) << 32) | BigInt(shadow("PRIM_BASE_LO"))
        assert(dut.io.primBase.peek().litValue == (base & ((BigInt(1) << primBaseBits) - 1)), s"op $i: primBase (seed $seed)")
        // the hit that ends a batch of RAY_COUNT rays has index RAY_COUNT - 1 (mod 2^32: a batch of 0 has none)
        if (rayCountWritten)
          assert(dut.io.lastHitIndex.peek().litValue == ((shadow("RAY_COUNT") - 1) & 0xffffffffL), s"op $i: lastHitIndex (seed $seed)")
        dut.io.irq.expect(false.B) // nothing pending
      }
      for (r <- rw) assert(h.readOk(r) == shadow(r.name), s"${r.name} (seed $seed)")
      assert(h.readOk(Control) == 0)
    }
  }

  test("CONTROL: CLEAR_COUNTERS and SOFT_RESET pulse clearCounters for exactly one cycle; START starts; 0 does nothing") {
    withHost(6L) { (dut, h) =>
      var pulses = Vector.empty[Long]
      h.tick = () => if (dut.io.clearCounters.peek().litToBoolean) pulses :+= h.cycle
      h.writeOk(Control, 0)
      assert(pulses.isEmpty && !dut.io.running.peek().litToBoolean)
      for (cmd <- Seq(ClearCounters, SoftReset, ClearCounters | SoftReset)) {
        pulses = Vector.empty
        var fired = -1L
        h.tick = () => {
          if (dut.io.clearCounters.peek().litToBoolean) pulses :+= h.cycle
          if (h.firing.nonEmpty) fired = h.cycle
        }
        h.writeOk(Control, cmd)
        for (_ <- 0 until 5) h.step()
        assert(pulses == Vector(fired), s"CONTROL=$cmd: clearCounters in cycles $pulses, want only the write's cycle $fired")
      }
      h.tick = () => ()
      h.writeOk(RayCount, 3)
      h.writeOk(Control, Start)
      dut.io.running.expect(true.B); dut.io.acceptRays.expect(true.B)
      val s = h.readOk(Status)
      assert((s & st("RUNNING")) != 0 && (s & st("BUSY")) != 0 && (s & st("DONE")) == 0, s"STATUS $s after START")
      assert(h.readOk(Control) == 0, "CONTROL reads 0")
      // SOFT_RESET ends the batch
      h.writeOk(Control, SoftReset)
      dut.io.running.expect(false.B); dut.io.acceptRays.expect(false.B)
      assert(h.readOk(Status) == 0)
    }
  }

  test("IRQ_STATUS is write-1-to-clear and irq = IRQ_STATUS & IRQ_ENABLE") {
    withHost(7L) { (dut, h) =>
      def setBoth(): Unit = {
        h.writeOk(RayCount, 0); h.writeOk(Control, Start) // DONE at once
        dut.io.events.hitOut.poke(true.B); dut.io.events.readError.poke(true.B); h.step(); h.idle() // ERROR
        assert(h.readOk(IrqStatus) == (IrqDone | IrqError))
      }
      setBoth()
      for (en <- 0 until 4) {
        h.writeOk(IrqEnable, en)
        assert(dut.io.irq.peek().litToBoolean == (en != 0), s"enable $en with both pending")
      }
      h.writeOk(IrqStatus, 0) // writing 0 clears nothing
      assert(h.readOk(IrqStatus) == 3)
      h.writeOk(IrqStatus, 0xfffffffcL) // bits outside the register clear nothing
      assert(h.readOk(IrqStatus) == 3)
      h.writeOk(IrqStatus, IrqDone)
      assert(h.readOk(IrqStatus) == IrqError)
      for (en <- 0 until 4) { h.writeOk(IrqEnable, en); assert(dut.io.irq.peek().litToBoolean == ((en & IrqError) != 0), s"enable $en, ERROR pending") }
      h.writeOk(IrqStatus, IrqError)
      assert(h.readOk(IrqStatus) == 0)
      for (en <- 0 until 4) { h.writeOk(IrqEnable, en); dut.io.irq.expect(false.B, s"enable $en, nothing pending") }
      setBoth()
      h.writeOk(IrqEnable, 3)
      h.writeOk(IrqStatus, IrqDone | IrqError)
      assert(h.readOk(IrqStatus) == 0); dut.io.irq.expect(false.B)
      // a read error without a hit leaving is no event
      h.writeOk(Control, SoftReset)
      dut.io.events.readError.poke(true.B); dut.io.events.overflow.poke(true.B); h.step(); h.step(); h.idle()
      assert(h.readOk(IrqStatus) == 0 && (h.readOk(Status) & (st("READ_ERROR") | st("OVERFLOW"))) == 0)
    }
  }

  /** One batch of `n` rays: the platform's events come at random, rays only while acceptRays; checks per
    * cycle that acceptRays = RUNNING and fewer than RAY_COUNT rays in, and that the DONE interrupt rises in
    * the cycle after the n-th hit and not before.
    */
  private def batch(dut: RegFile, h: Host, n: Int, seed: Long): Unit = {
    val rnd = new Random(seed)
    var raysIn = 0; var hits = 0; var started = false; var lastHitCycle = -1L
    h.writeOk(IrqEnable, IrqDone)
    h.writeOk(IrqStatus, IrqDone | IrqError)
    h.writeOk(RayCount, n)
    dut.io.acceptRays.expect(false.B, "no rays before START")
    h.tick = () => {
      val accept = dut.io.acceptRays.peek().litToBoolean
      val wantAccept = started && raysIn < n
      assert(accept == wantAccept, s"cycle ${h.cycle}: acceptRays $accept with $raysIn of $n rays in (seed $seed)")
      assert(dut.io.running.peek().litToBoolean == (started && lastHitCycle < 0), s"cycle ${h.cycle}: running (seed $seed)")
      assert(dut.io.irq.peek().litToBoolean == (lastHitCycle >= 0), s"cycle ${h.cycle}: DONE irq with $hits of $n hits out (seed $seed)")
      val rayIn = accept && rnd.nextInt(3) != 0
      val hitOut = hits < raysIn && rnd.nextInt(3) == 0
      dut.io.events.rayIn.poke(rayIn.B); dut.io.events.hitOut.poke(hitOut.B)
      dut.io.events.busy.poke((raysIn > hits).B)
      if (rayIn) raysIn += 1
      if (hitOut) { hits += 1; if (hits == n) lastHitCycle = h.cycle }
      if (h.firing.exists(w => w._1 == Control.offset && (w._2 & Start) != 0)) started = true
    }
    h.writeOk(Control, Start)
    assert(started)
    var polls = 0
    while ((h.readOk(Status) & st("DONE")) == 0) { polls += 1; assert(polls < 10 * n + 20, s"batch of $n never done (seed $seed)") }
    assert(hits == n && raysIn == n, s"$raysIn rays in, $hits hits out, want $n (seed $seed)")
    for (_ <- 0 until 4) h.step() // no more rays are accepted (checked by the hook)
    h.tick = () => ()
    h.idle()
    val s = h.readOk(Status)
    assert((s & st("DONE")) != 0 && (s & (st("RUNNING") | st("BUSY"))) == 0, s"STATUS $s after the batch (seed $seed)")
    assert(h.readOk(RaysIn) == n && h.readOk(HitsDone) == n)
    assert(h.readOk(IrqStatus) == IrqDone)
    dut.io.irq.expect(true.B)
  }

  test("batches: rays accepted only between START and RAY_COUNT rays in; DONE and IRQ DONE when RAY_COUNT hits are out") {
    val seed = 8L
    withHost(seed) { (dut, h) =>
      val sizes = Seq(1, 2, 7, 1, 23) ++ Seq.fill(4)(1 + h.rnd.nextInt(40))
      for ((n, i) <- sizes.zipWithIndex) {
        batch(dut, h, n, seed * 100 + i)
        // the next START clears DONE and the batch counts
        if (i == 0) { h.writeOk(RayCount, 4); h.writeOk(Control, Start); assert((h.readOk(Status) & st("DONE")) == 0 && h.readOk(RaysIn) == 0) ; h.writeOk(Control, SoftReset) }
      }
      info(s"${sizes.length} batches of ${sizes.mkString(",")} rays")
    }
  }

  test("RAY_COUNT = 0: START finishes the batch at once (DONE, IRQ DONE, no ray accepted)") {
    withHost(9L) { (dut, h) =>
      var accepted = 0
      h.tick = () => if (dut.io.acceptRays.peek().litToBoolean || dut.io.running.peek().litToBoolean) accepted += 1
      h.writeOk(IrqEnable, IrqDone)
      h.writeOk(RayCount, 0)
      dut.io.irq.expect(false.B)
      h.writeOk(Control, Start)
      dut.io.irq.expect(true.B)
      val s = h.readOk(Status)
      assert(s == st("DONE"), s"STATUS $s, want DONE only")
      assert(h.readOk(IrqStatus) == IrqDone && accepted == 0)
    }
  }

  test("READ_ERROR, OVERFLOW and STEP_LIMIT are sticky, set only by a flagged hit leaving, raise IRQ ERROR; SOFT_RESET clears them") {
    withHost(10L) { (dut, h) =>
      val ev = dut.io.events
      def pulse(hit: Boolean, re: Boolean, ov: Boolean, sl: Boolean = false): Unit = {
        ev.hitOut.poke(hit.B); ev.readError.poke(re.B); ev.overflow.poke(ov.B); ev.stepLimit.poke(sl.B); h.step(); h.idle()
      }
      def flags() = h.readOk(Status) & (st("READ_ERROR") | st("OVERFLOW") | st("STEP_LIMIT"))
      h.writeOk(IrqEnable, IrqError)
      pulse(hit = false, re = true, ov = true)
      assert(flags() == 0 && h.readOk(IrqStatus) == 0)
      pulse(hit = true, re = true, ov = false)
      assert(flags() == st("READ_ERROR") && h.readOk(IrqStatus) == IrqError); dut.io.irq.expect(true.B)
      for (_ <- 0 until 5) pulse(hit = true, re = false, ov = false) // clean hits keep it
      assert(flags() == st("READ_ERROR"))
      h.writeOk(IrqStatus, IrqError); dut.io.irq.expect(false.B)
      assert(flags() == st("READ_ERROR"), "clearing the interrupt does not clear the sticky status")
      pulse(hit = true, re = false, ov = true)
      assert(flags() == (st("READ_ERROR") | st("OVERFLOW")) && h.readOk(IrqStatus) == IrqError)
      h.writeOk(Control, SoftReset)
      assert(flags() == 0 && h.readOk(IrqStatus) == 0); dut.io.irq.expect(false.B)
      pulse(hit = true, re = false, ov = true)
      assert(flags() == st("OVERFLOW"))
      // the step limit alike: only with a hit leaving, sticky, IRQ ERROR, cleared by SOFT_RESET alone
      h.writeOk(IrqStatus, IrqError)
      pulse(hit = false, re = false, ov = false, sl = true)
      assert(flags() == st("OVERFLOW") && h.readOk(IrqStatus) == 0)
      pulse(hit = true, re = false, ov = false, sl = true)
      assert(flags() == (st("OVERFLOW") | st("STEP_LIMIT")) && h.readOk(IrqStatus) == IrqError); dut.io.irq.expect(true.B)
      pulse(hit = true, re = false, ov = false)
      h.writeOk(IrqStatus, IrqError)
      assert(flags() == (st("OVERFLOW") | st("STEP_LIMIT")), "clearing the interrupt does not clear the sticky status")
      h.writeOk(Control, SoftReset)
      assert(flags() == 0 && h.readOk(IrqStatus) == 0)
    }
  }

  test("64-bit counters: reading LO snapshots the counter, so HI matches LO even when the counter moves in between") {
    val seed = 11L
    withHost(seed) { (dut, h) =>
      val rnd = h.rnd
      var values = distinctCounters(rnd)
      pokeCounters(dut, values)
      val lo = (v: BigInt) => (v & 0xffffffffL).toLong; val hi = (v: BigInt) => (v >> 32).toLong
      for (round <- 0 until 3; i <- counterNames.indices) {
        val base = RegMap.CounterBase + 8 * i
        // carry cases: the counter crosses a 2^32 boundary between the LO and HI reads
        val v1 = if (round == 0) (BigInt(rnd.nextInt(1000) + 1) << 32) | 0xffffffffL else values(i)
        val v2 = if (round == 0) v1 + 1 else v1 + (BigInt(rnd.nextInt(1 << 20) + 1) << 32) + rnd.nextInt(1000)
        values = values.updated(i, v1); pokeCounters(dut, values)
        val (l1, r1) = h.read(base)
        values = values.updated(i, v2); pokeCounters(dut, values)
        val (h1, r2) = h.read(base + 4)
        assert(r1 == AxiLite.Okay && r2 == AxiLite.Okay)
        assert(l1 == lo(v1) && h1 == hi(v1), f"counter $i round $round: read 0x$h1%08x_$l1%08x, want 0x${hi(v1)}%08x_${lo(v1)}%08x (snapshot), counter now $v2 (seed $seed)")
        // HI again: still the snapshot; a fresh LO/HI pair sees the new value
        assert(h.read(base + 4)._1 == hi(v1))
        assert(h.read(base)._1 == lo(v2) && h.read(base + 4)._1 == hi(v2), s"counter $i round $round: fresh pair (seed $seed)")
        // another counter's HI without its LO is its live value
        val j = (i + 1 + rnd.nextInt(counterNames.length - 1)) % counterNames.length
        assert(h.read(RegMap.CounterBase + 8 * j + 4)._1 == hi(values(j)), s"counter $j HI after counter $i LO (seed $seed)")
      }
    }
  }

  test("one write at a time: a second write waits until the first B is taken; B and R stay valid until taken") {
    withHost(12L) { (dut, h) =>
      val l = dut.io.lite
      l.aw.valid.poke(true.B); l.aw.bits.addr.poke(RayCount.offset.U); l.w.valid.poke(true.B); l.w.bits.data.poke(11.U)
      l.aw.ready.expect(true.B); h.step()
      l.w.bits.data.poke(22.U) // a second write presented at once, B not taken
      for (_ <- 0 until 6) { l.b.valid.expect(true.B); l.aw.ready.expect(false.B); l.w.ready.expect(false.B); h.step() }
      l.b.bits.resp.expect(AxiLite.Okay.U)
      l.b.ready.poke(true.B); l.aw.ready.expect(false.B); h.step()
      l.b.ready.poke(false.B); l.aw.ready.expect(true.B); h.step() // the second write is taken now
      l.aw.valid.poke(false.B); l.w.valid.poke(false.B)
      l.b.valid.expect(true.B); l.b.ready.poke(true.B); h.step(); l.b.ready.poke(false.B)
      l.ar.valid.poke(true.B); l.ar.bits.addr.poke(RayCount.offset.U); l.ar.ready.expect(true.B); h.step()
      l.ar.valid.poke(false.B)
      for (_ <- 0 until 6) { l.r.valid.expect(true.B); l.r.bits.data.expect(22.U); l.ar.ready.expect(false.B); h.step() }
      l.r.ready.poke(true.B); h.step(); l.r.ready.poke(false.B); l.r.valid.expect(false.B)
    }
  }
}
