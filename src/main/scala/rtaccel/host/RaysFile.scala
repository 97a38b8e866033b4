package rtaccel.host

import java.nio.file.Path
import rtaccel.io.Npy
import rtaccel.scene.Rays

/** Rays as the harness's ROM holds them: one $readmemh line of 9 words (id, then the rays.npy row),
  * word 0 least significant, as on the AXI4-Stream.
  */
object RaysFile {
  def write(rays: Rays, path: Path): Unit = {
    val sb = new java.lang.StringBuilder(rays.count * 74)
    for (i <- 0 until rays.count) {
      for (k <- 7 to 0 by -1) sb.append(f"${java.lang.Float.floatToRawIntBits(rays(i, k))}%08x")
      sb.append(f"$i%08x").append('\n')
    }
    Npy.atomicWrite(path, sb.toString.getBytes("US-ASCII"))
  }
}
