package rtaccel.config

import rtaccel.io.InputError

/** What the user asked for: a preset with the overrides given (`base`), and the parts that only a scene settles.
  * Resolving it gives the PlatformParams a circuit is built from: with a scene (cli.Cli.build fits or checks it against
  * the tree and the rays) or without one (`withoutScene`, for the commands that build a circuit from a preset alone).
  *
  * A field of `base` that a request leaves to the scene holds the preset's value and means nothing until resolved:
  * - `fitWidths` (CONFIG=fit): the reference field widths and the stack depth, from the tree (Fit.fitTo);
  * - `boxFit` (BOX_FORMAT=m<M>): M fraction bits, the exponent from the rays (BoxRange.fit);
  * - `nodeFit` (NODE_FORMAT=fit): the narrowest node quantization the rays allow (model.FormatFit).
  * `stackGiven` (STACK= given): `base.stackDepth` is kept as given, even below what the tree needs (Cli.build).
  */
final case class RequestedParams(base: PlatformParams, fitWidths: Boolean = false, boxFit: Option[Int] = None,
                                 nodeFit: Boolean = false, stackGiven: Boolean = false) {
  /** The same request over another base (a sweep's TUS, an analysis's MPPL). */
  def map(f: PlatformParams => PlatformParams): RequestedParams = copy(base = f(base))

  /** The base with the box format a fit starts from: the fraction bits asked and the widest exponent (8 bits). The
    * scene narrows the exponent; the tree does not depend on it. */
  def unfitted: PlatformParams = boxFit.fold(base)(m => base.copy(boxFormat = rtaccel.fp.FpFormat(8, m)))

  /** The platform as asked, for a command that reads no scene (`what` names it): refused, with what to give instead,
    * when a part of it is left to a scene. */
  def withoutScene(what: String): PlatformParams = {
    if (fitWidths) throw new InputError(s"$what needs a preset (CONFIG=${Presets.all.keys.toSeq.sorted.mkString("|")}); " +
      "fitted configs come from a scene via make simulate")
    boxFit.foreach(m => throw new InputError(s"BOX_FORMAT=m$m fits the exponent to a scene's rays, which $what does not read; " +
      s"give the format as e<E>m$m (make trace prints the fitted one under numerics)"))
    if (nodeFit) throw new InputError(s"NODE_FORMAT=fit picks the quantization from a scene's rays, which $what does not read; " +
      "give it as q<bits> or full (make trace prints the fitted one under numerics)")
    base
  }
}
