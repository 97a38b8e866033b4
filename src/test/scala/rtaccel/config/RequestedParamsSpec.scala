package rtaccel.config

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.TestScenes
import rtaccel.cli.{Args, Cli}
import rtaccel.fp.FpFormat
import rtaccel.io.InputError

/** What the user asks for (RequestedParams) against what a circuit is built from (PlatformParams): the parts left to
  * a scene stay requests until a scene resolves them, and the commands without a scene refuse them by name. */
class RequestedParamsSpec extends AnyFunSuite {
  private def request(kv: (String, String)*) = Cli.request(Args(kv.toMap))

  test("the parts only a scene settles are requests, not placeholder values in the platform") {
    val r = request("config" -> "paper2017", "box-format" -> "m10", "node-format" -> "fit")
    assert(r.boxFit.contains(10) && r.nodeFit && !r.fitWidths && !r.stackGiven)
    assert(r.base.boxFormat == Presets.paper2017.boxFormat, "the preset's format until the scene fits one")
    assert(r.unfitted.boxFormat == FpFormat(8, 10), "a fit starts from the widest exponent")
    val e = request("config" -> "paper2017", "box-format" -> "e5m10", "stack-depth" -> "9")
    assert(e.boxFit.isEmpty && e.base.boxFormat == FpFormat(5, 10) && e.unfitted == e.base && e.stackGiven && e.base.stackDepth == 9)
    assert(request().fitWidths && request("config" -> "fit").fitWidths && !request("config" -> "small").fitWidths)
  }

  test("a command without a scene takes a preset as asked and refuses each part left to a scene, naming what to give") {
    val p = request("config" -> "small", "tus" -> "2", "box-format" -> "bf16").withoutScene("make verilog")
    assert(p.tus == 2 && p.boxFormat == FpFormat.parse("bf16") && p.name == "small")
    def refusal(kv: (String, String)*) = intercept[InputError](request(kv: _*).withoutScene("make area")).getMessage
    val fit = refusal("config" -> "fit")
    assert(fit.contains("make area needs a preset") && fit.contains("paper2017|paper2017-lrp|small"), fit)
    val box = refusal("config" -> "small", "box-format" -> "m7")
    assert(box.contains("BOX_FORMAT=m7") && box.contains("make area does not read") && box.contains("e<E>m7"), box)
    val node = refusal("config" -> "small", "node-format" -> "fit")
    assert(node.contains("NODE_FORMAT=fit") && node.contains("q<bits> or full"), node)
    // and through the entry point of those commands, which also refuses caches the RTL cannot build
    assert(intercept[InputError](Cli.preset(Args(Map("config" -> "small", "box-format" -> "m7")), "make timing")).getMessage.contains("make timing"))
    val ways = intercept[InputError](Cli.preset(Args(Map("config" -> "small", "node-cache" -> "64", "node-ways" -> "8")), "make verilog")).getMessage
    assert(ways.contains("NODE_WAYS=8") && ways.contains("state bits"), ways)
  }

  test("CLOCK_MHZ=fmax is refused for a box format the scene fits: the measured clock belongs to one circuit") {
    val e = intercept[InputError](request("config" -> "small", "box-format" -> "m10", "clock-mhz" -> "fmax")).getMessage
    assert(e.contains("BOX_FORMAT=m10") && e.contains("CLOCK_MHZ=fmax"), e)
  }

  test("a scene resolves the request: the exponent fitted, a given format kept, CONFIG=fit's widths and an explicit STACK") {
    val scene = TestScenes.soup(3, 300); val rays = TestScenes.rays(5, 200)
    val fitted = Cli.build(scene, rays, request("config" -> "small", "box-format" -> "m10")).params
    assert(fitted.boxFormat.manBits == 10 && fitted.boxFormat.expBits <= 8 && BoxRange.represents(fitted.boxFormat, BoxRange.depth(scene, rays)))
    // the same fit by hand: the widths BoxRange allows, judged by the node fetches FormatFit measures
    val exact = Cli.build(scene, rays, request("config" -> "small", "box-format" -> s"e${fitted.boxFormat.expBits}m10")).params
    assert(exact.boxFormat == fitted.boxFormat && exact.copy(name = "") == fitted.copy(name = ""))
    val fit = Cli.build(scene, rays, request("config" -> "fit", "stack-depth" -> "2")).params
    assert(fit.stackDepth == 2 && fit.refs.primIndexBits == Fit.bitsFor(299), "STACK= kept as given below the tree's bound; widths fitted")
  }
}
