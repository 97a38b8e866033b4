"""make precision — every numerics option on one set of rays: accuracy, work, bandwidth, speed and cost.

One row per option (BOX_FORMAT x TRI_TEST, docs/numerics.md "The trade, measured"), all from the same golden rays.
An option is BOX_FORMAT:TRI_TEST[@TRI_FORMAT][:NODE_FORMAT[:PRIM_FORMAT]], e.g. fp32:mt, bf16:watertight:q8:packed,
fp32:mt@fp64 (Möller–Trumbore in binary64, t/u/v rounded to fp32; TRI_FORMAT defaults to fp32):
  accuracy   agreement with Embree as `make check` classifies it; hits that differ from the fp32 Möller–Trumbore
             baseline (another primitive, or the same with other t bits; the largest relative t difference) and
             the classes of those differences; hits a box test lost (the traversal against every
             triangle with the same triangle test and no boxes, on the first EXHAUSTIVE rays; 0 for conservative
             boxes); max relative t error against Embree;
  work       node fetches, box tests, primitive tests per ray (the reference traversal);
  bandwidth  node and primitive DRAM bytes per ray with and without the node cache, node-cache miss rate
             (every option here has the same node layout, so equal entries are equal BRAM);
  speed      RTL rays/s at the configured clock and memory (make simulate; off with --rtl 0);
  cost       LUT/FF/DSP/BRAM36 of the intersection unit from a real synthesis (--area yosys, cached per
             circuit); empty otherwise, never estimated.
Writes OUT/precision.csv (provenance line first) and OUT/precision.png (the table); one JSON line last. A row
whose RTL check failed is kept in the CSV with its failure, left out of the PNG, and the command exits 3.
"""
import json
import os

import numpy as np

from golden.check import classify
from golden.io import load_hits, load_rays, load_tris
from scenes.cli import ArgParser, run
from scenes.errors import UserError

from ..common import provenance_line, save_png, write_text
from ..explore.worker import JvmServer

DEFAULT_OPTIONS = ["fp32:mt", "fp24:mt", "fp16:mt", "bf16:mt", "fp32:watertight", "fp24:watertight",
                   "fp16:watertight", "bf16:watertight", "fp32:mt:q8", "fp32:mt:q12", "fp32:mt:full:packed",
                   "fp32:mt:q8:packed", "bf16:watertight:q8:packed"]
BASELINE = "fp32:mt"
COLUMNS = ["option", "box_format", "tri_test", "tri_format", "node_format", "prim_format", "rays", "agree", "classified", "unexplained", "max_rel_t_err",
           "differ_from_baseline", "prim_differs_from_baseline", "max_rel_t_vs_baseline", "differ_classes", "exhaustive_rays", "lost_hits",
           "node_fetches_per_ray", "box_tests_per_ray", "prim_tests_per_ray",
           "node_bytes_per_ray", "prim_bytes_per_ray", "node_bytes_per_ray_nocache", "prim_bytes_per_ray_nocache",
           "node_miss_rate", "rtl_rays_per_s", "rtl_ok", "iu_lut", "iu_ff", "iu_dsp", "iu_bram36", "failure", "note"]


def parse_options(text):
    out = []
    for item in text.replace(",", " ").split():
        parts = item.split(":")
        test, _, fmt = parts[1].partition("@") if len(parts) > 1 else ("", "", "")
        if len(parts) not in (2, 3, 4) or not all(parts) or test not in ("mt", "watertight") or (parts[1].endswith("@")):
            raise UserError(f"--options: '{item}' is not BOX_FORMAT:TRI_TEST[@TRI_FORMAT][:NODE_FORMAT[:PRIM_FORMAT]] "
                            "(e.g. fp32:mt, bf16:watertight:q8, fp32:mt:full:packed, fp32:mt@fp64)")
        out.append((parts[0], parts[1], parts[2] if len(parts) > 2 else "full", parts[3] if len(parts) > 3 else "slot64"))
    if not out:
        raise UserError("--options is empty; give e.g. 'fp32:mt bf16:watertight'")
    return out


def name_of(box, tri, node, prim):
    return f"{box}:{tri}" + ("" if node == "full" and prim == "slot64" else f":{node}") + ("" if prim == "slot64" else f":{prim}")


def ask(jvm, cmd, args):
    a = jvm.request(cmd, args)
    if a.get("status") == 2:  # a refused option: the user's input, one clear error
        raise UserError(f"{cmd} {' '.join(map(str, args))}: {a.get('error')}")
    return a


def _cls(res):
    return " ".join(f"{k}={v}" for k, v in res["classified"].items() if v)


def synthesis_knobs(knobs):
    """The platform knobs of an IU synthesis: a circuit has fixed field widths, so CONFIG=fit synthesizes its preset
    (as make verilog does); make passes BOARD= among the knobs too, and the synthesis takes it once, from --board."""
    out = ["paper2017" if k > 0 and knobs[k - 1] == "--config" and v == "fit" else v for k, v in enumerate(knobs)]
    return [v for k, v in enumerate(out) if v != "--board" and not (k > 0 and out[k - 1] == "--board")]


def main(argv=None):
    ap = ArgParser(prog="make precision", description=__doc__.splitlines()[0])
    ap.add_argument("--scene", required=True, help="scene label (the mesh path)")
    ap.add_argument("--tris", required=True, help="float32 triangles .npy (tools/tris)")
    ap.add_argument("--golden", required=True, help="golden directory (rays.npy, hits.npy)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--java", required=True, help="the java command line (classpath included)")
    ap.add_argument("--knobs", default="", help="platform flags for every command (TUS, NODE_CACHE, CONFIG, ...)")
    ap.add_argument("--options", default=" ".join(DEFAULT_OPTIONS),
                    help="BOX_FORMAT:TRI_TEST[@TRI_FORMAT][:NODE_FORMAT[:PRIM_FORMAT]] list, e.g. 'fp32:mt fp32:mt@fp64 bf16:watertight:q8'")
    ap.add_argument("--exhaustive", type=int, default=1000, help="rays checked against every triangle (lost hits)")
    ap.add_argument("--rtl", type=int, default=1, help="1: RTL rays/s per option (make simulate)")
    ap.add_argument("--area", choices=("none", "yosys"), default="none", help="yosys: synthesize the IU per option")
    ap.add_argument("--board", default="xc5vlx330t", help="board of the area synthesis")
    a = ap.parse_args(argv)
    opts = parse_options(a.options)
    if BASELINE not in {name_of(*o) for o in opts}:
        opts = [tuple(BASELINE.split(":")) + ("full", "slot64")] + opts
    if a.exhaustive < 0:
        raise UserError("--exhaustive must be >= 0")
    tris = load_tris(a.tris)
    rays = load_rays(os.path.join(a.golden, "rays.npy"))
    golden = load_hits(os.path.join(a.golden, "hits.npy"), len(rays))
    os.makedirs(a.out, exist_ok=True)
    knobs = a.knobs.split()
    common = ["--tris", a.tris, "--rays", os.path.join(a.golden, "rays.npy"), "--scene-label", a.scene] + knobs
    jvm = JvmServer(a.java, os.path.join(a.out, "jvm.log"))
    rows, hits_of, made = [], {}, None
    try:
        for i, (box, tri, node, prim) in enumerate(opts):
            name = name_of(box, tri, node, prim)
            test, _, tri_format = tri.partition("@")
            tri_format = tri_format or "fp32"
            numerics = ["--box-format", box, "--tri-test", test, "--tri-format", tri_format, "--node-format", node, "--prim-format", prim]
            built = True  # the RTL builds every option (docs/numerics.md); a format it did not would say so in "note"
            d = os.path.join(a.out, name.replace(":", "-"))
            print(f"[precision] {i + 1}/{len(opts)} {name}: trace", flush=True)
            tr = ask(jvm, "trace", common + numerics + ["--out", d, "--access-trace", "0", "--exhaustive", a.exhaustive])
            if tr["status"] != 0:
                raise UserError(f"trace {name} failed: {tr.get('error')}")
            t = tr["result"]
            made = made or t
            hits = load_hits(os.path.join(d, "hits.npy"), len(rays))
            hits_of[name] = hits
            res = classify(tris, rays, golden, hits)
            n = max(1, t["rays"])
            row = {"option": name, "box_format": box, "tri_test": test, "tri_format": tri_format, "node_format": node, "prim_format": prim, "rays": t["rays"], "agree": res["agree"],
                   "classified": sum(res["classified"].values()), "unexplained": res["unexplained"],
                   "max_rel_t_err": res["max_rel_t_err"], "exhaustive_rays": t.get("exhaustive_rays", 0),
                   "lost_hits": t.get("lost_hits", ""), "node_fetches_per_ray": t["node_fetches"] / n,
                   "box_tests_per_ray": t["box_tests"] / n, "prim_tests_per_ray": t["prim_tests"] / n, "failure": "",
                   "note": "" if built else "a format modelled only: no RTL, no synthesis"}
            print(f"[precision] {i + 1}/{len(opts)} {name}: cachesim", flush=True)
            cs = ask(jvm, "cachesim", common + numerics)
            if cs["status"] != 0:
                raise UserError(f"cachesim {name} failed: {cs.get('error')}")
            c = cs["result"]
            row.update({k: c[k] for k in ("node_bytes_per_ray", "prim_bytes_per_ray", "node_bytes_per_ray_nocache",
                                          "prim_bytes_per_ray_nocache")})
            row["node_miss_rate"] = c["node_cache"]["miss_rate"] if c["node_cache"]["entries"] else ""
            row.update({"rtl_rays_per_s": "", "rtl_ok": "", "iu_lut": "", "iu_ff": "", "iu_dsp": "", "iu_bram36": ""})
            if a.rtl and built:
                print(f"[precision] {i + 1}/{len(opts)} {name}: RTL", flush=True)
                sm = ask(jvm, "simulate", common + numerics + ["--out", d + "-rtl", "--work", os.path.join("build", "sim-precision")])
                r = sm.get("result") or {}
                row["rtl_ok"] = bool(sm["status"] == 0 and r.get("ok"))
                row["rtl_rays_per_s"] = r.get("rays_per_s_at_clock", "")
                if not row["rtl_ok"]:
                    row["failure"] = f"RTL: {sm.get('error') or r.get('failures')}"
            if a.area == "yosys" and built:
                print(f"[precision] {i + 1}/{len(opts)} {name}: synthesis of the IU", flush=True)
                ar = ask(jvm, "area", synthesis_knobs(knobs) + numerics + ["--unit", "IntersectionUnit", "--fidelity", "yosys",
                                                           "--board", a.board, "--out", d + "-area"])
                if ar["status"] == 0:
                    tot = ar["result"]
                    row.update({"iu_lut": tot.get("lut"), "iu_ff": tot.get("ff"), "iu_dsp": tot.get("dsp"),
                                "iu_bram36": tot.get("bram36")})
                else:
                    row["failure"] = (row["failure"] + "; " if row["failure"] else "") + f"area: {ar.get('error')}"
            rows.append(row)
    finally:
        jvm.stop()
    base = hits_of[BASELINE]
    for row in rows:
        h = hits_of[row["option"]]
        same_prim = h["prim"] == base["prim"]
        same = same_prim & (h["t"].view(np.int32) == base["t"].view(np.int32))
        row["differ_from_baseline"] = int((~same).sum())  # a different primitive or other t bits
        row["prim_differs_from_baseline"] = int((~same_prim).sum())
        both = same_prim & (base["prim"] >= 0)
        rel = np.abs(h["t"][both].astype(np.float64) - base["t"][both]) / np.maximum(np.abs(base["t"][both].astype(np.float64)), 1e-30)
        row["max_rel_t_vs_baseline"] = float(rel.max()) if rel.size else 0.0
        row["differ_classes"] = _cls(classify(tris, rays, base, h)) if row["differ_from_baseline"] else ""
    csv = os.path.join(a.out, "precision.csv")
    prov = provenance_line(a.scene, made["config"], made["rtaccel"], scene_fields={"rays": len(rays)},
                           fields=" ".join(knobs[k].lstrip("-") + "=" + knobs[k + 1] for k in range(0, len(knobs) - 1, 2)
                                           if knobs[k] != "--config"))
    def fmt(v):
        return f"{v:.6g}" if isinstance(v, float) else str(v).replace(",", ";")
    write_text(csv, prov + ",".join(COLUMNS) + "\n" + "".join(",".join(fmt(r.get(k, "")) for k in COLUMNS) + "\n" for r in rows))
    failed = [r["option"] for r in rows if r["failure"]]
    png = os.path.join(a.out, "precision.png")
    table(png, [r for r in rows if not r["failure"]], prov.strip("# \n"))
    print(f"[precision] {len(rows)} options; CSV {csv}, table {png}" + (f"; FAILED: {', '.join(failed)}" if failed else ""))
    print(json.dumps({"scene": a.scene, "options": [r["option"] for r in rows], "csv": csv, "png": png,
                      "failed": failed, "numerics": made.get("numerics"), "rows": rows}))
    return 3 if failed else 0


def table(path, rows, caption):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    shown = [("option", "option"), ("agree", "agree"), ("unexplained", "unexpl."), ("differ_from_baseline", "≠ fp32:mt"),
             ("lost_hits", "lost"), ("node_fetches_per_ray", "nodes/ray"), ("prim_tests_per_ray", "prims/ray"),
             ("node_bytes_per_ray", "node B/ray"), ("prim_bytes_per_ray", "prim B/ray"), ("node_miss_rate", "node miss"),
             ("rtl_rays_per_s", "RTL rays/s"), ("iu_lut", "IU LUT"), ("iu_dsp", "IU DSP")]
    def cell(v):
        return f"{v:.4g}" if isinstance(v, float) else ("" if v is None else str(v))
    fig, ax = plt.subplots(figsize=(15, 0.45 * len(rows) + 1.2))
    ax.axis("off")
    t = ax.table(cellText=[[cell(r.get(k, "")) for k, _ in shown] for r in rows], colLabels=[h for _, h in shown],
                 loc="center", cellLoc="right")
    t.auto_set_font_size(False)
    t.set_fontsize(8)
    t.scale(1, 1.3)
    ax.set_title(caption, fontsize=8)
    save_png(fig, path)
    plt.close(fig)


if __name__ == "__main__":
    run(main)
