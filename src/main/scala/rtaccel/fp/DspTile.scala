package rtaccel.fp

import chisel3._
import chisel3.util._

/** An unsigned product of up to 18 x 18 bits with its operands and its result in registers: two cycles, and no fabric
  * logic between the registers (`DspTile.apply` puts a third, in the fabric, in front). Where the family's DSP block
  * has such registers of its own (DspShape.registered:
  * ECP5's MULT18X18D with REG_INPUTA/B and REG_OUTPUT on CLK0), synthesis gets the block with them, so neither the
  * block's multiply nor its routes share a stage with fabric logic (an unregistered MULT18X18D alone is 8.57 ns on
  * the LFE5UM5G -8, docs/timing.md), and the registers cost no flip-flops. Simulators get the same registers in
  * Verilog (the block is chosen under `SYNTHESIS`, which Yosys defines).
  */
class DspTile18 extends BlackBox with HasBlackBoxInline {
  val io = IO(new Bundle {
    val CLK = Input(Clock())
    val A = Input(UInt(DspTile.Bits.W))
    val B = Input(UInt(DspTile.Bits.W))
    val P = Output(UInt((2 * DspTile.Bits).W))
  })
  override def desiredName: String = "rtaccel_dsp_tile18"
  setInline(s"$desiredName.sv", DspTile.verilog(desiredName))
}

object DspTile {
  /** Operand width of the block (MULT18X18D, unsigned inputs). */
  val Bits: Int = 18
  /** Cycles from the operands to the product: a fabric register, the block's input registers and its output
    * register. The fabric register holds the operands with no logic after it, so the placer can put it near the
    * block: the blocks sit in rows across the die, and the route from the operands' logic into a block's input
    * registers was TriPipe's routed critical path on ECP5 (7.65 ns, 7.01 ns of it routing, with 108 blocks in use).
    */
  val latency: Int = 3

  /** a * b (each at most 18 bits), `latency` cycles later. */
  def apply(a: UInt, b: UInt): UInt = {
    require(a.getWidth <= Bits && b.getWidth <= Bits, s"a DSP tile multiplies at most $Bits x $Bits bits (got ${a.getWidth} x ${b.getWidth})")
    val t = Module(new DspTile18)
    t.io.CLK := Module.clock
    t.io.A := RegNext(a.pad(Bits)); t.io.B := RegNext(b.pad(Bits))
    t.io.P(a.getWidth + b.getWidth - 1, 0)
  }

  private[fp] def verilog(name: String): String = {
    def bus(port: String, sig: String, n: Int) = (0 until n).map(i => s".$port$i($sig[$i])")
    def tie(port: String, n: Int, v: String) = (0 until n).map(i => s".$port$i($v)")
    val conns = bus("A", "A", Bits) ++ bus("B", "B", Bits) ++ tie("C", Bits, "1'b0") ++
      Seq(".SIGNEDA(1'b0)", ".SIGNEDB(1'b0)", ".SOURCEA(1'b0)", ".SOURCEB(1'b0)", ".CLK0(CLK)") ++
      tie("CLK", 4, "1'b0").drop(1) ++ Seq(".CE0(1'b1)") ++ tie("CE", 4, "1'b0").drop(1) ++ tie("RST", 4, "1'b0") ++
      bus("P", "P", 2 * Bits)
    s"""// An unsigned ${Bits} x ${Bits} product with registered operands and result (two cycles): rtaccel.fp.DspTile.
       |module $name (input CLK, input [${Bits - 1}:0] A, input [${Bits - 1}:0] B, output [${2 * Bits - 1}:0] P);
       |`ifdef SYNTHESIS
       |  MULT18X18D #(.REG_INPUTA_CLK("CLK0"), .REG_INPUTB_CLK("CLK0"), .REG_OUTPUT_CLK("CLK0"), .GSR("DISABLED")) block (
       |    ${conns.grouped(12).map(_.mkString(", ")).mkString(",\n    ")});
       |`else
       |  reg [${Bits - 1}:0] a_q, b_q;
       |  reg [${2 * Bits - 1}:0] p_q;
       |  always @(posedge CLK) begin
       |    a_q <= A;
       |    b_q <= B;
       |    p_q <= a_q * b_q;
       |  end
       |  assign P = p_q;
       |`endif
       |endmodule
       |""".stripMargin
  }
}
