package rtaccel.io

import java.io.{ByteArrayOutputStream, File}
import java.nio.{ByteBuffer, ByteOrder}
import java.nio.file.{Files, Path, StandardCopyOption}

/** Thrown for any user-facing input problem; CLIs print the message and exit 2. */
final class InputError(msg: String) extends RuntimeException(msg)

/** A parsed .npy array: header fields plus the raw little-endian payload. */
final case class NpyArray(descr: String, shape: Seq[Int], data: ByteBuffer) {
  def count: Int = shape.product
  /** Refuses a payload shorter than the shape needs (a truncated file) before anything reads past it. */
  def requireBytes(path: Path, itemBytes: Int): Unit = {
    val need = shape.map(_.toLong).product * itemBytes
    if (data.remaining < need)
      throw new InputError(s"$path: the shape (${shape.mkString(",")}) needs $need bytes of data but the file holds ${data.remaining}; the file is truncated, write it again")
  }
}

/** Minimal NumPy .npy (format 1.0/2.0) reader and writer for the layouts rtaccel exchanges with Python:
  * C-order float32/int32 arrays and the structured hits record. Kept tiny and strict on purpose: a file
  * in another layout is an input error, not something to coerce silently.
  */
object Npy {
  private val Magic = Array[Byte](0x93.toByte, 'N', 'U', 'M', 'P', 'Y')

  def read(path: Path): NpyArray = {
    if (!Files.isRegularFile(path)) throw new InputError(s"$path: no such file")
    val bytes = Files.readAllBytes(path)
    if (bytes.length < 10 || !bytes.take(6).sameElements(Magic))
      throw new InputError(s"$path: not a NumPy .npy file (bad magic); write it with numpy.save")
    val major = bytes(6).toInt
    val bb = ByteBuffer.wrap(bytes).order(ByteOrder.LITTLE_ENDIAN)
    val (hlen, hstart) = major match {
      case 1 => (bb.getShort(8) & 0xffff, 10)
      case 2 | 3 => (bb.getInt(8), 12)
      case v => throw new InputError(s"$path: unsupported .npy version $v")
    }
    if (hlen < 0 || hstart.toLong + hlen > bytes.length)
      throw new InputError(s"$path: its header claims $hlen bytes but the file has ${bytes.length - hstart}; the file is truncated")
    val header = new String(bytes, hstart, hlen, "latin1")
    val descr = field(header, "descr", path)
    if (field(header, "fortran_order", path).trim != "False")
      throw new InputError(s"$path: Fortran-order array; save a C-contiguous array (np.ascontiguousarray)")
    val shapeTxt = field(header, "shape", path).trim.stripPrefix("(").stripSuffix(")")
    val shape = shapeTxt.split(",").map(_.trim).filter(_.nonEmpty).map(d => d.toIntOption.filter(_ >= 0).getOrElse(
      throw new InputError(s"$path: malformed shape '($shapeTxt)' in the .npy header; write the file with numpy.save"))).toSeq
    val data = ByteBuffer.wrap(bytes, hstart + hlen, bytes.length - hstart - hlen).slice().order(ByteOrder.LITTLE_ENDIAN)
    NpyArray(descr.trim, shape, data)
  }

  /** Extracts one value of the header dict; values are a quoted string, a list, a tuple or a bare word. */
  private def field(header: String, key: String, path: Path): String = {
    val k = header.indexOf(s"'$key'")
    if (k < 0) throw new InputError(s"$path: .npy header has no '$key'")
    val rest = header.substring(header.indexOf(':', k) + 1).trim
    def until(open: Char, close: Char): String = {
      var depth = 0; var i = 0
      while (i < rest.length && !(depth == 1 && rest(i) == close)) {
        if (rest(i) == open) depth += 1 else if (rest(i) == close) depth -= 1
        i += 1
      }
      rest.substring(0, i + 1)
    }
    try rest.head match {
      case '\'' => rest.substring(1, rest.indexOf('\'', 1))
      case '['  => until('[', ']')
      case '('  => until('(', ')')
      case _    => rest.takeWhile(c => c != ',' && c != '}')
    } catch { // a damaged header: say so in one line instead of an index error
      case _: IndexOutOfBoundsException | _: NoSuchElementException =>
        throw new InputError(s"$path: malformed '$key' in the .npy header; write the file with numpy.save")
    }
  }

  /** Float32 array of an exact trailing shape, e.g. expectTrailing = Seq(3,3) for (T,3,3). */
  def readFloats(path: Path, what: String, expectTrailing: Seq[Int]): (Array[Float], Int) = {
    val a = read(path)
    if (a.descr != "<f4")
      throw new InputError(s"$path: $what must be float32 ('<f4'), found '${a.descr}'; convert with .astype(np.float32)")
    if (a.shape.length != expectTrailing.length + 1 || a.shape.tail != expectTrailing)
      throw new InputError(s"$path: $what must have shape (N,${expectTrailing.mkString(",")}), found (${a.shape.mkString(",")})")
    a.requireBytes(path, 4)
    val out = new Array[Float](a.count)
    a.data.asFloatBuffer().get(out)
    (out, a.shape.head)
  }

  def header(descr: String, shape: Seq[Int]): Array[Byte] = {
    val shapeTxt = if (shape.length == 1) s"(${shape.head},)" else shape.mkString("(", ", ", ")")
    val dict = s"{'descr': $descr, 'fortran_order': False, 'shape': $shapeTxt, }"
    val total = ((6 + 2 + 2 + dict.length + 1 + 63) / 64) * 64
    val padded = dict + " " * (total - 10 - dict.length - 1) + "\n"
    val bb = ByteBuffer.allocate(10).order(ByteOrder.LITTLE_ENDIAN)
    bb.put(Magic).put(1.toByte).put(0.toByte).putShort(padded.length.toShort)
    bb.array() ++ padded.getBytes("latin1")
  }

  /** Writes atomically (temp file + rename) so a failed run never leaves a half-written output. */
  def write(path: Path, descr: String, shape: Seq[Int], payload: ByteBuffer => Unit, payloadBytes: Int): Unit = {
    val bb = ByteBuffer.allocate(payloadBytes).order(ByteOrder.LITTLE_ENDIAN)
    payload(bb)
    val out = new ByteArrayOutputStream()
    out.write(header(descr, shape)); out.write(bb.array())
    atomicWrite(path, out.toByteArray)
  }

  def writeInts(path: Path, data: Array[Int], cols: Int): Unit =
    write(path, "'<i4'", Seq(data.length / cols, cols), bb => data.foreach(bb.putInt), data.length * 4)

  def atomicWrite(path: Path, bytes: Array[Byte]): Unit = {
    val dir = Option(path.toAbsolutePath.getParent).getOrElse(new File(".").toPath)
    Files.createDirectories(dir)
    val tmp = Files.createTempFile(dir, ".part-", path.getFileName.toString)
    Files.write(tmp, bytes)
    Files.move(tmp, path, StandardCopyOption.REPLACE_EXISTING, StandardCopyOption.ATOMIC_MOVE)
  }
}
