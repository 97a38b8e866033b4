package rtaccel.cli

import java.nio.file.{Files, Path}

/** What a long-lived JVM (rtaccel.cli.Serve) keeps between requests: parsed scenes and rays, trees and the
  * access traces of the cache model, so that a design point that only changes a cache costs a replay, not a
  * reload, a rebuild and a retrace. Off in the one-shot entry points (nothing to reuse there).
  *
  * Keys hold what shapes the value and nothing else. Values are never mutated after they are made (the scene,
  * rays, tree and trace arrays are read-only to every command), so sharing them between requests is safe.
  * Each table keeps its few most recently used entries: a trace of a large scene is hundreds of MB.
  */
object Memo {
  /** On per thread: the server answers its requests on one thread; other threads of the same JVM (test suites
    * run side by side in one) keep computing afresh and leave the counts a test checks alone. */
  private val on = ThreadLocal.withInitial[java.lang.Boolean](() => false)
  def enabled: Boolean = on.get
  def enabled_=(b: Boolean): Unit = on.set(b)

  /** Hits and misses per table since the JVM started (Serve reports them; tests check the reuse). */
  val hits: scala.collection.mutable.Map[String, Long] = scala.collection.mutable.Map().withDefaultValue(0L)
  val misses: scala.collection.mutable.Map[String, Long] = scala.collection.mutable.Map().withDefaultValue(0L)

  private val capacity = Map("scene" -> 4, "rays" -> 4, "bvh" -> 8, "trace" -> 2)
  private val tables = scala.collection.mutable.Map[String, rtaccel.io.Lru[Any, Any]]()

  private def table(name: String): rtaccel.io.Lru[Any, Any] =
    tables.getOrElseUpdate(name, new rtaccel.io.Lru[Any, Any](capacity.getOrElse(name, 2)))

  /** `make` once per key while enabled; every call when disabled. */
  def apply[V](name: String, key: Any)(make: => V): V = synchronized {
    if (!enabled) make
    else {
      val t = table(name)
      t.get(key) match {
        case Some(v) => hits(name) += 1; v.asInstanceOf[V]
        case None => misses(name) += 1; val v = make; t.put(key, v); v
      }
    }
  }

  /** Whether `name` would answer `key` from memory (for the "reused" flags of a result). */
  def has(name: String, key: Any): Boolean = synchronized(enabled && tables.get(name).exists(_.contains(key)))

  /** apply keyed by the file `p` (and `extra`); an absent file is left to `make`, which names the problem. */
  def file[V](name: String, p: Path, extra: Any = ())(make: => V): V =
    if (enabled && Files.isRegularFile(p)) apply(name, (fileKey(p), extra))(make) else make

  /** A file as a key: its real path, size and modification time, so an edited file is read again. */
  def fileKey(p: Path): (String, Long, Long) = {
    val r = p.toRealPath()
    (r.toString, Files.size(r), Files.getLastModifiedTime(r).toMillis)
  }

  /** An object as a key by identity: a kept tree is the same instance on every request, and hashing its nodes
    * deeply on every lookup would cost what the memo saves. */
  final class Id(val ref: AnyRef) {
    override def equals(o: Any): Boolean = o match { case i: Id => i.ref eq ref; case _ => false }
    override def hashCode: Int = System.identityHashCode(ref)
  }

  def clear(): Unit = synchronized { tables.clear(); hits.clear(); misses.clear() }
}
