package rtaccel.model

/** Poisoned DRAM beats: the simulation's memory-error injection (MEM_ERROR_RATE), known to the model
  * so that the RTL's fault handling can be checked ray by ray. A beat is poisoned by its index in memory (byte
  * address / beat bytes), not by when it is read. With MEM_ERROR_MODE=sticky, like a bad DRAM cell, every read of it
  * fails, a cache's refetch too, so the affected rays do not depend on timing;
  * transient, only its first read fails (MemoryController re-reads it with MEM_RETRIES).
  * `threshold` of 65536: each beat is poisoned with probability threshold / 65536 (0 = no errors).
  * The hash is simple 32-bit integer arithmetic so that the DRAM model computes it identically in hardware
  * (sim.DramModel).
  */
final case class MemFaults(threshold: Int, seed: Int, beatBytes: Int, nodeStrideBytes: Int, primBaseBytes: Long,
                           primStrideBytes: Int) {
  require(threshold >= 0 && threshold <= MemFaults.One, s"error threshold must be 0..${MemFaults.One} (got $threshold)")
  def enabled: Boolean = threshold > 0
  def beatBad(index: Long): Boolean = enabled && MemFaults.hash16(index, seed) < threshold
  private def anyBad(byteAddr: Long, bytes: Int): Boolean =
    (byteAddr / beatBytes until (byteAddr + bytes + beatBytes - 1) / beatBytes).exists(beatBad)
  /** A node fetch reads the node's whole slot. */
  def nodeBad(id: Int): Boolean = enabled && anyBad(id.toLong * nodeStrideBytes, nodeStrideBytes)
  def primBad(slot: Int): Boolean = enabled && anyBad(primBaseBytes + slot.toLong * primStrideBytes, primStrideBytes)
  /** A primitive record of `bytes` at `offset` bytes from the primitive base is bad if any beat it spans is: a
    * 64 B slot (its own beats), or a packed 40 B record, which may share a beat with its neighbours.
    */
  def recordBad(offset: Long, bytes: Int): Boolean = enabled && anyBad(primBaseBytes + offset, bytes)
}

object MemFaults {
  val One: Int = 1 << 16
  /** MEM_ERROR_MODE: a poisoned beat fails its first read only (transient, like a soft error the read corrects) or
    * every read (sticky, like a bad cell). The model's rays see the sticky case; PlatformRun says what the transient
    * one leaves to check. */
  val Transient = "transient"
  val Sticky = "sticky"
  val modes: Seq[String] = Seq(Transient, Sticky)
  def sticky(mode: String): Boolean = mode.toLowerCase match {
    case Sticky => true
    case Transient => false
    case m => throw new rtaccel.io.InputError(s"MEM_ERROR_MODE=$m: MEM_ERROR_MODE takes ${modes.mkString(" or ")}")
  }
  val none: MemFaults = MemFaults(0, 1, 32, 128, 0, 64)
  /** MEM_ERROR_RATE in [0, 1] as a threshold of 65536. */
  def threshold(rate: Double): Int = {
    require(rate >= 0 && rate <= 1, s"MEM_ERROR_RATE must be in 0..1 (got $rate)")
    math.round(rate * One).toInt
  }
  val Mul1: Long = 0x9E3779B1L
  val Mul2: Long = 0x85EBCA77L
  /** 16 bits of a multiply-xorshift hash of the low 32 bits of `index`, mixed with the seed. */
  def hash16(index: Long, seed: Int): Int = {
    val x = (index ^ (seed & 0xffffffffL)) & 0xffffffffL
    val m1 = (x * Mul1) & 0xffffffffL
    val h1 = m1 ^ (m1 >>> 15)
    val m2 = (h1 * Mul2) & 0xffffffffL
    ((m2 ^ (m2 >>> 13)) & 0xffff).toInt
  }
}
