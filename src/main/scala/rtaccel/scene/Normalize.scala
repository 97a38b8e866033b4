package rtaccel.scene

/** Host-side normalisation before upload: scene coordinates, ray origins and ray directions are all
  * multiplied by 2^-e, where 2^e is the scene's largest coordinate magnitude rounded down to a power of two.
  *
  * Why: Möller–Trumbore forms products of three coordinates (det ~ |e1||e2||d|), which overflow fp32 for
  * scenes near 1e13 and beyond and underflow for scenes near 1e-13 and below. Scaling every input by a power
  * of two is exact (no rounding) while nothing overflows or goes subnormal, and u, v and t are ratios in
  * which the scale cancels; so the hit results are bit for bit those of the unscaled scene wherever that
  * one does not overflow, and finite where it would. tmin/tmax are distances in units of the direction and
  * stay unchanged.
  */
object Normalize {
  def exponent(s: Scene): Int = {
    val maxAbs = s.coords.foldLeft(0f)((m, c) => math.max(m, math.abs(c)))
    if (maxAbs == 0f) 0 else java.lang.Math.getExponent(maxAbs)
  }

  private def scale(x: Float, e: Int): Float = java.lang.Math.scalb(x, -e)

  def scene(s: Scene, e: Int): Scene = if (e == 0) s else s.copy(coords = s.coords.map(scale(_, e)))

  def rays(r: Rays, e: Int): Rays =
    if (e == 0) r else Rays(r.data.zipWithIndex.map { case (x, i) => if (i % 8 < 6) scale(x, e) else x })
}
