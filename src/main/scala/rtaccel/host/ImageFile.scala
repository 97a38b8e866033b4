package rtaccel.host

import java.io.{BufferedWriter, OutputStreamWriter}
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, StandardCopyOption}
import rtaccel.bvh.MemoryImage
import rtaccel.mc.AxiParams

/** Where the image landed in the simulated DRAM: primitive slot 0 is at byte primBaseBytes (nodes start
  * at byte 0); words = number of AXI words (lines) in the hex file.
  */
final case class ImageLayout(primBaseBytes: Long, words: Int)

/** Writes a MemoryImage as a `$readmemh` file for the DRAM model: one line per AXI word of dataBits/4 hex
  * digits, little-endian (byte b lives in word b / beatBytes at bit 8 * (b % beatBytes)).
  * Nodes at byte 0 (node n at n * nodeSlotBytes, in NODE_FORMAT's layout), primitives from primBaseBytes = end of nodes rounded
  * up to 4096 B (slot s at primBaseBytes + 64 s).
  */
object ImageFile {
  val primAlignBytes: Long = 4096

  def layout(img: MemoryImage, axi: AxiParams): ImageLayout = {
    val nodeBytes = img.nodes.length.toLong * 4
    val primBase = (nodeBytes + primAlignBytes - 1) / primAlignBytes * primAlignBytes
    val end = primBase + img.prims.length.toLong * 4
    val words = math.max(1L, (end + axi.beatBytes - 1) / axi.beatBytes)
    require(words <= Int.MaxValue, s"image of $end bytes is too large for one hex file")
    ImageLayout(primBase, words.toInt)
  }

  /** The image as little-endian 32-bit words at 4-byte granularity (index = byte address / 4). */
  def flatWords(img: MemoryImage, lay: ImageLayout, axi: AxiParams): Array[Int] = {
    val w = new Array[Int](lay.words * (axi.beatBytes / 4))
    System.arraycopy(img.nodes, 0, w, 0, img.nodes.length)
    System.arraycopy(img.prims, 0, w, (lay.primBaseBytes / 4).toInt, img.prims.length)
    w
  }

  /** The image as the platform reads it, for the model to traverse: node ids over the whole id field and primitive
    * slots over the whole first field (plus a leaf's largest count), each read from memory where the platform reads
    * it (past the image: the gap before the primitives, the primitives, zeros), so that the stray references of a
    * corrupted image read the same words in the model as in the RTL. Every address those fields can name must lie in
    * the `capacityBytes` of memory (a fitted layout); slot64 primitives.
    */
  def asRead(img: MemoryImage, lay: ImageLayout, axi: AxiParams, capacityBytes: Long): MemoryImage = {
    val p = img.p
    require(!p.primPacked, "the memory view of an image takes PRIM_FORMAT=slot64")
    val nodeWords = (1L << p.refs.nodeIdBits) * img.nodeWords
    val primWords = ((1L << p.refs.primIndexBits) + p.refs.maxLeafPrims) * img.primWords
    require(4 * nodeWords <= capacityBytes && lay.primBaseBytes + 4 * primWords <= capacityBytes,
      s"the reference fields (${p.refs.nodeIdBits}-bit node ids, ${p.refs.primIndexBits}-bit primitive indices) name addresses " +
        s"beyond the $capacityBytes B of memory; fit the layout to the scene")
    val flat = flatWords(img, lay, axi)
    def read(from: Long, n: Long): Array[Int] = {
      val out = new Array[Int](n.toInt)
      val k = math.max(0L, math.min(n, flat.length - from)).toInt
      System.arraycopy(flat, from.toInt, out, 0, k)
      out
    }
    MemoryImage(p, read(0, nodeWords), read(lay.primBaseBytes / 4, primWords))
  }

  private val hexDigits = "0123456789abcdef".toCharArray

  def write(img: MemoryImage, axi: AxiParams, path: Path): ImageLayout = {
    require(axi.dataBits >= 32, "AXI words must hold at least one 32-bit image word")
    val lay = layout(img, axi)
    val flat = flatWords(img, lay, axi)
    val perWord = axi.beatBytes / 4
    val dir = Option(path.toAbsolutePath.getParent).getOrElse(path.toAbsolutePath)
    Files.createDirectories(dir)
    val tmp = Files.createTempFile(dir, path.getFileName.toString, ".tmp")
    try {
      val out = new BufferedWriter(new OutputStreamWriter(Files.newOutputStream(tmp), StandardCharsets.US_ASCII), 1 << 20)
      try {
        val line = new Array[Char](perWord * 8 + 1)
        line(perWord * 8) = '\n'
        var wi = 0
        while (wi < lay.words) {
          // The most significant 32-bit word (highest byte address) comes first on the line.
          var k = 0
          while (k < perWord) {
            val v = flat(wi * perWord + (perWord - 1 - k))
            var d = 0
            while (d < 8) { line(k * 8 + d) = hexDigits((v >>> (28 - 4 * d)) & 0xf); d += 1 }
            k += 1
          }
          out.write(line, 0, line.length)
          wi += 1
        }
      } finally out.close()
      Files.move(tmp, path, StandardCopyOption.REPLACE_EXISTING, StandardCopyOption.ATOMIC_MOVE)
    } finally Files.deleteIfExists(tmp)
    lay
  }
}
