package rtaccel.area

import java.nio.file.{Files, Path, Paths}
import scala.sys.process._
import rtaccel.io.InputError

/** Running the synthesis and place-and-route tools: a long run reports, every `beatS` seconds, the phase its log
  * is in (Yosys' numbered pass, nextpnr's "Info: Routing..."), since the whole platform takes minutes.
  */
object Tools {
  /** Runs `cmd` in `dir` to its end and returns its status; lines that name an error are shown as they come. */
  def run(cmd: Seq[String], dir: Path, progress: String => Unit, phase: () => String, beatS: Double = 30): Int = {
    val tail = scala.collection.mutable.Queue[String]()
    val show: String => Unit = l => {
      if (l.contains("ERROR") || l.contains("trap")) progress(l)
      tail.synchronized { tail += l; if (tail.length > 3) tail.dequeue(); () }
    }
    val proc = Process(cmd, dir.toFile).run(ProcessLogger(show, show))
    val t0 = System.nanoTime(); var beat = t0
    while (proc.isAlive()) {
      Thread.sleep(200)
      if (System.nanoTime() - beat > beatS * 1e9) {
        beat = System.nanoTime()
        progress(f"${(beat - t0) / 1e9}%.0f s, ${phase()}")
      }
    }
    val code = proc.exitValue()
    // a tool that dies (a WebAssembly trap) says why on its terminal, not in its log
    if (code != 0) tail.synchronized(tail.foreach(l => progress(s"  $l")))
    code
  }

  /** The last line of `log`'s tail that `keep` accepts (trimmed), or `otherwise`. */
  def lastLine(log: Path, keep: String => Boolean, otherwise: String): String = {
    if (!Files.exists(log)) return otherwise
    val r = new java.io.RandomAccessFile(log.toFile, "r")
    try {
      val n = math.min(r.length, 65536L); r.seek(r.length - n)
      val buf = new Array[Byte](n.toInt); r.readFully(buf)
      new String(buf, "latin1").split("\n").reverseIterator.map(_.trim).find(keep).getOrElse(otherwise)
    } finally r.close()
  }

  /** The lines `cmd` prints on stdout and stderr (nextpnr prints its version on stderr), YoWASP's own
    * "Preparing to run" notice left out. */
  def output(cmd: Seq[String]): Seq[String] = {
    val lines = scala.collection.mutable.ArrayBuffer[String]()
    val code = try Process(cmd).!(ProcessLogger(l => lines += l, l => lines += l)) catch {
      case e: Exception => throw new InputError(s"${cmd.mkString(" ")} failed (${e.getMessage}); run make deps")
    }
    if (code != 0) throw new InputError(s"${cmd.mkString(" ")} failed (status $code): ${lines.takeRight(3).mkString(" | ")}")
    lines.filterNot(_.startsWith("Preparing to run")).map(_.trim).filter(_.nonEmpty).toSeq
  }

  /** A YoWASP tool (`yosys`, `nextpnr-ecp5`) of the project's .venv, run through tools/yowasp_stack.py: with
    * YoWASP's default WebAssembly stack, Yosys' techmap of TraversalController (hence of the whole platform) traps
    * with "call stack exhausted". */
  def yowasp(tool: String): Seq[String] = {
    venv(s"yowasp-$tool") // present, or the error that says how to install it
    val launcher = Paths.get("tools/yowasp_stack.py").toAbsolutePath
    if (!Files.isRegularFile(launcher)) throw new InputError(s"$launcher not found; run from the project root")
    Seq(venv("python"), launcher.toString, tool)
  }

  /** A tool of the project's Python environment (.venv, from requirements.txt; RTACCEL_VENV names another one). */
  def venv(name: String): String = {
    val root = Paths.get(sys.env.getOrElse("RTACCEL_VENV", ".venv"))
    val p = root.resolve("bin").resolve(name).toAbsolutePath
    if (Files.isExecutable(p)) p.toString
    else throw new InputError(s"$name not found in $root/bin; run make deps (requirements.txt pins it)")
  }
}
