package rtaccel.io

import java.security.MessageDigest

/** Short names from content: the first bytes of a SHA-256 in lower-case hex (the synthesis and timing caches' keys,
  * the simulator builds' input folders, the shells of firtool's Verilog, a platform's parameters). */
object Digest {
  /** The first `bytes` bytes of the SHA-256 of `parts`, in order, as 2 * `bytes` hex digits. */
  def hex(bytes: Int, parts: Array[Byte]*): String = hexOfAll(bytes, parts.iterator)
  /** [[hex]] of parts made one at a time (a platform's Verilog files, read as they are hashed, not all at once). */
  def hexOfAll(bytes: Int, parts: Iterator[Array[Byte]]): String = {
    val md = MessageDigest.getInstance("SHA-256")
    parts.foreach(md.update)
    md.digest().take(bytes).map(b => f"${b & 0xff}%02x").mkString
  }
  /** [[hex]] of a text's UTF-8 bytes. */
  def hexOf(bytes: Int, text: String): String = hex(bytes, text.getBytes("UTF-8"))
}
