package rtaccel.area

import java.nio.file.{Files, Path}
import rtaccel.io.InputError

/** The wrapper that makes a unit's routed clock its own: a unit alone has far more port bits than a package has
  * pins (BoxPipe: ~1,160 in), and an unconstrained pin path would be timed as I/O, not as the unit. So every
  * input bit of the unit comes from one long shift register fed by pin `si`, and every output bit loads (pin `ld`)
  * into a second one that shifts out on pin `so`: every path through the unit is register to register, nothing is
  * trimmed (every output reaches a pin) and nothing is a constant (every input toggles). The unit's `clock` is
  * the pin `clk`; its reset comes from the input chain like any other input.
  */
object TimingWrap {
  val module = "RtaccelTimingWrap"

  final case class Port(name: String, input: Boolean, width: Int)

  private val header = """(?s)\bmodule\s+(\w+)\s*\((.*?)\);""".r
  private val line = """^\s*(input|output|inout)?\s*(?:\[(\d+):(\d+)\])?\s*([A-Za-z_][A-Za-z0-9_$]*)\s*,?\s*$""".r

  /** The ports of `top` from its emitted file: firtool writes one per line, a line without a direction (and
    * width) continuing the previous line's declaration (`input clock,` then `reset,`).
    */
  def ports(file: Path, top: String): Seq[Port] = {
    val text = Files.readString(file)
    val body = header.findAllMatchIn(text).find(_.group(1) == top).map(_.group(2))
      .getOrElse(throw new InputError(s"$file declares no module $top"))
    var dir: Option[String] = None; var width = 1
    body.linesIterator.map(_.replaceAll("//.*", "")).filter(_.trim.nonEmpty).map {
      case line(d, hi, lo, name) =>
        if (d != null) { dir = Some(d); width = if (hi == null) 1 else hi.toInt - lo.toInt + 1 }
        dir match {
          case Some("inout") => throw new InputError(s"$top has an inout port ($name): the timing wrapper drives inputs and loads outputs only")
          case Some(x) => Port(name, x == "input", width)
          case None => throw new InputError(s"cannot read the port list of $top in $file at '$name'")
        }
      case other => throw new InputError(s"cannot read the port list of $top in $file: '${other.trim}'")
    }.toSeq
  }

  /** The wrapper's Verilog around `top` with `ports`; (text, shift-register flip-flops it adds). */
  def verilog(top: String, ports: Seq[Port]): (String, Int) = {
    val clocks = ports.filter(p => p.input && p.name == "clock")
    val ins = ports.filter(p => p.input && p.name != "clock")
    val outs = ports.filter(!_.input)
    if (outs.isEmpty) throw new InputError(s"$top has no outputs: the routed design would be empty")
    // two bits at least, so that the shift expressions below stay legal for a one-bit chain
    val nIn = math.max(2, ins.map(_.width).sum); val nOut = math.max(2, outs.map(_.width).sum)
    def slices(ps: Seq[Port], vec: String): Seq[String] =
      ps.scanLeft(0)(_ + _.width).zip(ps).map { case (lo, p) => s"    .${p.name}($vec[${lo + p.width - 1}:$lo])" }
    val conns = clocks.map(p => s"    .${p.name}(clk)") ++ slices(ins, "in_sr") ++ slices(outs, "y")
    val text =
      s"""// rtaccel timing wrapper (rtaccel.area.TimingWrap): every input of $top from a shift register, every output
         |// into one, so that every path nextpnr times is register to register.
         |module $module(input clk, input si, input ld, output so);
         |  reg  [${nIn - 1}:0] in_sr;
         |  reg  [${nOut - 1}:0] out_sr;
         |  wire [${nOut - 1}:0] y;
         |  always @(posedge clk) begin
         |    in_sr <= {in_sr[${nIn - 2}:0], si};
         |    out_sr <= ld ? y : {out_sr[${nOut - 2}:0], in_sr[${nIn - 1}]};
         |  end
         |  assign so = out_sr[${nOut - 1}];
         |${if (outs.map(_.width).sum < nOut) "  assign y[1] = 1'b0;\n" else ""}  $top dut (
         |${conns.mkString(",\n")}
         |  );
         |endmodule
         |""".stripMargin
    (text, nIn + nOut)
  }
}
