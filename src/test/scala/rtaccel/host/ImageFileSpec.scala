package rtaccel.host

import java.nio.file.{Files, Path}
import org.scalatest.flatspec.AnyFlatSpec
import rtaccel.TestScenes
import rtaccel.bvh.{Mbvh, MemoryImage}
import rtaccel.config.{Fit, Presets, RefFormat}
import rtaccel.mc.AxiParams

/** Shared by the memory tests: a small real image and an independent parser of the hex file. */
object MemTestImages {
  /** A random soup packed with fitted reference widths, or with `refs` if given. */
  def image(seed: Long, tris: Int, refs: Option[RefFormat] = None): MemoryImage = {
    val scene = TestScenes.soup(seed, tris)
    val bvh = Mbvh.build(scene, Presets.small)
    MemoryImage.pack(bvh, scene, refs.fold(Fit.fitTo(Presets.small, bvh))(f => Presets.small.copy(refs = f)))
  }

  /** Parses a $readmemh file into a byte-addressed little-endian array (independent of ImageFile). */
  def parseHex(path: Path, axi: AxiParams): Array[Byte] = {
    val lines = Files.readAllLines(path)
    val out = new Array[Byte](lines.size * axi.beatBytes)
    for (i <- 0 until lines.size) {
      val s = lines.get(i)
      assert(s.length == axi.dataBits / 4, s"line $i: ${s.length} digits")
      val v = BigInt(s, 16)
      for (b <- 0 until axi.beatBytes) out(i * axi.beatBytes + b) = ((v >> (8 * b)) & 0xff).toByte
    }
    out
  }

  def le32(bytes: Array[Byte], at: Long): Int = {
    val a = at.toInt
    (bytes(a) & 0xff) | (bytes(a + 1) & 0xff) << 8 | (bytes(a + 2) & 0xff) << 16 | (bytes(a + 3) & 0xff) << 24
  }

  /** The image as a byte array laid out as in DRAM (the test's own reference for expected beats). */
  def dramBytes(img: MemoryImage, lay: ImageLayout, axi: AxiParams): Array[Byte] = {
    val out = new Array[Byte](lay.words * axi.beatBytes)
    def put(at: Long, w: Int): Unit = for (b <- 0 until 4) out((at + b).toInt) = (w >>> (8 * b)).toByte
    for (i <- img.nodes.indices) put(4L * i, img.nodes(i))
    for (i <- img.prims.indices) put(lay.primBaseBytes + 4L * i, img.prims(i))
    out
  }

  def beat(bytes: Array[Byte], addr: Long, axi: AxiParams): BigInt =
    (0 until axi.beatBytes).foldLeft(BigInt(0))((acc, b) => acc | (BigInt(bytes((addr + b).toInt) & 0xff) << (8 * b)))
}

class ImageFileSpec extends AnyFlatSpec {
  import MemTestImages._

  for (dataBits <- Seq(32, 256, 512)) {
    s"ImageFile ($dataBits-bit words)" should "round-trip every node and primitive word at its byte address" in {
      val axi = AxiParams(dataBits = dataBits)
      val img = image(11, 300)
      val dir = Files.createTempDirectory("imgfile")
      val path = dir.resolve("img.hex")
      val lay = ImageFile.write(img, axi, path)
      val nodeEnd = img.nodes.length * 4L
      assert(lay.primBaseBytes >= nodeEnd && lay.primBaseBytes % 4096 == 0 && lay.primBaseBytes - nodeEnd < 4096)
      assert(lay.words.toLong * axi.beatBytes >= lay.primBaseBytes + img.prims.length * 4L)
      assert(lay.words.toLong * axi.beatBytes < lay.primBaseBytes + img.prims.length * 4L + axi.beatBytes)
      val bytes = parseHex(path, axi)
      assert(bytes.length == lay.words * axi.beatBytes)
      val p = img.p
      for (n <- 0 until img.numNodes; k <- 0 until img.nodeWords)
        assert(le32(bytes, n.toLong * p.nodeStrideBytes + 4 * k) == img.nodes(n * img.nodeWords + k), s"node $n word $k")
      for (s <- 0 until img.numPrims; k <- 0 until img.primWords)
        assert(le32(bytes, lay.primBaseBytes + 64L * s + 4 * k) == img.prims(s * img.primWords + k), s"prim $s word $k")
      // The gap between nodes and primitives is zero.
      for (a <- nodeEnd until lay.primBaseBytes) assert(bytes(a.toInt) == 0)
      assert(!Files.list(dir).toArray.exists(_.toString.endsWith(".tmp")), "temp file left behind")
    }
  }

  "ImageFile" should "write a 32 MB image quickly" in {
    val axi = AxiParams(dataBits = 256)
    val img = image(3, 50)
    // A synthetic large image: same params, 32 MB of primitive words.
    val big = img.copy(prims = Array.tabulate(8 * 1024 * 1024)(i => i * 0x9e3779b9))
    val path = Files.createTempDirectory("imgfile").resolve("big.hex")
    val t0 = System.nanoTime()
    val lay = ImageFile.write(big, axi, path)
    val secs = (System.nanoTime() - t0) / 1e9
    info(f"32 MB image written in $secs%.2f s (${Files.size(path) / 1e6}%.0f MB hex)")
    assert(Files.size(path) == lay.words.toLong * (axi.dataBits / 4 + 1))
    assert(secs < 20)
    Files.delete(path)
  }
}
