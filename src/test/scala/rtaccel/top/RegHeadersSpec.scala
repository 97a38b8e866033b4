package rtaccel.top

import java.nio.file.Files
import org.scalatest.funsuite.AnyFunSuite
import scala.sys.process._
import rtaccel.config.Presets

/** The generated host headers say what RegMap says: the C header compiles and its macros equal the map's
  * offsets and fields (checked by the C compiler itself), and the Python module imports with the same table.
  */
class RegHeadersSpec extends AnyFunSuite {
  private val p = Presets.paper2017Lrp
  private val dir = Files.createTempDirectory("regheaders")
  private val regs = RegMap.all(RtAccelTop.counterNames)
  private def ident(s: String) = s.toUpperCase.replaceAll("[^A-Z0-9]", "_")

  test("the C header compiles cleanly and every macro equals the register map") {
    Files.writeString(dir.resolve("rtaccel_regs.h"), RegHeaders.c(p, "test"))
    val asserts = regs.flatMap { r =>
      s"_Static_assert(RTACCEL_${ident(r.name)} == ${r.offset}u, \"${r.name}\");" +:
        r.fields.map(f => s"_Static_assert(RTACCEL_${ident(r.name)}_${ident(f.name)}_MASK == ${f.mask}u, \"${r.name}.${f.name}\");")
    } ++ RtAccelTop.counterNames.zipWithIndex.map { case (n, i) => s"_Static_assert(RTACCEL_COUNTER_${ident(n)} == ${i}u, \"$n\");" } ++
      RtAccelTop.configWords(p).map { case (r, v) => s"_Static_assert(RTACCEL_EXPECT_${ident(r.name)} == ${v}u, \"${r.name}\");" }
    Files.writeString(dir.resolve("check.c"), "#include \"rtaccel_regs.h\"\n" + asserts.mkString("\n") + "\nint main(void) { return 0; }\n")
    val log = new StringBuilder
    val code = Seq("cc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-fsyntax-only", "-I", dir.toString, dir.resolve("check.c").toString) !
      ProcessLogger(l => log ++= l + "\n", l => log ++= l + "\n")
    assert(code == 0, log.toString)
    assert(regs.length > 40, "the map lists the fixed registers and two words per counter")
  }

  test("the Python module imports and holds the same registers, fields, counters and configuration words") {
    Files.writeString(dir.resolve("rtaccel_regs.py"), RegHeaders.python(p, "test"))
    val out = Process(Seq("python3", "-c",
      "import json, rtaccel_regs as r; print(json.dumps({'regs': {k: v[0] for k, v in r.REGS.items()}, " +
        "'fields': r.FIELDS, 'counters': r.COUNTERS, 'expect': r.EXPECT, 'cnt': r.counter_offset('hits_out')}))"),
      dir.toFile).!!
    val j = ujson.read(out)
    assert(j("regs").obj.map { case (k, v) => k -> v.num.toInt }.toMap == regs.map(r => r.name -> r.offset).toMap)
    for (r <- regs; f <- r.fields) assert(j("fields")(r.name)(f.name).arr.map(_.num.toInt) == Seq(f.lsb, f.width), s"${r.name}.${f.name}")
    assert(j("counters").arr.map(_.str) == RtAccelTop.counterNames)
    assert(j("cnt").num.toInt == RegMap.CounterBase + 8 * RtAccelTop.counterNames.indexOf("hits_out"))
    for ((r, v) <- RtAccelTop.configWords(p)) assert(BigInt(j("expect")(r.name).num.toLong) == v, r.name)
  }

  test("docs/registers.md carries the register table of RegMap") {
    val doc = java.nio.file.Paths.get("docs/registers.md")
    val text = Files.readString(doc)
    val (begin, end) = ("<!-- BEGIN register table -->\n", "<!-- END register table -->")
    val i = text.indexOf(begin); val k = text.indexOf(end)
    assert(i >= 0 && k > i, "docs/registers.md lost its table markers")
    val current = text.substring(i + begin.length, k)
    if (sys.env.get("RTACCEL_UPDATE_DOCS").contains("1") && current != RegHeaders.markdown)
      Files.writeString(doc, text.substring(0, i + begin.length) + RegHeaders.markdown + text.substring(k))
    else assert(current == RegHeaders.markdown, "docs/registers.md differs from RegMap; run with RTACCEL_UPDATE_DOCS=1")
  }
}
