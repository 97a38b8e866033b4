package rtaccel.config

import rtaccel.io.InputError

/** PIPELINE=auto|none|<levels> (docs/timing.md): how many LUT levels of logic the datapaths may put between two
  * registers. `auto` takes the budget the target clock leaves on the board's family (area.FamilyTiming), `<levels>`
  * gives it directly, `none` keeps the fixed stages of before pipelining was a parameter (for comparison).
  */
sealed trait Pipelining {
  def name: String
  /** The budget in LUT levels for a clock on a family, or None (PIPELINE=none). */
  def budget(family: String, clockMhz: Double): Option[Int]
}

object Pipelining {
  case object Fixed extends Pipelining {
    val name = "none"
    def budget(family: String, clockMhz: Double): Option[Int] = None
  }
  case object Auto extends Pipelining {
    val name = "auto"
    def budget(family: String, clockMhz: Double): Option[Int] = Some(rtaccel.area.Timing.forFamily(family).levelsFor(clockMhz))
  }
  final case class Levels(n: Int) extends Pipelining {
    require(n >= MinLevels && n <= MaxLevels, s"PIPELINE=$n: give $MinLevels..$MaxLevels LUT levels per stage, auto or none")
    val name: String = n.toString
    def budget(family: String, clockMhz: Double): Option[Int] = Some(n)
  }
  /** A budget below this would need a register inside a LUT level's worth of carry chain or shifter. */
  val MinLevels = 2
  val MaxLevels = 64

  /** What every JSON line that describes a circuit records of its pipelining. */
  def json(p: PlatformParams): ujson.Obj = ujson.Obj("mode" -> p.pipelining.name,
    "budget_levels" -> p.stageBudget.fold[ujson.Value](ujson.Null)(n => ujson.Num(n)),
    "family" -> p.family, "for_mhz" -> ujson.Num(p.pipelineMhz.getOrElse(p.clockMhz)))

  def parse(s: String): Pipelining = s.toLowerCase match {
    case "auto" => Auto
    case "none" => Fixed
    case v => v.toIntOption.filter(n => n >= MinLevels && n <= MaxLevels).map(Levels(_)).getOrElse(
      throw new InputError(s"PIPELINE=$s: use auto (registers for the target clock on the board's family), none (the fixed " +
        s"stages, for comparison) or a budget of $MinLevels..$MaxLevels LUT levels between registers"))
  }
}
