package rtaccel.model

/** Memory accesses one traversal unit issues for one ray, in issue order. */
trait AccessSink {
  def node(ray: Int, id: Int, level: Int): Unit
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit
}

object AccessSink {
  val none: AccessSink = new AccessSink {
    def node(ray: Int, id: Int, level: Int): Unit = ()
    def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = ()
  }
}

/** Records accesses as rows of 5 ints: ray, kind (0 node, 1 leaf), id or first primitive slot, level,
  * primitive count (0 for nodes). This is the layout of trace.npy.
  */
final class AccessRecorder extends AccessSink {
  private var buf = new Array[Int](1 << 16)
  private var n = 0
  private def add(a: Int, b: Int, c: Int, d: Int, e: Int): Unit = {
    if (n + 5 > buf.length) buf = java.util.Arrays.copyOf(buf, buf.length * 2)
    buf(n) = a; buf(n + 1) = b; buf(n + 2) = c; buf(n + 3) = d; buf(n + 4) = e; n += 5
  }
  def node(ray: Int, id: Int, level: Int): Unit = add(ray, 0, id, level, 0)
  def leaf(ray: Int, firstPrim: Int, count: Int, level: Int): Unit = add(ray, 1, firstPrim, level, count)
  def rows: Int = n / 5
  def toArray: Array[Int] = java.util.Arrays.copyOf(buf, n)
}
