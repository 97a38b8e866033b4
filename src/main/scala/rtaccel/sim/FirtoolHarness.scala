package rtaccel.sim

import java.nio.file.{Files, Path}
import chisel3._

/** A module as the simulators build it: the SystemVerilog that firtool (CIRCT, make verilog's compiler) makes of it,
  * inside a shell of the same ports that chiseltest compiles and drives. chiseltest's own path lowers the whole
  * circuit with its Scala FIRRTL compiler (firrtl2), which was most of a platform build: measured on make test's
  * 4-TU fixed-stage platform, 25 s of JVM (elaboration and firrtl2's passes) and 3.0 MB of Verilog that Verilator made
  * into 25 MB of C++, against 14 s (elaboration, firtool, the shell) and 0.9 MB of Verilog, 11 MB of C++ through
  * firtool: the case took 33 s instead of 46 (docs/platform.md, "Test time"). Ports and behaviour are the same: both
  * are the one Chisel circuit.
  */
object FirtoolHarness {
  /** The elaborated module (its Scala values, e.g. a latency, stay readable), the shell to elaborate and the files
    * that Verilator is given among its flags (VerilatorBuild.withSources), its `define` included. Not black-box resources: chiseltest lists those in a `-f` file, and Verilator 5.006 then runs
    * its `--build` make at `-j 1` whatever `-j` says (a platform's C++ compiled on one core).
    */
  final case class Shell[M, I <: Data](module: M, gen: () => FirtoolShell[I], sources: Seq[String])

  /** firtool's SystemVerilog of `gen` (make verilog's options: no randomization, so every register and memory starts
    * at zero in Verilator as chiseltest's firrtl2 output did) in `dir`, one file per module, and the shell that drives
    * it through `io` (the module's only port besides clock and reset). The shell's name carries the text's digest:
    * chiseltest's build cache compares the shell's circuit, so another text is another circuit and is rebuilt.
    */
  def shell[M <: Module, I <: Data](gen: => M, dir: Path)(io: M => I): Shell[M, I] = {
    var top: Option[M] = None
    val files = rtaccel.cli.EmitVerilog.emitModule({ val m = gen; top = Some(m); m }, dir)
    val digest = rtaccel.io.Digest.hexOfAll(6, files.iterator.map(f => Files.readAllBytes(f)))
    val m = top.get
    val port = io(m)
    // firtool puts the memories' $readmemh (SimHarness's image and rays) under ENABLE_INITIAL_MEM_, which its
    // randomization header would define, and that header is off
    Shell(m, () => new FirtoolShell(() => chiselTypeOf(port), m.name, digest), "+define+ENABLE_INITIAL_MEM_" +: files.map(_.toAbsolutePath.toString))
  }

  /** `shell` once per `key` and `dir` in this JVM (the few most recent): a run that finds its simulator in chiseltest's
    * build cache would otherwise elaborate the module and run firtool again only to name the shell (10-25 s for a
    * platform; make test runs most of its platforms more than once). `key` must hold everything that shapes the
    * circuit, as a build key does; the files must still be in `dir`, else they are made again.
    */
  def shellOnce[M <: Module, I <: Data](key: Any, gen: => M, dir: Path)(io: M => I): Shell[M, I] = {
    val k = (key, dir.toAbsolutePath.normalize.toString)
    val kept = recent.get(k).map(_.asInstanceOf[Shell[M, I]])
      .filter(_.sources.tail.forall(f => Files.isRegularFile(java.nio.file.Paths.get(f))))
    kept.getOrElse {
      val s = shell(gen, dir)(io)
      recent.put(k, s)
      s
    }
  }
  // an entry holds an elaborated module (tens of MB for a platform): the two suites a test JVM runs side by side
  // each reuse their last two
  private val recent = new rtaccel.io.Lru[Any, Shell[_, _]](4)
}

/** firtool's module `name` as a black box: ports `clock`, `reset` and the module's `io`, flattened `io_*`. */
class FirtoolBox[I <: Data](ioType: () => I, name: String) extends BlackBox {
  val io = IO(new Bundle {
    val clock = Input(Clock())
    val reset = Input(Bool())
    val io = ioType()
  })
  override def desiredName = name
}

/** What chiseltest builds and drives: the module's `io`, passed through to the firtool-built module. */
class FirtoolShell[I <: Data](ioType: () => I, name: String, digest: String) extends Module {
  val io = IO(ioType())
  private val m = Module(new FirtoolBox(ioType, name))
  m.io.clock := clock
  m.io.reset := reset.asBool
  m.io.io <> io
  override def desiredName = s"${name}Shell_$digest"
}
