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

  private def cell(t: String, ins: Map[String, Seq[Int]], outs: Map[String, Seq[Int]], params: Map[String, String] = Map.empty) =
    ujson.Obj("type" -> t,
      "port_directions" -> ujson.Obj.from((ins.keys.map(_ -> ujson.Str("input")) ++ outs.keys.map(_ -> ujson.Str("output"))).toSeq),
      "connections" -> ujson.Obj.from((ins ++ outs).map { case (p, b) => p -> ujson.Arr.from(b.map(ujson.Num(_))) }.toSeq),
      "parameters" -> ujson.Obj.from(params.map { case (k, v) => k -> ujson.Str(v) }.toSeq))
  private def module(ports: Seq[(String, String, Seq[Int])], cells: (String, ujson.Obj)*) = ujson.Obj("attributes" -> ujson.Obj(),
    "ports" -> ujson.Obj.from(ports.map { case (n, d, b) => n -> ujson.Obj("direction" -> d, "bits" -> ujson.Arr.from(b.map(ujson.Num(_)))) }),
    "cells" -> ujson.Obj.from(cells))
  private def lut(i: Int, o: Int) = cell("LUT4", Map("I0" -> Seq(i)), Map("O" -> Seq(o)))
  private def ff(d: Int, q: Int) = cell("FDRE", Map("D" -> Seq(d)), Map("Q" -> Seq(q)))
  private val zero = "00000000000000000000000000000000"; private val one = "00000000000000000000000000000001"

  test("LUTs count, carry and wide muxes pass the path on, flip-flops cut it") {
    // in -> LUT6 -> CARRY4 -> MUXF7 -> LUT2 -> FDRE -> LUT3 -> out: 2 levels to the flip-flop, 1 after it
    val top = ujson.Obj("attributes" -> ujson.Obj(), "cells" -> ujson.Obj(
      "l1" -> cell("LUT6", Map("I0" -> Seq(2)), Map("O" -> Seq(3))),
      "c1" -> cell("CARRY4", Map("S" -> Seq(3)), Map("CO" -> Seq(4))),
      "m1" -> cell("MUXF7", Map("I0" -> Seq(4)), Map("O" -> Seq(5))),
      "l2" -> cell("LUT2", Map("I0" -> Seq(5)), Map("O" -> Seq(6))),
      "f1" -> cell("FDRE", Map("D" -> Seq(6)), Map("Q" -> Seq(7))),
      "l3" -> cell("LUT3", Map("I0" -> Seq(7)), Map("O" -> Seq(8)))))
    val box = ujson.Obj("attributes" -> ujson.Obj("blackbox" -> one), "cells" -> ujson.Obj())
    val f = Files.createTempFile("netlist", ".json")
    Files.writeString(f, ujson.write(ujson.Obj("modules" -> ujson.Obj("Top" -> top, "LUT6" -> box))))
    assert(Levels.ofNetlist(f, 4).levels == Map("Top" -> 2))
  }

  test("a path through submodule ports counts the submodule's part: register to output, input through to output, input to register") {
    // Sub: a (input) -> 2 LUTs -> y (output); a -> 1 LUT -> FF; FF -> 3 LUTs -> z (output)
    val sub = module(Seq(("a", "input", Seq(2)), ("y", "output", Seq(4)), ("z", "output", Seq(9))),
      "l1" -> lut(2, 3), "l2" -> lut(3, 4), "l3" -> lut(2, 5), "f" -> ff(5, 6), "l4" -> lut(6, 7), "l5" -> lut(7, 8), "l6" -> lut(8, 9))
    // Top: FF -> LUT -> Sub.a; Sub.y -> LUT -> FF; Sub.z -> 2 LUTs -> FF
    val top = module(Seq(), "f1" -> ff(20, 10), "la" -> lut(10, 11),
      "u" -> cell("\\Sub", Map("a" -> Seq(11)), Map("y" -> Seq(12), "z" -> Seq(13))),
      "lb" -> lut(12, 14), "f2" -> ff(14, 15), "lc" -> lut(13, 16), "ld" -> lut(16, 17), "f3" -> ff(17, 20))
    val got = Levels.ofModules(Map("Top" -> top, "Sub" -> sub), 4)
    // alone, Sub's deepest is its own 3 LUTs; in Top: 1 + 2 (through a -> y) + 1 = 4, and 3 (FF -> z) + 2 = 5
    assert(got.levels == Map("Sub" -> 3, "Top" -> 5))
    // the path is reported by the nets the source named, crossing the submodule by its instance and port; a name
    // Yosys made (`$...`) or hid is left out
    top("netnames") = ujson.Obj(
      "state" -> ujson.Obj("hide_name" -> 0, "bits" -> ujson.Arr(20)),
      "zz" -> ujson.Obj("hide_name" -> 0, "bits" -> ujson.Arr(16, 17)),
      "$abc$1" -> ujson.Obj("hide_name" -> 1, "bits" -> ujson.Arr(13)),
      "hidden" -> ujson.Obj("hide_name" -> 1, "bits" -> ujson.Arr(14)))
    assert(Levels.ofModules(Map("Top" -> top, "Sub" -> sub), 4).paths("Top") == Seq("u.z", "zz[0]", "zz[1]"))
    // no LUT on any path: no levels and no path
    assert(Levels.ofModules(Map("M" -> module(Seq(), "f1" -> ff(1, 2), "f2" -> ff(2, 1))), 4) == Levels.Result(Map("M" -> 0), Map("M" -> Nil)))
    // the first proxy cut paths at submodule instances: without them Top would read 2
    val flat = module(Seq(), "f1" -> ff(20, 10), "la" -> lut(10, 11), "lb" -> lut(12, 14), "f2" -> ff(14, 15), "lc" -> lut(13, 16), "ld" -> lut(16, 17), "f3" -> ff(17, 20))
    assert(Levels.ofModules(Map("Top" -> flat), 4).levels == Map("Top" -> 2))
  }

  test("an unregistered DSP block is its family's levels plus its post-adder; registered ports cut the path") {
    def dsp(a: Int, p: Int, regs: String, pcin: Option[Int] = None, pcout: Option[Int] = None) =
      cell("DSP48E1", Map("A" -> Seq(a)) ++ pcin.map(b => "PCIN" -> Seq(b)), Map("P" -> Seq(p)) ++ pcout.map(b => "PCOUT" -> Seq(b)),
        Map("AREG" -> regs, "BREG" -> regs, "MREG" -> regs, "PREG" -> regs))
    // FF -> LUT -> DSP -> LUT -> FF with the family's 5 levels: 1 + 5 + 1 + 1
    val comb = module(Seq(), "f1" -> ff(9, 1), "l1" -> lut(1, 2), "d" -> dsp(2, 3, zero), "l2" -> lut(3, 4), "f2" -> ff(4, 9))
    assert(Levels.ofModules(Map("M" -> comb), 5).levels == Map("M" -> 8))
    // a second block cascaded behind the first adds its post-adder: 1 + 5 + 1 + 1 + 1
    val cas = module(Seq(), "f1" -> ff(9, 1), "l1" -> lut(1, 2), "d1" -> dsp(2, 3, zero, pcout = Some(5)),
      "d2" -> dsp(6, 7, zero, pcin = Some(5)), "l2" -> lut(7, 4), "f2" -> ff(4, 9))
    assert(Levels.ofModules(Map("M" -> cas), 5).levels == Map("M" -> 9))
    // with its input, M and P registers inside the block, the block's own multiply is the deepest (5 levels) and the
    // LUTs on each side stand alone
    val reg = module(Seq(), "f1" -> ff(9, 1), "l1" -> lut(1, 2), "l0" -> lut(2, 5), "d" -> dsp(5, 3, one), "l2" -> lut(3, 4), "f2" -> ff(4, 9))
    assert(Levels.ofModules(Map("M" -> reg), 5).levels == Map("M" -> 5))
    assert(Levels.ofModules(Map("M" -> reg), 1).levels == Map("M" -> 2))
    // ECP5's MULT18X18D as Yosys infers it (no register): the same rule with ECP5's levels
    val ecp = module(Seq(), "f1" -> ff(9, 1), "m" -> cell("MULT18X18D", Map("A0" -> Seq(1)), Map("P0" -> Seq(3)),
      Map("REG_INPUTA_CLK" -> "NONE", "REG_INPUTB_CLK" -> "NONE", "REG_OUTPUT_CLK" -> "NONE", "REG_PIPELINE_CLK" -> "NONE")), "l2" -> lut(3, 4), "f2" -> ff(4, 9))
    assert(Levels.ofModules(Map("M" -> ecp), 3).levels == Map("M" -> 5))
  }

  test("an asynchronous LUT-RAM read is a level from its address; its write ends the path") {
    // FF -> LUT -> RAM64X1D.DPRA -> DPO -> LUT -> FF: 3 levels; FF -> 2 LUTs -> RAM64X1D.D (the write): 2
    val ram = cell("RAM64X1D", Map("DPRA0" -> Seq(2), "D" -> Seq(12), "WE" -> Seq(1)), Map("DPO" -> Seq(3), "SPO" -> Seq(13)))
    val m = module(Seq(), "f1" -> ff(9, 1), "l1" -> lut(1, 2), "r" -> ram, "l2" -> lut(3, 4), "f2" -> ff(4, 9),
      "l3" -> lut(1, 11), "l4" -> lut(11, 12))
    assert(Levels.ofModules(Map("M" -> m), 4).levels == Map("M" -> 3))
    // ECP5's distributed RAM reads the same way
    val dpr = cell("TRELLIS_DPR16X4", Map("RAD" -> Seq(2), "DI" -> Seq(12), "WAD" -> Seq(1)), Map("DO" -> Seq(3)))
    val e = module(Seq(), "f1" -> ff(9, 1), "l1" -> lut(1, 2), "r" -> dpr, "l2" -> lut(3, 4), "f2" -> ff(4, 9))
    assert(Levels.ofModules(Map("M" -> e), 3).levels == Map("M" -> 3))
  }
}
