package rtaccel.cli

import java.nio.file.{Path, Paths}
import rtaccel.config.{CacheParams, Fit, PlatformParams, Presets}
import rtaccel.bvh.Mbvh
import rtaccel.io.{InputError, Npy}
import rtaccel.scene.{Normalize, Rays, Scene}

/** Shared plumbing of the command-line entry points the Makefile calls. */
object Cli {
  val version: String = sys.props.getOrElse("rtaccel.version", "0.1.0")

  /** Runs a command body; user errors become one `error:` line and status 2 (returned for tests). */
  def status(args: Array[String])(body: Args => Unit): Int =
    try { body(Args.parse(args)); 0 }
    catch {
      case e: InputError => Console.err.println(s"error: ${e.getMessage}"); 2
      case e: IllegalArgumentException =>
        Console.err.println(s"error: ${e.getMessage.stripPrefix("requirement failed: ")}")
        if (sys.env.contains("RTACCEL_DEBUG")) e.printStackTrace()
        2
    }
    finally System.out.flush()

  /** `main` of an entry point: exits with the status when it is not 0. */
  def run(args: Array[String])(body: Args => Unit): Unit = {
    val code = status(args)(body)
    if (code != 0) sys.exit(code)
  }

  /** CONFIG=<preset> uses the preset's fixed widths and refuses scenes that exceed them; CONFIG=fit (default)
    * starts from paper2017 and fits field widths and stack depth to the scene. M/MPPL/TUS override either.
    */
  def params(a: Args): PlatformParams = {
    val cfg = a.get("config", "fit")
    val base = if (cfg == "fit") Presets.paper2017.copy(name = "fit") else Presets.byName(cfg)
    base.copy(m = a.int("m", base.m), mppl = a.int("mppl", base.mppl), tus = a.int("tus", base.tus),
      nodeAccessBytesOverride = a.int("node-bytes", base.nodeAccessBytesOverride),
      primAccessBytes = a.int("prim-bytes", base.primAccessBytes),
      stackDepth = a.int("stack-depth", base.stackDepth),
      nodeCache = cacheArg(a, "node"), primCache = cacheArg(a, "prim"))
  }

  /** NODE_CACHE/NODE_WAYS/NODE_POLICY (or PRIM_...) and MAX_LEVEL. Absent --<prefix>-cache means no cache:
    * a preset's own cache (paper2017: 2^13 DM) is used only when asked for, so every command's default is
    * the uncached platform. Policy default: dm for one way, lru otherwise.
    */
  def cacheArg(a: Args, prefix: String): CacheParams = {
    val entries = a.int(s"$prefix-cache", 0)
    if (entries < 0) throw new InputError(s"--$prefix-cache must be >= 0 (got $entries)")
    val ways = a.int(s"$prefix-ways", 1)
    val pol = a.get(s"$prefix-policy", if (ways == 1) "dm" else "lru")
    CacheParams(entries = entries, ways = ways, policy = pol, maxLevel = a.int("max-level", 15))
  }

  final case class Built(scene: Scene, params: PlatformParams, bvh: Mbvh, buildSeconds: Double)

  def build(scene: Scene, p0: PlatformParams, fit: Boolean): Built = {
    val t0 = System.nanoTime()
    val bvh = Mbvh.build(scene, p0)
    val secs = (System.nanoTime() - t0) / 1e9
    val p = if (fit) Fit.fitTo(p0, bvh) else { Fit.check(p0, bvh, scene.name); p0 }
    Built(scene, p, bvh, secs)
  }

  def fitRequested(a: Args): Boolean = a.get("config", "fit") == "fit"

  /** The scene and rays as the host driver uploads them: scaled by one power of two (see Normalize). */
  def inputs(a: Args): (Scene, Rays, Int) = {
    val raw = Scene.load(a.path("tris"))
    val rays = Rays.load(a.path("rays"))
    val e = Normalize.exponent(raw)
    (Normalize.scene(raw, e), Normalize.rays(rays, e), e)
  }

  def writeText(path: Path, text: String): Unit = Npy.atomicWrite(path, text.getBytes("UTF-8"))
}

/** `--key value` arguments; every value a command reads is validated where it is read. */
final case class Args(kv: Map[String, String]) {
  def get(k: String, default: String): String = kv.getOrElse(k, default)
  def opt(k: String): Option[String] = kv.get(k).filter(_.nonEmpty)
  def need(k: String): String = opt(k).getOrElse(throw new InputError(s"missing --$k"))
  def path(k: String): Path = Paths.get(need(k))
  def int(k: String, default: Int): Int = opt(k).map(v => v.toIntOption.getOrElse(
    throw new InputError(s"--$k must be an integer (got '$v')"))).getOrElse(default)
}

object Args {
  def parse(a: Array[String]): Args = {
    if (a.length % 2 != 0 || a.grouped(2).exists(p => !p(0).startsWith("--")))
      throw new InputError(s"arguments must be --key value pairs (got ${a.mkString(" ")})")
    Args(a.grouped(2).map(p => p(0).stripPrefix("--") -> p(1)).toMap)
  }
}
