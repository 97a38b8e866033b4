package rtaccel.area

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite

/** The wrapper's reading of firtool's port list (no tools): continuation lines inherit direction and width. */
class TimingWrapSpec extends AnyFunSuite {
  test("ports: a line without a direction continues the previous declaration; the wrapper wires every bit") {
    val f = Files.createTempFile("wrap", ".sv")
    Files.writeString(f, """// header
      |module Other(input x, output y);
      |endmodule
      |module Unit(
      |  input         clock,
      |                reset,
      |  input  [31:0] io_a,
      |                io_b,
      |  output        io_ready,
      |  output [7:0]  io_y // a comment
      |);
      |endmodule
      |""".stripMargin)
    val ps = TimingWrap.ports(f, "Unit")
    assert(ps == Seq(TimingWrap.Port("clock", true, 1), TimingWrap.Port("reset", true, 1), TimingWrap.Port("io_a", true, 32),
      TimingWrap.Port("io_b", true, 32), TimingWrap.Port("io_ready", false, 1), TimingWrap.Port("io_y", false, 8)))
    val (v, ff) = TimingWrap.verilog("Unit", ps)
    assert(ff == 65 + 9, v) // reset + 2 x 32 in, 1 + 8 out
    for (c <- Seq(".clock(clk)", ".reset(in_sr[0:0])", ".io_a(in_sr[32:1])", ".io_b(in_sr[64:33])", ".io_ready(y[0:0])", ".io_y(y[8:1])"))
      assert(v.contains(c), s"$c in\n$v")
    assert(v.contains("module RtaccelTimingWrap(input clk, input si, input ld, output so);"))
    val e = intercept[rtaccel.io.InputError](TimingWrap.ports(f, "Missing"))
    assert(e.getMessage.contains("no module Missing"))
    Files.delete(f)
  }
}
