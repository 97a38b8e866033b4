package rtaccel.cli

import java.io.{BufferedReader, ByteArrayOutputStream, InputStreamReader, OutputStream, PrintStream}
import scala.util.control.NonFatal

/** rtaccel.cli.Serve: one JVM that answers many commands, for the design-space explorer (dse/explore/explore.py).
  * Reads one JSON request per stdin line, {"cmd": "cachesim"|"analyze"|"simulate"|"area"|"trace", "args":
  * ["--flag", "value", ...]}, runs that command's main logic in this JVM with the same flags and checks as its
  * entry point, and answers one JSON line on stdout:
  *   {"status": 0|2|3, "result": <the command's JSON last line or null>, "error": "<its error: line or null>",
  *    "wall_s": s, "memo": {table: [hits, misses]}}
  * Status 0, 2 and 3 mean what they mean for the entry point; 1 = the command threw (a crash: the message is
  * in "error"). The JVM never exits on a request's status, only at the end of its input. Scenes, rays, trees
  * and access traces are kept between requests (Memo): the first request on a scene pays for them.
  * Progress lines of the commands go to stderr, as they do from the entry points.
  */
object Serve {
  val commands: Map[String, (Seq[Flags.Flag], Args => Unit)] = Map(
    "cachesim" -> (Flags.cacheSim, CacheSim.main0), "analyze" -> (Flags.analyze, Analyze.main0),
    "simulate" -> (Flags.simulate, Simulate.main0), "area" -> (Flags.area, Area.main0),
    "trace" -> (Flags.trace, Trace.main0))

  def main(args: Array[String]): Unit = {
    // The protocol owns the real stdout; anything else a command prints goes to stderr, never into an answer.
    val protocol = new PrintStream(new java.io.FileOutputStream(java.io.FileDescriptor.out), true, "UTF-8")
    System.setOut(System.err)
    Memo.enabled = true
    val in = new BufferedReader(new InputStreamReader(System.in, "UTF-8"))
    Iterator.continually(in.readLine()).takeWhile(_ != null).filter(_.trim.nonEmpty).foreach { line =>
      protocol.println(ujson.write(answer(line)))
    }
  }

  /** The answer to one request line (never throws for a request's fault). */
  def answer(line: String): ujson.Obj = {
    val t0 = System.nanoTime()
    val req = try Right(ujson.read(line)) catch { case NonFatal(e) => Left(s"request is not JSON (${e.getMessage.take(80)}); send one object per line") }
    val parsed = req.flatMap { j =>
      val cmd = j.objOpt.flatMap(_.get("cmd")).flatMap(_.strOpt)
      val args = j.objOpt.flatMap(_.get("args")).flatMap(_.arrOpt).map(_.toSeq)
      (cmd, args) match {
        case (Some(c), Some(as)) if !commands.contains(c) =>
          Left(s"unknown cmd '$c'; choose one of ${commands.keys.toSeq.sorted.mkString(", ")}")
        case (Some(c), Some(as)) if as.forall(_.strOpt.isDefined) => Right((c, as.map(_.str).toArray))
        case _ => Left("""a request is {"cmd": "<command>", "args": ["--flag", "value", ...]} with string args""")
      }
    }
    val out = parsed match {
      case Left(msg) => ujson.Obj("status" -> 2, "result" -> ujson.Null, "error" -> msg)
      case Right((cmd, args)) => run(cmd, args)
    }
    out("wall_s") = (System.nanoTime() - t0) / 1e9
    out("memo") = ujson.Obj.from((Memo.hits.keySet ++ Memo.misses.keySet).toSeq.sorted.map(k =>
      k -> ujson.Arr(Memo.hits(k).toDouble, Memo.misses(k).toDouble)))
    out
  }

  private def run(cmd: String, args: Array[String]): ujson.Obj = {
    val (flags, body) = commands(cmd)
    val stdout = new ByteArrayOutputStream()
    val err = new Tee(System.err)
    val status = try Console.withOut(new PrintStream(stdout, true, "UTF-8"))(Console.withErr(new PrintStream(err, true, "UTF-8"))(
      Cli.status(args, flags)(body)))
    catch { case NonFatal(e) => err.note(s"error: $cmd crashed: ${e.getClass.getName}: ${e.getMessage}"); 1 }
    val result = stdout.toString("UTF-8").linesIterator.toSeq.reverse.find(_.trim.startsWith("{"))
      .flatMap(l => scala.util.Try(ujson.read(l)).toOption).getOrElse(ujson.Null)
    val error = err.lines.reverse.find(_.startsWith("error:")).map(l => ujson.Str(l.stripPrefix("error:").trim)).getOrElse(ujson.Null)
    ujson.Obj("status" -> status, "result" -> result, "error" -> error)
  }

  /** Passes a command's stderr on and keeps it, so the answer can carry its `error:` line. */
  private final class Tee(to: OutputStream) extends OutputStream {
    private val kept = new ByteArrayOutputStream()
    override def write(b: Int): Unit = { to.write(b); kept.write(b) }
    override def write(b: Array[Byte], off: Int, len: Int): Unit = { to.write(b, off, len); kept.write(b, off, len) }
    override def flush(): Unit = to.flush()
    def note(line: String): Unit = write((line + "\n").getBytes("UTF-8"))
    def lines: Seq[String] = kept.toString("UTF-8").linesIterator.toSeq
  }
}
