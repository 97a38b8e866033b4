package rtaccel.config

/** A platform ready to run on a scene: the tree built for it and the configuration fitted (or checked) against that
  * tree (cli.Cli.build makes one from the command line; sim.PlatformRun and the models run it).
  */
final case class Built(scene: rtaccel.scene.Scene, params: PlatformParams, bvh: rtaccel.bvh.Mbvh, buildSeconds: Double)

/** The version every output file names (the Makefile passes `git describe` as -Drtaccel.version). */
object Version {
  val current: String = sys.props.getOrElse("rtaccel.version", "0.1.0")
}
