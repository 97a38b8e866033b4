package chiseltest.formal.backends

/** chiseltest 6 keeps its Yices 2 engine annotation package-private; this names it for rtaccel.formal.FormalChecks
  * (the only reason this file lives in chiseltest's package).
  */
object Engines {
  val yices2: firrtl2.annotations.Annotation = Yices2EngineAnnotation
}
