package rtaccel.cli

import java.nio.file.Paths
import rtaccel.area.{Boards, CostModel, Synthesis}
import rtaccel.io.InputError

/** make max-tus BOARD=<name> [knobs]: the largest TU count of a configuration that fits the board, found with
  * the fitted cost model (a bisection: resources grow with TUs) and confirmed by one real synthesis at that
  * count (CONFIRM=0 skips it, e.g. for boards whose answer is hundreds of TUs). Exit 3 when not even one TU
  * fits or the synthesis disagrees with the model.
  */
object MaxTus {
  def main(args: Array[String]): Unit = Cli.run(args, Flags.maxTus)(main0)

  def main0(a: Args): Unit = {
    val t0 = System.nanoTime()
    val board = Boards.requireXilinx(Boards.byName(a.get("board", "xc5vlx330t"), a.opt("catalog").map(Paths.get(_)).getOrElse(Boards.defaultPath)), "make max-tus")
    val p0 = Cli.preset(a, "make max-tus")
    val model = CostModel.load(a.opt("cost-model").map(Paths.get(_)).getOrElse(CostModel.defaultPath))
    val hi = a.int("max", 1024)
    if (hi < 1 || hi > 1024) throw new InputError(s"--max must be 1..1024 (got $hi)")
    // IUS clusters: TUS moves in steps of IUS (every cluster has the same TUs)
    val step = p0.ius
    if (hi < step) throw new InputError(s"--max $hi is below IUS=$step; raise --max or lower IUS")
    def at(t: Int) = { val j = ujson.Obj.from(model.total(p0.copy(tus = t), board.family).map { case (k, v) => k -> ujson.Num(v) }); (j, Area.fits(j, board)) }
    if (at(step)._2.nonEmpty) {
      val (r, used, have) = at(step)._2.get
      throw new CheckFailed(Seq(f"not even $step TU${if (step > 1) "s" else ""} of '${p0.name}' fit${if (step > 1) "" else "s"} ${board.name}: $r $used%.0f > $have"))
    }
    // largest k in [1, hi / step] whose k * step TUs fit: fits(lo) holds, fits(top + 1) does not (or top = hi / step)
    var lo = 1; var top = hi / step
    while (lo < top) { val mid = (lo + top + 1) / 2; if (at(mid * step)._2.isEmpty) lo = mid else top = mid - 1 }
    val best = lo * step
    val limit = if (best + step <= hi) at(best + step)._2 else None
    System.err.println(f"[max-tus] cost model: ${best} TUs of '${p0.name}' fit ${board.name}" +
      limit.fold(s" (the most tried, --max $hi)")(l => f"; ${best + step} would need ${l._1} ${l._2}%.0f > ${l._3}"))
    val confirm = a.get("confirm", "1") != "0"
    val yosys = if (!confirm) None else {
      val p = p0.copy(tus = best)
      val out = Paths.get(a.get("out", s"build/max-tus/${p0.name}-${board.name}"))
      val s = Synthesis.of(p, board.family, "RtAccelTop", out.resolve("rtl"), Paths.get(a.get("cache", "build/area-cache")),
        line => System.err.println(s"[max-tus] $line"))
      val j = ujson.Obj.from(CostModel.resources.map(r => r -> ujson.Num(CostModel.get(s.total, r))))
      Some(j -> Area.fits(j, board))
    }
    val json = ujson.Obj("config" -> p0.name, "board" -> board.name, "family" -> board.family, "max_tus" -> best,
      "limit" -> limit.fold[ujson.Value](ujson.Null) { case (r, u, h) => ujson.Obj("tus" -> (best + step), "resource" -> r, "used" -> u, "available" -> h.toDouble) },
      "model" -> at(best)._1, "confirmed" -> yosys.fold[ujson.Value](ujson.Null)(y => ujson.Bool(y._2.isEmpty)),
      "yosys" -> yosys.fold[ujson.Value](ujson.Null)(_._1), "wall_s" -> (System.nanoTime() - t0) / 1e9, "rtaccel" -> Cli.version)
    println(ujson.write(json))
    yosys.flatMap(_._2).foreach { case (r, u, h) =>
      throw new CheckFailed(Seq(f"the synthesis of $best TUs does not fit ${board.name} ($r $u%.0f > $h): the cost model is optimistic here"))
    }
  }
}
