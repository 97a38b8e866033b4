package rtaccel.area

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite

/** The timing proxy's parts on fixed inputs: ltp's text, a hand-made netlist, the longest-path walk. */
class LevelsSpec extends AnyFunSuite {
  test("ltp's report gives the cells on the longest path of each module") {
    val text =
      """3. Executing LTP pass (find longest path).
        |
        |Longest topological path in sub (length=11):
        |    0: \b [16]
        |    1: $auto$alumacc.cc:485:replace_alu$1882.B [0] (via $mul$t.v:2$2.sliceB[0].mul)
        |   11: \q [28] (via $auto$ff.cc:266:slice$2941)
        |
        |Longest topological path in \BoxPipe (length=42):
        |    0: \io_in_a [3]
        |""".stripMargin
    assert(Levels.parseLtp(text) == Map("sub" -> 11, "BoxPipe" -> 42))
    assert(Levels.parseLtp("no path here") == Map.empty)
  }

  test("the longest path adds the weights of a chain and takes the deeper of two branches") {
    // 0 <- 1 <- 2 (weights 1,1,1) and 0 <- 3 (weight 0): 3 levels; a cell read by two others is counted once per path
    assert(Levels.longest(Array(1, 1, 1, 0), Array(Array(1, 3), Array(2), Array(), Array())) == 3)
    assert(Levels.longest(Array(), Array()) == 0)
    // a loop (never in firtool output) is broken instead of hanging
    assert(Levels.longest(Array(1, 1), Array(Array(1), Array(0))) == 2)
  }

  test("LUTs count, carry and wide muxes pass the path on, flip-flops and submodules cut it") {
    // in -> LUT6 -> CARRY4 -> LUT2 -> FDRE -> LUT3 -> out, and a submodule between LUT2 and another LUT
    def cell(t: String, ins: Map[String, Seq[Int]], outs: Map[String, Seq[Int]]) = ujson.Obj("type" -> t,
      "port_directions" -> ujson.Obj.from((ins.keys.map(_ -> ujson.Str("input")) ++ outs.keys.map(_ -> ujson.Str("output"))).toSeq),
      "connections" -> ujson.Obj.from((ins ++ outs).map { case (p, b) => p -> ujson.Arr.from(b.map(ujson.Num(_))) }.toSeq))
    val top = ujson.Obj("attributes" -> ujson.Obj(), "cells" -> ujson.Obj(
      "l1" -> cell("LUT6", Map("I0" -> Seq(2)), Map("O" -> Seq(3))),
      "c1" -> cell("CARRY4", Map("S" -> Seq(3)), Map("CO" -> Seq(4))),
      "m1" -> cell("MUXF7", Map("I0" -> Seq(4)), Map("O" -> Seq(5))),
      "l2" -> cell("LUT2", Map("I0" -> Seq(5)), Map("O" -> Seq(6))),
      "f1" -> cell("FDRE", Map("D" -> Seq(6)), Map("Q" -> Seq(7))),
      "l3" -> cell("LUT3", Map("I0" -> Seq(7)), Map("O" -> Seq(8))),
      "u" -> cell("Sub", Map("a" -> Seq(6)), Map("y" -> Seq(9))),
      "l4" -> cell("LUT1", Map("I0" -> Seq(9)), Map("O" -> Seq(10)))))
    val sub = ujson.Obj("cells" -> ujson.Obj("x" -> cell("LUT4", Map("I0" -> Seq(2)), Map("O" -> Seq(3)))))
    val box = ujson.Obj("attributes" -> ujson.Obj("blackbox" -> "00000000000000000000000000000001"), "cells" -> ujson.Obj())
    val f = Files.createTempFile("netlist", ".json")
    Files.writeString(f, ujson.write(ujson.Obj("modules" -> ujson.Obj("Top" -> top, "\\Sub" -> sub, "LUT6" -> box))))
    assert(Levels.ofNetlist(f) == Map("Top" -> 2, "Sub" -> 1))
  }
}
