package rtaccel.top

import org.scalatest.funsuite.AnyFunSuite
import rtaccel.config.{CacheParams, CachePolicy, Knobs, Pipelining, PlatformParams, Presets, TriTest}
import rtaccel.fp.FpFormat

/** The register fields the knob registry names (Knob.registers) against the register map and the configuration words
  * the board top encodes: each named field exists, and the read-only ones move when their knob does. */
class RegisterFieldsSpec extends AnyFunSuite {
  private def field(name: String): (RegMap.Reg, RegMap.Field) = {
    val Array(r, f) = name.split('.')
    val reg = RegMap.fixed.find(_.name == r).getOrElse(fail(s"$name: no register $r"))
    (reg, reg.fields.find(_.name == f).getOrElse(fail(s"$name: $r has no field $f")))
  }
  private def value(p: PlatformParams, name: String): BigInt = {
    val (r, f) = field(name)
    val w = RtAccelTop.configWords(p).find(_._1 == r).getOrElse(fail(s"$name: ${r.name} is not a configuration word"))._2
    (w >> f.lsb) & ((BigInt(1) << f.width) - 1)
  }

  test("every field a knob names is in the register map") {
    for (k <- Knobs.all; n <- k.registers) field(n)
    assert(Knobs.all.count(_.registers.nonEmpty) >= 20, "most knobs shaping the circuit are readable by the host")
  }

  test("a read-only configuration field moves with its knob (each knob against a platform that differs in it alone)") {
    val base = Presets.paper2017.copy(primCache = CacheParams(64, 1, CachePolicy.Dm))
    val changed: Map[String, PlatformParams] = Map(
      "M" -> base.copy(m = 8), "TUS" -> base.copy(tus = 8), "IUS" -> base.copy(ius = 2), "STACK" -> base.copy(stackDepth = 16),
      "RESP_ORDER" -> base.copy(respByPath = true), "RAY_STORE" -> base.copy(rayStore = true), "TAG_FORWARD" -> base.copy(tagForward = true),
      "NODE_BANKS" -> base.copy(nodeBanks = 2, ius = 2, respByPath = true, respTagged = true), "MEM_RETRIES" -> base.copy(memRetries = 2),
      "BOX_FORMAT" -> base.copy(boxFormat = FpFormat(6, 9)), "TRI_TEST" -> base.copy(triTest = TriTest.Watertight),
      "TRI_FORMAT" -> base.copy(triFormat = FpFormat.fp64), "TRI_II" -> base.copy(triInterval = 2), "BOX_II" -> base.copy(boxInterval = 2), "NODE_FORMAT" -> base.copy(nodeQuantBits = 8),
      "PRIM_FORMAT" -> base.copy(primPacked = true), "PIPELINE" -> base.copy(pipelining = Pipelining.parse("4")),
      "NODE_CACHE" -> base.copy(nodeCache = base.nodeCache.copy(entries = 1024)), "NODE_WAYS" -> base.copy(nodeCache = CacheParams(8192, 2, CachePolicy.Lru)),
      "NODE_POLICY" -> base.copy(nodeCache = base.nodeCache.copy(policy = CachePolicy.Bf)),
      "PRIM_CACHE" -> base.copy(primCache = base.primCache.copy(entries = 256)), "PRIM_WAYS" -> base.copy(primCache = CacheParams(64, 2, CachePolicy.Lru)),
      "PRIM_POLICY" -> base.copy(primCache = CacheParams(64, 1, CachePolicy.Lru)))
    // RW registers hold a reset value the host may overwrite: their fields are checked by RegFileSpec, not here
    val rw = Set("MAX_STEPS", "MAX_LEVEL")
    val readOnly = Knobs.all.filter(k => k.registers.nonEmpty && !rw(k.make))
    for (k <- readOnly) {
      val p = changed.getOrElse(k.make, fail(s"${k.make}: no changed platform in this test"))
      assert(k.registers.exists(n => value(p, n) != value(base, n)), s"${k.make}: none of ${k.registers.mkString(", ")} changed")
    }
    for (k <- Knobs.all.filter(k => rw(k.make))) assert(k.registers.forall(n => field(n)._1.access == RegMap.RW), k.make)
  }
}
