"""python -m dse.studies.fidelity --java CMD --version V [--scenes sponza,conference,hairball] [--tus 1,2,4,8,16,32]
[--caches none,dm,lrp,hybrid] [--mppls 4,8] [--node-cache 8192] [--width 32 --height 24 --depth 5 --seed 1]
[--out build/fidelity] [--workers 1]

`make fidelity`: the speed-for-accuracy ladder measured. On a fixed grid of configurations (TUs x node cache kind
x MPPL) and scenes, every rung of `make dse` is run on every point (dse/explore/rungs.py, the same workers, JVM server
and SQLite store, so a rerun evaluates only what is missing) and each cheap figure is compared with the RTL's:

  mva         the analytic rays/s (`predicted_rays_per_s`, MVA with head-of-line blocking)
  mva_no_hol  the plain MVA before head-of-line blocking (`predicted_rays_per_s_no_hol`), for comparison
  bw_bound    rays/s from DRAM bandwidth alone (`bandwidth_bound_rays_per_s`)
  cachesim    the trace-driven cache model: node/prim miss rate, DRAM bytes per ray
  rtl         the platform RTL under Verilator, checked ray by ray against the model (the reference)

Writes OUT/fidelity.csv (one row per point x scene), OUT/fidelity.png, OUT/fidelity.md (the tables of docs/dse.md)
and OUT/store.sqlite; the last stdout line
is {"configurations", "scenes", "rungs": {rung: {"figure", "median_abs_err", "max_abs_err", "wall_s_per_ray"}},
"mva_by_tus", "failed", "csv", ...}. A run that failed its check (RTL vs model mismatch), was refused or crashed
is listed in the CSV with its status, never plotted nor counted in an error; the exit status is then 3.
"""
import csv
import io
import json
import os
import statistics
import sys
import textwrap
import time

from scenes.cli import EXIT_CHECK_FAILED, ArgParser, run
from scenes.errors import UserError
from scenes.procedural import NAMES as PROCEDURAL

from ..common import provenance_line, save_png, write_text
from ..explore import store as st
from ..explore.explore import Sweep, log, prepare_scene
from ..explore.knobs import ROOT
from ..explore.pool import Pool
from ..explore.space import Scene, Space

SHARED = os.environ.get("RTACCEL_SHARED_SCENES") or os.path.join(os.path.dirname(ROOT), "shared", "scenes")
MESHES = {"sponza": "sponza_dabrovic.obj", "conference": "conference.obj"}  # short names of the shared meshes


def cache_knobs(kind, entries):
    """The knobs of one node-cache kind at `entries` entries (LRP and hybrid need the preset with level fields)."""
    kinds = {
        "none": {"CONFIG": "paper2017", "NODE_CACHE": 0},
        "dm": {"CONFIG": "paper2017", "NODE_CACHE": entries, "NODE_POLICY": "dm"},
        "lrp": {"CONFIG": "paper2017-lrp", "NODE_CACHE": entries, "NODE_POLICY": "lrp", "MAX_LEVEL": 4},
        "hybrid": {"CONFIG": "paper2017-lrp", "NODE_CACHE": entries, "NODE_POLICY": "hybrid", "MAX_LEVEL": 6},
    }
    if kind not in kinds:
        raise UserError(f"FIDELITY_CACHES: unknown cache kind '{kind}'; choose from {', '.join(kinds)}")
    return kinds[kind]


def grid(tus, caches, mppls, entries):
    """The fixed set of configurations: (cache kind, config) for every TUs x cache kind x MPPL."""
    return [(c, {**cache_knobs(c, entries), "MPPL": m, "TUS": t}) for c in caches for m in mppls for t in tus]


def scene_of(name, a):
    """A dse Scene for a short name (sponza, conference), a procedural scene or a mesh path; None when absent."""
    if name in PROCEDURAL:
        return Scene(name, os.path.join(ROOT, "build", "scenes", f"{name}.obj"), name, "", a.width, a.height, a.depth, a.seed)
    mesh = os.path.join(SHARED, MESHES[name]) if name in MESHES else os.path.abspath(name)
    if name not in MESHES and not name.endswith((".obj", ".ply")):
        raise UserError(f"FIDELITY_SCENES: '{name}' is neither {', '.join(MESHES)}, a procedural scene "
                        f"({', '.join(PROCEDURAL)}) nor a .obj/.ply path")
    if not os.path.isfile(mesh):
        return None
    return Scene(os.path.splitext(os.path.basename(mesh))[0], mesh, "", "", a.width, a.height, a.depth, a.seed)


def _ints(text, what):
    try:
        xs = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise UserError(f"{what}: '{text}' is not a comma-separated list of integers")
    if not xs or any(x < 1 for x in xs):
        raise UserError(f"{what}: give one or more positive integers (got '{text}')")
    return xs


def rel(model, ref):
    return (model - ref) / ref if model is not None and ref else None


def _miss(res, which):
    c = (res or {}).get(which) or {}
    return c.get("miss_rate") if c.get("entries") else None  # no cache: nothing to compare


def row(kind, c, scene, cs, rtl):
    """One CSV row: the point, every rung's figure, its error against the RTL row, and the statuses."""
    r = {"scene": scene["name"], "point": st.point_id(c), "cache": kind, "tus": c["TUS"], "mppl": c["MPPL"],
         "config": c["CONFIG"], "node_cache": c["NODE_CACHE"], "node_policy": c.get("NODE_POLICY", ""),
         "cachesim_status": cs["status"] if cs else "missing", "rtl_status": rtl["status"] if rtl else "missing",
         "error": "; ".join(x["error"] for x in (cs, rtl) if x and x["status"] != st.OK and x.get("error"))}
    m = cs["result"] if cs and cs["status"] == st.OK else None
    t = rtl["result"] if rtl and rtl["status"] == st.OK else None
    if m:
        n = m["rays"] or 1
        r.update(rays=m["rays"], clock_mhz=m.get("clock_mhz"), clock_source=m.get("clock_source"),
                 mva_rays_per_s=m["predicted_rays_per_s"], mva_no_hol_rays_per_s=m.get("predicted_rays_per_s_no_hol"),
                 bw_bound_rays_per_s=m["bandwidth_bound_rays_per_s"], cachesim_node_miss_rate=_miss(m, "node_cache"),
                 cachesim_prim_miss_rate=_miss(m, "prim_cache"), cachesim_dram_bytes_per_ray=m["dram_bytes_per_ray"],
                 cachesim_wall_s_per_ray=((m.get("trace_s") or 0.0) + (m.get("wall_s") or 0.0)) / n,
                 mva_wall_s_per_ray=(m["predict_s"] / n) if m.get("predict_s") is not None else None)
    if t:
        n = t["rays"] or 1
        r.update(clock_mhz=t.get("clock_mhz"), clock_source=t.get("clock_source"), rtl_rays_per_s=t["rays_per_s_at_clock"], rtl_node_miss_rate=_miss(t, "node_cache"),
                 rtl_prim_miss_rate=_miss(t, "prim_cache"), rtl_dram_bytes_per_ray=t.get("dram_bytes_per_ray"),
                 rtl_wall_s_per_ray=(rtl["wall_s"] or 0.0) / n, rtl_sim_s_per_ray=(t.get("sim_wall_s") or 0.0) / n)
    if m and t:
        ref = t["rays_per_s_at_clock"]
        diff = lambda a, b: (a - b) if a is not None and b is not None else None  # noqa: E731
        r.update(mva_err=rel(r["mva_rays_per_s"], ref), mva_no_hol_err=rel(r["mva_no_hol_rays_per_s"], ref),
                 bw_bound_err=rel(r["bw_bound_rays_per_s"], ref),
                 dram_bytes_err=rel(r["cachesim_dram_bytes_per_ray"], r["rtl_dram_bytes_per_ray"]),
                 node_miss_diff=diff(r["cachesim_node_miss_rate"], r["rtl_node_miss_rate"]),
                 prim_miss_diff=diff(r["cachesim_prim_miss_rate"], r["rtl_prim_miss_rate"]))
    return r


COLUMNS = ["scene", "point", "cache", "tus", "mppl", "config", "node_cache", "node_policy", "rays", "clock_mhz", "clock_source",
           "rtl_rays_per_s", "mva_rays_per_s", "mva_err", "mva_no_hol_rays_per_s", "mva_no_hol_err",
           "bw_bound_rays_per_s", "bw_bound_err",
           "rtl_node_miss_rate", "cachesim_node_miss_rate", "node_miss_diff",
           "rtl_prim_miss_rate", "cachesim_prim_miss_rate", "prim_miss_diff",
           "rtl_dram_bytes_per_ray", "cachesim_dram_bytes_per_ray", "dram_bytes_err",
           "mva_wall_s_per_ray", "cachesim_wall_s_per_ray", "rtl_wall_s_per_ray", "rtl_sim_s_per_ray",
           "cachesim_status", "rtl_status", "error"]

# rung -> (the figure it is judged on, the CSV error column, the CSV wall-time column)
RUNGS = {"mva": ("rays_per_s", ["mva_err"], "mva_wall_s_per_ray"),
         "mva_no_hol": ("rays_per_s", ["mva_no_hol_err"], "mva_wall_s_per_ray"),
         "bw_bound": ("rays_per_s", ["bw_bound_err"], "mva_wall_s_per_ray"),
         "cachesim": ("dram_bytes_per_ray, node/prim miss rate (points)", ["dram_bytes_err", "node_miss_diff", "prim_miss_diff"],
                      "cachesim_wall_s_per_ray"),
         "rtl": ("reference", [], "rtl_wall_s_per_ray")}


def ok_rows(rows):
    return [r for r in rows if r["cachesim_status"] == st.OK and r["rtl_status"] == st.OK]


def _stats(xs):
    xs = [abs(x) for x in xs if x is not None]
    return {"median_abs_err": statistics.median(xs), "max_abs_err": max(xs), "n": len(xs)} if xs else None


def summary(rows):
    """Per rung: median/max |error| against the RTL on the passing rows and wall time per ray (total time over
    total rays, so a trace made once per scene is spread over the runs that reuse it)."""
    good = ok_rows(rows)
    out = {}
    for name, (figure, errs, wall) in RUNGS.items():
        s = {"figure": figure}
        for e in errs:
            s[e] = _stats(r.get(e) for r in good)
        if errs:
            s.update({k: v for k, v in (s[errs[0]] or {}).items()})
        num = sum((r.get(wall) or 0.0) * (r.get("rays") or 0) for r in good if r.get(wall) is not None)
        den = sum(r.get("rays") or 0 for r in good if r.get(wall) is not None)
        s["wall_s_per_ray"] = num / den if den else None
        out[name] = s
    by_tus = {}
    for t in sorted({r["tus"] for r in good}):
        by_tus[str(t)] = {"mva": _stats(r["mva_err"] for r in good if r["tus"] == t),
                          "mva_no_hol": _stats(r["mva_no_hol_err"] for r in good if r["tus"] == t)}
    return out, by_tus


def _pct(s, key="median_abs_err", unit="%"):
    return f"{100 * s[key]:.1f} {unit}" if s else "–"


def markdown(rungs, by_tus, prov):
    """The two tables of docs/dse.md: per rung (wall time per ray, median/max error against the RTL) and the MVA's
    rays/s error per TU count, before and after head-of-line blocking."""
    out = [f"<!-- {prov.strip('# ').strip()} -->", "", "| rung | judged on | wall time per ray | median \\|error\\| | max \\|error\\| | n |",
           "|---|---|---|---|---|---|"]
    for name, s in rungs.items():
        wall = f"{s['wall_s_per_ray'] * 1e6:.3g} µs" if s.get("wall_s_per_ray") is not None else "–"
        if name == "cachesim":
            parts = [(k, s.get(k)) for k in ("dram_bytes_err", "node_miss_diff", "prim_miss_diff")]
            unit = {"dram_bytes_err": "%", "node_miss_diff": "points", "prim_miss_diff": "points"}
            med = ", ".join(f"{k}: {_pct(v, unit=unit[k])}" for k, v in parts if v)
            mx = ", ".join(f"{k}: {_pct(v, 'max_abs_err', unit[k])}" for k, v in parts if v)
            n = max((v["n"] for _, v in parts if v), default=0)
        elif name == "rtl":
            med = mx = "reference"
            n = ""
        else:
            med, mx, n = _pct(s if s.get("n") else None), _pct(s if s.get("n") else None, "max_abs_err"), s.get("n", 0)
        out.append(f"| {name} | {s['figure']} | {wall} | {med} | {mx} | {n} |")
    out += ["", "| TUs | MVA median \\|error\\| | MVA max \\|error\\| | plain MVA median | plain MVA max | n |", "|---|---|---|---|---|---|"]
    for t, v in by_tus.items():
        out.append(f"| {t} | {_pct(v['mva'])} | {_pct(v['mva'], 'max_abs_err')} | {_pct(v['mva_no_hol'])} | "
                   f"{_pct(v['mva_no_hol'], 'max_abs_err')} | {(v['mva'] or {}).get('n', 0)} |")
    return "\n".join(out) + "\n"


def write_csv(path, rows, prov):
    buf = io.StringIO()
    buf.write(prov)
    w = csv.DictWriter(buf, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r.get(k) is None else (f"{r[k]:.6g}" if isinstance(r[k], float) else r[k])) for k in COLUMNS})
    write_text(path, buf.getvalue())


def plot(path, rows, title):
    """Top: rays/s against TUs per scene (RTL solid, MVA dashed, plain MVA dotted), one colour per cache kind, at
    the first MPPL. Bottom: every passing point's MVA error against the RTL per TU count, with the 10 % band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    good = ok_rows(rows)
    scenes = list(dict.fromkeys(r["scene"] for r in good))
    if not scenes:
        return None
    mppl = min(r["mppl"] for r in good)
    fig, axes = plt.subplots(2, len(scenes), figsize=(4.6 * len(scenes), 7.2), squeeze=False)
    colours = {"none": "tab:grey", "dm": "tab:blue", "lrp": "tab:orange", "hybrid": "tab:green"}
    for i, s in enumerate(scenes):
        ax = axes[0][i]
        for kind in dict.fromkeys(r["cache"] for r in good):
            pts = sorted((r for r in good if r["scene"] == s and r["cache"] == kind and r["mppl"] == mppl), key=lambda r: r["tus"])
            if not pts:
                continue
            x = [r["tus"] for r in pts]
            col = colours.get(kind)
            ax.plot(x, [r["rtl_rays_per_s"] for r in pts], "-o", color=col, label=f"{kind} RTL", ms=4)
            ax.plot(x, [r["mva_rays_per_s"] for r in pts], "--", color=col, label=f"{kind} MVA")
            if all(r.get("mva_no_hol_rays_per_s") for r in pts):
                ax.plot(x, [r["mva_no_hol_rays_per_s"] for r in pts], ":", color=col, label=f"{kind} MVA, no HOL")
        ax.set_xscale("log", base=2)
        ax.set_title(f"{s} (MPPL {mppl})")
        ax.set_xlabel("TUs")
        ax.set_ylabel("rays/s")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
        ax = axes[1][i]
        pts = [r for r in good if r["scene"] == s]
        ax.axhspan(-10, 10, color="tab:green", alpha=0.1)
        for key, mk, lab in (("mva_err", "o", "MVA"), ("mva_no_hol_err", "x", "MVA, no HOL")):
            xy = [(r["tus"], 100 * r[key]) for r in pts if r.get(key) is not None]
            if xy:
                ax.scatter(*zip(*xy), marker=mk, s=18, label=lab)
        ax.set_xscale("log", base=2)
        ax.set_xlabel("TUs")
        ax.set_ylabel("rays/s error vs RTL (%)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("\n".join(textwrap.wrap(title, 60 * len(scenes))), fontsize=7)
    fig.tight_layout()
    save_png(fig, path)
    plt.close(fig)
    return path


def main(argv=None):
    ap = ArgParser(prog="make fidelity", description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="sponza,conference,hairball")
    ap.add_argument("--tus", default="1,2,4,8,16,32")
    ap.add_argument("--caches", default="none,dm,lrp,hybrid")
    ap.add_argument("--mppls", default="4,8")
    ap.add_argument("--node-cache", type=int, default=8192)
    ap.add_argument("--width", type=int, default=32)
    ap.add_argument("--height", type=int, default=24)
    ap.add_argument("--depth", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "fidelity"))
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--java", default=os.environ.get("RTACCEL_JAVA", ""))
    ap.add_argument("--version", default=os.environ.get("RTACCEL_VERSION", "unknown"))
    a = ap.parse_args(argv)
    t0 = time.time()
    if not a.java:
        raise UserError("give --java '<java command on the rtaccel classpath>' (make fidelity passes it)")
    if a.workers < 0:
        raise UserError(f"FIDELITY_WORKERS={a.workers}: give 0 (inline, no Ray) or more workers")
    if a.width < 1 or a.height < 1 or a.depth < 0:
        raise UserError("FIDELITY_WIDTH and FIDELITY_HEIGHT must be at least 1 and FIDELITY_DEPTH at least 0")
    caches = [c.strip() for c in a.caches.split(",") if c.strip()]
    points = grid(_ints(a.tus, "FIDELITY_TUS"), caches, _ints(a.mppls, "FIDELITY_MPPLS"), a.node_cache)
    names = [s.strip() for s in a.scenes.split(",") if s.strip()]
    if not names:
        raise UserError("FIDELITY_SCENES is empty; give e.g. sponza,conference,hairball")
    wanted = [(n, scene_of(n, a)) for n in names]
    for n, s in wanted:
        if s is None:
            log(f"skip scene {n}: {os.path.join(SHARED, MESHES.get(n, n))} is absent")
    scenes = [prepare_scene(s) for _, s in wanted if s is not None]
    if not scenes:
        raise UserError(f"none of the scenes {', '.join(names)} is present; give FIDELITY_SCENES=hairball or put the meshes in {SHARED}")
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    sp = Space(path="", name="fidelity", description="make fidelity", base={}, scenes=[], axes={}, constraints={},
               maximize=[], minimize=[], strategy={}, fidelity={"area": False, "rtl": True})
    cfgs = [c for _, c in points]
    log(f"{len(cfgs)} configurations x {len(scenes)} scenes ({', '.join(s['name'] for s in scenes)}), "
        f"{a.width}x{a.height} depth {a.depth}: cache model, then RTL")
    # one worker builds where make simulate does (build/sim, cached per circuit), so the two share their builds
    pool = Pool(a.workers, "", a.java, os.path.join(out, "logs"), "build/sim" if a.workers <= 1 else None)
    sweep = Sweep(sp, scenes, out, pool, a.version)
    try:
        cs = sweep.runs("cachesim", cfgs)
        rtl = sweep.runs("rtl", cfgs)
    finally:
        pool.close()
        sweep.close()
    rows = [row(kind, c, s, cs.get((st.point_id(c), s["name"])), rtl.get((st.point_id(c), s["name"])))
            for s in scenes for kind, c in points]
    prov = provenance_line(",".join(s["label"] for s in scenes), "paper2017|paper2017-lrp", a.version,
                           scene_fields={"frame": f"{a.width}x{a.height}", "depth": a.depth, "seed": a.seed},
                           fields={"tus": a.tus, "caches": ",".join(caches), "mppls": a.mppls, "node_cache": a.node_cache})
    csv_path = os.path.join(out, "fidelity.csv")
    write_csv(csv_path, rows, prov)
    rungs, by_tus = summary(rows)
    png = plot(os.path.join(out, "fidelity.png"), rows, prov.strip("# \n"))
    write_text(os.path.join(out, "fidelity.md"), markdown(rungs, by_tus, prov))
    failed = [{"point": r["point"], "scene": r["scene"], "tus": r["tus"], "cache": r["cache"], "mppl": r["mppl"],
               "cachesim": r["cachesim_status"], "rtl": r["rtl_status"], "error": r["error"]}
              for r in rows if r not in ok_rows(rows)]
    c = sweep.counts
    print(json.dumps({
        "configurations": len(cfgs), "scenes": [s["name"] for s in scenes],
        "skipped_scenes": [n for n, s in wanted if s is None], "rows": len(rows), "ok_rows": len(ok_rows(rows)),
        "rungs": rungs, "mva_by_tus": by_tus, "failed": failed, "csv": csv_path, "png": png,
        "store": os.path.join(out, "store.sqlite"), "evaluated": sum(v["evaluated"] for v in c.values()),
        "skipped": sum(v["skipped"] for v in c.values()), "wall_s": round(time.time() - t0, 3), "rtaccel": a.version}))
    if failed:
        print(f"error: check failed: {len(failed)} of {len(rows)} runs did not pass (listed in {csv_path} and the JSON's "
              f"\"failed\"); they are not in the errors nor the plot", file=sys.stderr)
        return EXIT_CHECK_FAILED
    return 0


if __name__ == "__main__":
    run(main)
