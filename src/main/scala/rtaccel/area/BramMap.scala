package rtaccel.area

/** Block RAM a memory of depth x width needs on 7-series-like parts (RAMB36 = 36 Kb, RAMB18 = half), the way
  * Yosys' memory mapper tiles it: one aspect ratio for the whole memory, the cheapest one.
  * E.g. 32768 x 257 = 8 x 29 RAMB36 of 4K x 9 = 232; 1024 x 257 = 15 RAMB18 of 1K x 18 = 7.5 (both as synthesized).
  */
object BramMap {
  /** (depth, width, RAMB36 equivalents) of the simple-dual-port aspect ratios. */
  private val shapes: Seq[(Int, Int, Double)] =
    Seq((32768, 1), (16384, 2), (8192, 4), (4096, 9), (2048, 18), (1024, 36), (512, 72)).map { case (d, w) => (d, w, 1.0) } ++
      Seq((16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)).map { case (d, w) => (d, w, 0.5) }

  private def tile(depth: Long, width: Int, s: (Int, Int, Double)): Double =
    math.ceil(depth.toDouble / s._1) * math.ceil(width.toDouble / s._2) * s._3

  def bram36(depth: Long, width: Int): Double = {
    if (depth <= 0 || width <= 0) 0.0 else shapes.map(tile(depth, width, _)).min
  }
}
