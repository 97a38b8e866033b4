package rtaccel.top

import rtaccel.config.PlatformParams

/** RegMap as a C header and a Python module for host drivers (written by make verilog beside the Verilog):
  * offsets, access, field positions and masks, the counter list, and the configuration words this build
  * reads back, so a driver can refuse a bitstream that is not the configuration its image was packed for.
  */
object RegHeaders {
  private def ident(s: String) = s.toUpperCase.replaceAll("[^A-Z0-9]", "_")
  private def hex(v: BigInt) = f"0x${v.toLong}%08x"

  def c(p: PlatformParams, version: String): String = {
    val sb = new StringBuilder
    sb ++= s"/* rtaccel register map ${RegMap.VersionMajor}.${RegMap.VersionMinor} for configuration '${p.name}' " +
      s"(rtaccel $version). Generated from rtaccel.top.RegMap; do not edit. */\n"
    sb ++= "#ifndef RTACCEL_REGS_H\n#define RTACCEL_REGS_H\n\n"
    sb ++= s"#define RTACCEL_REGMAP_VERSION_MAJOR ${RegMap.VersionMajor}u\n#define RTACCEL_REGMAP_VERSION_MINOR ${RegMap.VersionMinor}u\n"
    sb ++= s"#define RTACCEL_MAGIC ${hex(RegMap.Magic)}u\n#define RTACCEL_COUNTER_BASE ${hex(RegMap.CounterBase)}u\n"
    sb ++= s"#define RTACCEL_COUNTER_COUNT ${RtAccelTop.counterNames.length}u\n\n"
    for (r <- RegMap.all(RtAccelTop.counterNames)) {
      sb ++= s"#define RTACCEL_${ident(r.name)} ${hex(r.offset)}u /* ${r.access.code}: ${r.doc} */\n"
      for (f <- r.fields) {
        sb ++= s"#define RTACCEL_${ident(r.name)}_${ident(f.name)}_LSB ${f.lsb}u\n"
        sb ++= s"#define RTACCEL_${ident(r.name)}_${ident(f.name)}_MASK ${hex(f.mask)}u" +
          (if (f.doc.nonEmpty) s" /* ${f.doc} */\n" else "\n")
      }
    }
    sb ++= "\n/* counter indices: counter i is RTACCEL_COUNTER_BASE + 8 i (LO, snapshots), + 4 (HI) */\n"
    for ((n, i) <- RtAccelTop.counterNames.zipWithIndex) sb ++= s"#define RTACCEL_COUNTER_${ident(n)} ${i}u\n"
    sb ++= s"\n/* the read-only configuration words of this build ('${p.name}') */\n"
    for ((r, v) <- RtAccelTop.configWords(p)) sb ++= s"#define RTACCEL_EXPECT_${ident(r.name)} ${hex(v)}u\n"
    sb ++= "\n#endif /* RTACCEL_REGS_H */\n"
    sb.toString
  }

  def python(p: PlatformParams, version: String): String = {
    val sb = new StringBuilder
    sb ++= s"\"\"\"rtaccel register map ${RegMap.VersionMajor}.${RegMap.VersionMinor} for configuration '${p.name}' " +
      s"(rtaccel $version).\n\nGenerated from rtaccel.top.RegMap; do not edit.\n\"\"\"\n"
    sb ++= s"VERSION_MAJOR = ${RegMap.VersionMajor}\nVERSION_MINOR = ${RegMap.VersionMinor}\n"
    sb ++= s"MAGIC = ${hex(RegMap.Magic)}\nCOUNTER_BASE = ${hex(RegMap.CounterBase)}\nCONFIG = ${ujson.write(ujson.Str(p.name))}\n\n"
    sb ++= "# name: (offset, access, doc)\nREGS = {\n"
    for (r <- RegMap.all(RtAccelTop.counterNames))
      sb ++= s"    ${ujson.write(ujson.Str(r.name))}: (${hex(r.offset)}, ${ujson.write(ujson.Str(r.access.code))}, ${ujson.write(ujson.Str(r.doc))}),\n"
    sb ++= "}\n\n# register: {field: (lsb, width)}\nFIELDS = {\n"
    for (r <- RegMap.all(RtAccelTop.counterNames) if r.fields.nonEmpty)
      sb ++= s"    ${ujson.write(ujson.Str(r.name))}: {" + r.fields.map(f => s"${ujson.write(ujson.Str(f.name))}: (${f.lsb}, ${f.width})").mkString(", ") + "},\n"
    sb ++= "}\n\n# counter i: LO at COUNTER_BASE + 8 i (reading it snapshots the counter), HI at + 4\nCOUNTERS = [\n"
    for (n <- RtAccelTop.counterNames) sb ++= s"    ${ujson.write(ujson.Str(n))},\n"
    sb ++= "]\n\n# read-only configuration words of this build\nEXPECT = {\n"
    for ((r, v) <- RtAccelTop.configWords(p)) sb ++= s"    ${ujson.write(ujson.Str(r.name))}: ${hex(v)},\n"
    sb ++= "}\n\n\ndef offset(name):\n    return REGS[name][0]\n\n\ndef counter_offset(name):\n    return COUNTER_BASE + 8 * COUNTERS.index(name)\n"
    sb.toString
  }

  /** The register table of docs/registers.md (between its BEGIN/END markers; RegHeadersSpec keeps it current). */
  def markdown: String = {
    val sb = new StringBuilder("| offset | register | access | meaning | fields (bits) |\n|---|---|---|---|---|\n")
    for (r <- RegMap.fixed)
      sb ++= f"| 0x${r.offset}%03x | `${r.name}` | ${r.access.code} | ${r.doc} | " +
        r.fields.map(f => s"`${f.name}` [${if (f.width == 1) f.lsb.toString else s"${f.lsb + f.width - 1}:${f.lsb}"}]" +
          (if (f.doc.nonEmpty) s" ${f.doc}" else "")).mkString("; ") + " |\n"
    for ((n, i) <- RtAccelTop.counterNames.zipWithIndex)
      sb ++= f"| 0x${RegMap.CounterBase + 8 * i}%03x | `CNT_${n.toUpperCase}_LO`/`_HI` | RO | counter `$n` (64-bit) | |\n"
    sb.toString
  }
}
