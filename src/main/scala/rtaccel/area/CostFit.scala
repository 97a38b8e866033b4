package rtaccel.area

import org.apache.commons.math3.linear.{Array2DRowRealMatrix, ArrayRealVector, SingularValueDecomposition}
import rtaccel.config.PlatformParams

/** The cost model's fit (make cost-model, cli.CostFit): least squares of each unit's resources on its features over
  * real syntheses, and the error measure its report uses.
  */
object CostFit {
  /** One configuration of the calibration plan: its platform, the module synthesized and the family. */
  final case class Point(name: String, p: PlatformParams, top: String, family: String)

  /** Relative error of the model against Yosys; NaN where both are 0 (nothing to be wrong about). */
  def relErr(model: Double, yosys: Double): Double =
    if (yosys == 0) { if (model == 0) Double.NaN else 1.0 } else (model - yosys) / yosys

  /** Least squares per unit and resource over the training syntheses that contain the unit. The SVD solve is
    * the minimum-norm solution, so a feature the training set never varies gets no weight instead of failing.
    */
  def fit(trained: Seq[(Point, Synthesis)]): Map[String, Map[String, Map[String, Double]]] = {
    val samples = trained.flatMap { case (pt, s) =>
      CostModel.decompose(s).toSeq.flatMap { case (u, (r, n)) => CostModel.units.find(_.name == u).map(un => (un, pt.p, r, n)) }
    }
    samples.groupBy(_._1).map { case (u, ss) =>
      u.name -> CostModel.resources.map { res =>
        val rows = ss.map { case (_, p, r, n) => (CostModel.featuresFor(u, res, u.features(p)), CostModel.get(r, res) / (if (u.perInstance) n else 1)) }
        res -> solve(rows)
      }.toMap
    }
  }

  def solve(rows: Seq[(Seq[(String, Double)], Double)]): Map[String, Double] = {
    val names = rows.head._1.map(_._1)
    // columns that never vary from zero carry nothing; the rest are scaled to unit size for a well-posed solve
    val used = names.indices.filter(j => rows.exists(_._1(j)._2 != 0))
    if (used.isEmpty) return names.map(_ -> 0.0).toMap
    val norm = used.map(j => rows.map(r => math.abs(r._1(j)._2)).max)
    val x = new Array2DRowRealMatrix(rows.map(r => used.zip(norm).map { case (j, s) => r._1(j)._2 / s }.toArray).toArray)
    val y = new ArrayRealVector(rows.map(_._2).toArray)
    val b = new SingularValueDecomposition(x).getSolver.solve(y)
    names.map(_ -> 0.0).toMap ++ used.zip(norm).zipWithIndex.map { case ((j, s), i) => names(j) -> b.getEntry(i) / s }
  }

}
