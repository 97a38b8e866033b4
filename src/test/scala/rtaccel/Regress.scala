package rtaccel

/** `make regress` (RTACCEL_REGRESS=full) runs every variant; `make test` keeps one case per feature so that it stays
  * near its 20-minute budget on 2 cores. Specs branch on this flag, never on their own reading of the variable.
  */
object Regress {
  val full: Boolean = sys.env.get("RTACCEL_REGRESS").contains("full")
}
