package rtaccel.top

/** The host's view of the board top: the AXI4-Lite register map, defined once here. The RTL (RegFile), the
  * simulation host driver (sim.HostDriver), the generated C header and Python module (RegHeaders) and
  * docs/registers.md all follow this table. 32-bit registers at byte offsets; 64-bit counters are two words,
  * LO then HI: reading LO takes a snapshot of the whole counter, so the HI read that follows matches it.
  */
object RegMap {
  sealed abstract class Access(val code: String)
  /** read only */
  case object RO extends Access("RO")
  /** read/write */
  case object RW extends Access("RW")
  /** write-only pulses: each written 1 bit acts once; reads 0 */
  case object WP extends Access("WP")
  /** read, write 1 to clear */
  case object W1C extends Access("W1C")

  final case class Field(name: String, lsb: Int, width: Int, doc: String) {
    require(lsb >= 0 && width >= 1 && lsb + width <= 32, s"field $name must lie in 32 bits")
    def mask: Long = ((1L << width) - 1) << lsb
  }
  final case class Reg(name: String, offset: Int, access: Access, doc: String, fields: Seq[Field] = Nil) {
    require(offset % 4 == 0, s"register $name must be word aligned")
  }

  /** Bumped whenever the map changes incompatibly (major) or grows (minor). */
  val VersionMajor = 2
  val VersionMinor = 10
  val Magic: Long = 0x52544143L // "RTAC"

  val Id = Reg("ID", 0x000, RO, "magic 0x52544143 ('RTAC')")
  val Version = Reg("VERSION", 0x004, RO, "register map version", Seq(Field("MINOR", 0, 16, ""), Field("MAJOR", 16, 16, "")))
  val Config0 = Reg("CONFIG0", 0x008, RO, "generator parameters", Seq(
    Field("M", 0, 8, "MBVH width"), Field("MAX_LEAF_PRIMS", 8, 8, "primitives a leaf reference can count"),
    Field("TUS", 16, 16, "traversal units")))
  val Config1 = Reg("CONFIG1", 0x00C, RO, "traversal stack and reference format", Seq(
    Field("STACK_DEPTH", 0, 16, "entries per TU stack"), Field("LEVEL_BITS", 16, 4, "level field of a node reference"),
    Field("COUNT_BITS", 20, 4, "leaf count field"), Field("NODE_ID_BITS", 24, 8, "node id field")))
  private val cacheFields = Seq(
    Field("LOG2_ENTRIES", 0, 5, "log2 of the entries (valid when PRESENT)"), Field("PRESENT", 5, 1, "the cache is built"),
    Field("WAYS", 8, 8, "ways"), Field("POLICY", 16, 4, "0 dm, 1 lru, 2 plru, 3 lrp, 4 bf, 5 hybrid"))
  val NodeCache = Reg("NODE_CACHE", 0x010, RO, "node cache geometry", cacheFields ++ Seq(
    Field("SHARED", 6, 1, "1 = NODE_BANKS > 0: one node cache of LOG2_ENTRIES serves every IU, in 2^BANKS_LOG2 banks (0: one such cache per IU)"),
    Field("BANKS_LOG2", 20, 3, "log2 of the node cache's banks (valid when SHARED)")))
  val PrimCache = Reg("PRIM_CACHE", 0x014, RO, "primitive cache geometry (the fields of NODE_CACHE but SHARED and BANKS_LOG2; one per IU)", cacheFields)
  val Formats = Reg("FORMATS", 0x018, RO, "arithmetic and memory formats", Seq(
    Field("BOX_FP", 0, 4, "0 = fp32, 1 = the narrower format of BOX_EXP_BITS / BOX_MAN_BITS, rounded outward"), Field("TRI_FP", 4, 4, "0 = fp32, 1 = the wider format of FORMATS2.TRI_EXP_BITS / TRI_MAN_BITS (TRI_FORMAT)"), Field("NODE_BYTES_LOG2", 8, 4, "bytes per node slot"),
    Field("PRIM_BYTES_LOG2", 12, 4, "bytes per primitive slot"), Field("AXI_DATA_BYTES_LOG2", 16, 4, "memory bus beat"),
    Field("BOX_EXP_BITS", 20, 4, "exponent bits of the box test's format"), Field("BOX_MAN_BITS", 24, 5, "fraction bits of the box test's format"),
    Field("TRI_TEST", 29, 2, "0 = Möller–Trumbore, 1 = watertight (Woop et al. 2013)"),
    Field("PRIM_PACKED", 31, 1, "1 = PRIM_FORMAT=packed: 40 B records back to back, a leaf per row of ceil(MPPL x 40 / beat) beats (PRIM_BYTES_LOG2 does not apply)")))
  val Formats2 = Reg("FORMATS2", 0x01C, RO, "memory layouts and the triangle format (FORMATS has no room left)", Seq(
    Field("NODE_QUANT_BITS", 0, 5, "0 = full fp32 nodes, k = NODE_FORMAT=q<k> quantized nodes (docs/numerics.md)"),
    Field("TRI_EXP_BITS", 8, 4, "exponent bits of Möller–Trumbore's format (8 for fp32)"),
    Field("TRI_MAN_BITS", 12, 6, "fraction bits of Möller–Trumbore's format (23 for fp32)"),
    Field("RESP_ORDER", 18, 1, "0 = the MC answers in request order (the paper's), 1 = RESP_ORDER=path or tagged: node and primitive responses each in their own order"),
    Field("RESP_TAGGED", 19, 1, "1 = RESP_ORDER=tagged: each stream answers in any order, tagged by TU (hits under misses; RESP_ORDER is 1 too)"),
    Field("RAY_STORE", 20, 1, "1 = RAY_STORE=1: each IU keeps its TUs' rays in a ray store; requests carry the TU's index, not the ray"),
    Field("TAG_FORWARD", 21, 1, "1 = TAG_FORWARD=1: every cache path's tags take one lookup per cycle (0: one per two cycles)"),
    Field("MEM_RETRIES", 22, 2, "MEM_RETRIES: re-reads of a burst the memory answered with SLVERR before its rays are flagged (0: flagged at once)"),
    Field("IUS", 24, 8, "intersection units (IU clusters, each with its own MC and caches; CONFIG0.TUS / IUS TUs each)")))
  val Control = Reg("CONTROL", 0x020, WP, "commands", Seq(
    Field("START", 0, 1, "start a batch of RAY_COUNT rays"), Field("SOFT_RESET", 1, 1,
      "end the batch and clear status, interrupts and every counter (use only while STATUS.BUSY = 0)"),
    Field("CLEAR_COUNTERS", 2, 1, "zero every performance counter, MC and caches included")))
  val Status = Reg("STATUS", 0x024, RO, "state of the platform", Seq(
    Field("BUSY", 0, 1, "a batch is running or a TU holds a ray"), Field("DONE", 1, 1, "the last batch returned all its hits"),
    Field("READ_ERROR", 2, 1, "sticky: a ray hit a memory read error (its hit has prim -2)"),
    Field("OVERFLOW", 3, 1, "sticky: a ray overflowed its stack (its hit has prim -3)"),
    Field("RUNNING", 4, 1, "accepting rays of the current batch"),
    Field("STEP_LIMIT", 5, 1, "sticky: a ray needed more fetches than MAX_STEPS (its hit has prim -4)")))
  val IrqEnable = Reg("IRQ_ENABLE", 0x028, RW, "interrupt enables (irq = IRQ_STATUS & IRQ_ENABLE)", Seq(
    Field("DONE", 0, 1, "batch done"), Field("ERROR", 1, 1, "a read error, an overflow or a step limit")))
  val IrqStatus = Reg("IRQ_STATUS", 0x02C, W1C, "pending interrupts", IrqEnable.fields)
  val MaxLevel = Reg("MAX_LEVEL", 0x030, RW, "MAX_LEVEL of the level replacement policy",
    Seq(Field("VALUE", 0, 6, "the low hw.levelCodeBits bits are kept (4 on the paper's platform)")))
  val RayCount = Reg("RAY_COUNT", 0x034, RW, "rays in the next batch")
  val PrimBaseLo = Reg("PRIM_BASE_LO", 0x038, RW, "byte address of primitive slot 0, low word")
  val PrimBaseHi = Reg("PRIM_BASE_HI", 0x03C, RW, "byte address of primitive slot 0, high word")
  val HitsDone = Reg("HITS_DONE", 0x040, RO, "hits returned in the current batch")
  val RaysIn = Reg("RAYS_IN", 0x044, RO, "rays accepted in the current batch")

  val Pipeline = Reg("PIPELINE", 0x048, RO, "register stages of the datapaths (PIPELINE=, docs/timing.md)", Seq(
    Field("BUDGET", 0, 8, "LUT levels allowed between two registers (0 = PIPELINE=none: the fixed stages)"),
    Field("BOX_LATENCY", 8, 8, "cycles of the box test pipe (255: 255 or more)"),
    Field("TRI_LATENCY", 16, 8, "cycles of the triangle test pipe of TRI_TEST (255: 255 or more)"),
    Field("PREP_LATENCY", 24, 8, "cycles of the TC's ray preparation, 1/d (255: 255 or more)")))

  val Intervals = Reg("INTERVALS", 0x050, RO, "initiation intervals of the IU's pipes: cycles between two jobs at least, over which each pipe shares its operators (docs/platform.md)", Seq(
    Field("TRI_II", 0, 4, "TRI_II: the triangle pipe takes a primitive every TRI_II cycles (1: one per cycle)"),
    Field("BOX_II", 4, 4, "BOX_II: the box pipe takes a node every BOX_II cycles (1: one per cycle)")))

  val MaxSteps = Reg("MAX_STEPS", 0x04C, RW, "fetches (node or leaf) a ray may make; a ray that needs more ends flagged, " +
    "prim -4 (0 = no limit; reset: the generator's MAX_STEPS, by default a bound no ray of an uncorrupted image reaches). " +
    "Each ray reads it as it starts: write it between batches", Seq(Field("VALUE", 0, 32, "the low hw.stepBits bits are kept (32 by default)")))

  val CounterBase = 0x100
  /** Counter i is LO at CounterBase + 8 i, HI at + 4. */
  def counterRegs(names: Seq[String]): Seq[Reg] = names.zipWithIndex.flatMap { case (n, i) =>
    Seq(Reg(s"CNT_${n.toUpperCase}_LO", CounterBase + 8 * i, RO, s"counter $n, bits 31..0 (reading it snapshots bits 63..32)"),
      Reg(s"CNT_${n.toUpperCase}_HI", CounterBase + 8 * i + 4, RO, s"counter $n, bits 63..32 of the last LO snapshot"))
  }

  val fixed: Seq[Reg] = Seq(Id, Version, Config0, Config1, NodeCache, PrimCache, Formats, Formats2, Control, Status, IrqEnable,
    IrqStatus, MaxLevel, RayCount, PrimBaseLo, PrimBaseHi, HitsDone, RaysIn, Pipeline, MaxSteps, Intervals)
  def all(counterNames: Seq[String]): Seq[Reg] = fixed ++ counterRegs(counterNames)
  /** Address bits of the AXI4-Lite port: the map with every counter fits. */
  def addrBits(counterNames: Seq[String]): Int = {
    val end = CounterBase + 8 * counterNames.length
    math.max(12, 32 - Integer.numberOfLeadingZeros(end - 1))
  }
  def policyCode(policy: rtaccel.config.CachePolicy): Int = rtaccel.config.CachePolicy.code(policy)
}
