package rtaccel.cache.hw

import chisel3._
import chisel3.util._
import rtaccel.cache.policy.ReplacementPolicy

/** One way of a set: valid, tag and the level code (hw.levelCodeBits) of the line it holds. */
class WayEntry(tagBits: Int, levelBits: Int) extends Bundle {
  val valid = Bool()
  val tag = UInt(tagBits.W)
  val level = UInt(levelBits.W)
}

/** A set: its ways and the replacement state (one RAM word, read and written whole). */
class SetEntry(ways: Int, tagBits: Int, stateBits: Int, levelBits: Int) extends Bundle {
  val way = Vec(ways, new WayEntry(tagBits, levelBits))
  val state = UInt(stateBits.W) // zero-width (removed) for direct-mapped sets
}

/** What one access does to a set (combinational, from the set as read, `prev`): hit, fill (a miss that allocates;
  * a miss without fill is a bypass), the way hit or filled, the set to write back (`next`) and whether it is
  * written (`changes`: hit or fill; constant where the set's rule makes it so, to keep the RAM's output off the
  * write).
  */
final class Decision(val hit: Bool, val fill: Bool, val way: UInt, val next: SetEntry, val prev: SetEntry,
                     val changes: Bool)

/** The tag side of a set-associative array (`sets` x `ways`), a single-port synchronous RAM.
  * Lookup and fill follow the model's rules (docs/caches.md): a hit touches the way; a miss fills the lowest
  * empty way, else the policy's victim, which under the level policy (`lrp`) only if
  * LevelPolicy.allocate(victim level, incoming level, MAX_LEVEL); a refused fill changes nothing.
  * Protocol: `read(line)` in one cycle, the `Decision` on the next (the data stays valid while the same set
  * is read again each cycle), `write` when the decision is taken (one port: to the set being read).
  * `ruw`: what a read returns when it starts in the cycle its set is written. Undefined (the default) while a read
  * never overlaps a used write, as with one lookup per two cycles; WriteFirst for TAG_FORWARD=1, where the next
  * lookup's read starts in the cycle the decision before writes: the RAM's write-first port (a block RAM in
  * WRITE_FIRST mode) hands it the set just written, the read-after-write forwarding. (ReadFirst only in the formal
  * checks: the stale set, the mutant they must refute.)
  */
class TagArray(val sets: Int, val pol: ReplacementPolicy, lrp: Boolean, levelBits: Int, maxStateBits: Int,
               ruw: SyncReadMem.ReadUnderWrite = SyncReadMem.Undefined) {
  PolicyTables.check(pol, maxStateBits)
  val ways: Int = pol.ways
  val setBits: Int = log2Ceil(sets)
  val tagBits: Int = 32 - setBits
  /** A way keeps its line's level code only where the level policy reads it. */
  private val keptLevelBits = if (lrp) levelBits else 0
  /** A direct-mapped set without the level policy holds the line of the last lookup whatever it found: a hit
    * leaves {valid, tag} as it was, a miss fills it, so the set to write back is known without reading the RAM.
    */
  private val alwaysFills = ways == 1 && !lrp
  private def entryType = new SetEntry(ways, tagBits, pol.stateBits, keptLevelBits)
  private val mem = SyncReadMem(sets, entryType, ruw)
  private val addrBits = math.max(1, setBits)

  def setOf(line: UInt): UInt = if (setBits == 0) 0.U(1.W) else line(setBits - 1, 0)
  def tagOf(line: UInt): UInt = line(31, setBits)

  // the port: `read` names the set to read, `update` the write; set once each
  private val rSet = WireDefault(0.U(addrBits.W))
  private val wEn = WireDefault(false.B)
  private val wSet = WireDefault(0.U(addrBits.W))
  private val wData = WireDefault(emptyEntry)
  /** One lookup per two cycles never uses what is read in the cycle of a write (the decision it belongs to has
    * just left), so reads and writes share one read-write port: a block RAM's single port, which a synthesis that
    * keeps the memory's module apart (Yosys, hierarchical) can map to block RAM; a read port and a write port with
    * a clock each it can only map to LUT RAM. TAG_FORWARD=1 reads while the decision before writes: two ports.
    */
  private val clearingNow = WireDefault(false.B)
  /** Single port: a decision writes the set its lookup keeps reading while it waits (`read` names it again each
    * cycle), so the address is the read's, or the sweep's while clearing: it does not wait on the write enable.
    */
  private val rData: SetEntry =
    if (ruw == SyncReadMem.Undefined) {
      when(wEn && !clearingNow) { assert(rSet === wSet, "TagArray: a decision writes another set than the one read") }
      mem.readWrite(Mux(clearingNow, wSet, rSet), wData, true.B, wEn)
    } else if (sets == 1 && ruw == SyncReadMem.WriteFirst) {
      // one write-first set (a hybrid side array of one set: NODE_CACHE=32 or less) is a register: what a read
      // started in a cycle returns on the next is the set as written in that cycle, else as it was. firtool 1.62.1
      // stops on a write-first SyncReadMem of depth 1 ("operand #0 does not dominate this use").
      val set = Reg(entryType)
      when(wEn) { set := wData }
      set
    } else { when(wEn) { mem.write(wSet, wData) }; mem.read(rSet, true.B) }

  /** Starts a read of `line`'s set; the result is the entry one cycle later (undefined after a cycle that wrote). */
  def read(line: UInt): SetEntry = { rSet := setOf(line); rData }

  /** The empty set of reset, written by the init sweep. */
  def emptyEntry: SetEntry = {
    val e = Wire(entryType)
    e.way.foreach { w => w.valid := false.B; w.tag := 0.U; w.level := 0.U }
    e.state := pol.init.U(pol.stateBits.W)
    e
  }

  def decide(e: SetEntry, line: UInt, level: UInt, maxLevel: UInt): Decision = {
    val tag = tagOf(line)
    val hitVec = e.way.map(w => w.valid && w.tag === tag)
    val hit = hitVec.reduce(_ || _)
    val hitWay = OHToUInt(hitVec)
    val emptyVec = e.way.map(!_.valid)
    val hasEmpty = emptyVec.reduce(_ || _)
    val allocWay = Mux(hasEmpty, PriorityEncoder(emptyVec), PolicyTables.victim(pol, e.state))
    val victimLevel = if (ways == 1) e.way(0).level else VecInit(e.way.map(_.level))(allocWay)
    val levelOk = if (lrp) PolicyTables.allocate(victimLevel, level, maxLevel) else true.B
    val fill = !hit && (hasEmpty || levelOk)
    val way = Mux(hit, hitWay, allocWay)
    val next = WireDefault(e)
    for (w <- 0 until ways) when(alwaysFills.B || fill && (if (ways == 1) true.B else allocWay === w.U)) {
      next.way(w).valid := true.B
      next.way(w).tag := tag
      if (keptLevelBits > 0) next.way(w).level := level(keptLevelBits - 1, 0)
    }
    if (pol.stateBits > 0) next.state := PolicyTables.touch(pol, e.state, way)
    new Decision(hit, fill, if (ways == 1) 0.U else way, next, e, if (alwaysFills) true.B else hit || fill)
  }

  /** The one write port: while `clearing`, empties set `clearSet` (the reset sweep); otherwise writes the set
    * back whenever a lookup leaves (`fire`): the decision's set when `apply` and it hit or filled, else the set as
    * read (a refused fill, or the other array's line in a hybrid cache, changes nothing). The enable and the
    * address come from queue state alone: the set just read reaches only the write data, a shorter path from the
    * block RAM's output than through the enable to the address.
    */
  def update(line: UInt, d: Decision, fire: Bool, apply: Bool, clearing: Bool, clearSet: UInt): Unit = {
    val clearThis = clearing && clearSet < sets.U
    clearingNow := clearing
    wEn := clearThis || (!clearing && fire)
    wSet := Mux(clearThis, clearSet(addrBits - 1, 0), setOf(line))
    wData := Mux(clearThis, emptyEntry, Mux(apply && d.changes, d.next, d.prev))
  }
}
