package rtaccel.host

import rtaccel.config.PlatformParams
import rtaccel.io.InputError
import rtaccel.top.{RegMap, RtAccelTop}

/** The driver contract (docs/registers.md) as the simulation's host follows it, step by step, with the
  * register names of the generated header. A board bring-up follows the same steps.
  */
object HostSession {
  import RegMap._

  /** Steps 1-4: identify the board, check that the bitstream is the configuration the image was packed
    * for, write the run's registers, clear the counters and start the batch.
    */
  def configure(host: HostDriver, p: PlatformParams, primBaseBytes: Long, rayCount: Int): Unit = {
    val id = host.read(Id)
    if (id != Magic) throw new InputError(f"the board's ID register reads 0x$id%08x, not RTAC (0x$Magic%08x)")
    val major = host.field(Version, "MAJOR")
    if (major != VersionMajor) throw new InputError(s"register map version $major, this driver speaks $VersionMajor")
    for ((r, want) <- RtAccelTop.configWords(p)) {
      val got = host.read(r)
      if (BigInt(got) != want) throw new InputError(f"${r.name} reads 0x$got%08x but the image was packed for 0x$want%08x: " +
        "the bitstream is another configuration")
    }
    host.write(PrimBaseLo, primBaseBytes & 0xffffffffL)
    host.write(PrimBaseHi, primBaseBytes >>> 32)
    host.write(MaxLevel, p.nodeCache.maxLevel)
    host.write(MaxSteps, p.stepLimit)
    host.write(RayCount, rayCount)
    host.write(IrqEnable, bits(IrqEnable, "DONE"))
    host.write(Control, bits(Control, "CLEAR_COUNTERS"))
    host.write(Control, bits(Control, "START"))
  }

  final case class Finish(irqDone: Boolean, status: Map[String, Boolean], counters: Map[String, Long]) {
    def statusJson: ujson.Obj = ujson.Obj.from(status.map { case (k, v) => k.toLowerCase -> ujson.Bool(v) })
  }

  /** Steps 6-7 after the interrupt: read the status and every counter, acknowledge the interrupt. */
  def finish(host: HostDriver): Finish = {
    val irq = host.read(IrqStatus)
    val st = host.read(Status)
    val status = Status.fields.map(f => f.name -> (((st >> f.lsb) & 1) == 1)).toMap
    val counters = RtAccelTop.counterNames.zipWithIndex.map { case (n, i) => n -> host.counter(i) }.toMap
    host.write(IrqStatus, irq) // write 1 to clear what was pending
    Finish((irq & bits(IrqStatus, "DONE")) != 0, status, counters)
  }

  def bits(r: Reg, names: String*): Long = names.map(n => 1L << r.fields.find(_.name == n).get.lsb).sum
}
