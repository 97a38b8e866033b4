package rtaccel.io

/** A map that keeps its `capacity` most recently used entries, safe to share between threads: the in-JVM memos of
  * emitted circuits (cli.EmitVerilog), firtool shells (sim.FirtoolHarness) and a server's scenes and traces (cli.Memo).
  */
final class Lru[K, V](capacity: Int) {
  require(capacity >= 1, s"an LRU map keeps at least one entry (got $capacity)")
  private val m = new java.util.LinkedHashMap[K, V](16, 0.75f, true) { // access order: the eldest is the least recently used
    override def removeEldestEntry(e: java.util.Map.Entry[K, V]): Boolean = size > capacity
  }
  def get(k: K): Option[V] = synchronized(Option(m.get(k)))
  def contains(k: K): Boolean = synchronized(m.containsKey(k))
  def put(k: K, v: V): Unit = synchronized(m.put(k, v))
}
