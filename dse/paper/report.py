"""report.md of `make paper`: every reproducible figure and table of Collinson & Sinnen 2017, ours beside theirs.

`render(run, scenes)` reads the outputs of the sub-steps (the CSV/JSON files `make analyze`, `make paper-nocache`,
`make paper-caches`, `make bench` and `make roofline` write) and returns the markdown text; it never runs
anything. `run` holds what the whole run shares (version, settings, machine bandwidth, step log, wall time);
each `SceneOutputs` names one mesh's files, None for a step that was not run (its section says which knob
skipped it). A present file that cannot be read raises UserError: a report is never made from half an output.
"""
import os
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..common import last_json_file, NoJsonResult
from ..plots.analysis import BANDWIDTH_COLUMNS, LEVEL_COLUMNS, read_csv
from ..plots.caches import read_bytes, read_fig11, split_csv
from . import facts as P
from scenes.errors import UserError


@dataclass
class SceneOutputs:
    name: str
    mesh: str
    analyze_dir: Optional[str] = None      # bandwidth_vs_mppl.csv, levels.csv (+ .png)
    caches_dir: Optional[str] = None       # fig11_miss_rate.csv, fig8_9_bytes_per_ray.csv (+ .png)
    nocache_csv: Optional[str] = None      # tus_sweep.csv of make paper-nocache
    cache_tus_csv: Optional[str] = None    # tus_sweep.csv of make paper-caches (2^13 DM node cache)
    tus_png: Optional[str] = None          # fig12_13_tus.png (both sweeps)
    bench_dir: Optional[str] = None        # model.json, embree.json
    table2_csv: Optional[str] = None       # roofline.csv of make roofline at the paper's settings
    table2_fmax_csv: Optional[str] = None  # the same at CLOCK_MHZ=fmax (the clock the circuit reaches)
    pngs: dict = field(default_factory=dict)  # figure key -> PNG path (inside the report's folder)


@dataclass
class RunInfo:
    out: str
    version: str
    settings: dict
    machine_gbps: Optional[float] = None
    machine_gbps_how: str = ""
    steps: list = field(default_factory=list)   # (step, scene, "ran"/"reused", seconds)
    wall_s: Optional[float] = None
    skipped_scenes: list = field(default_factory=list)
    skipped_steps: dict = field(default_factory=dict)  # step -> why


def g(x, d=3):
    """A number as the paper prints it: 3 significant digits, exponent form for big ones."""
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    x = float(x)
    if abs(x) >= 1e5:
        m, e = f"{x:.{d - 1}e}".split("e")
        return f"{m}e{int(e)}"
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.{d}g}"


def pct(x):
    return "—" if x is None else f"{100 * x:.1f} %"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def read_tus(path):
    """(provenance, {column: array}) of a tus_sweep.csv (rtaccel.cli.SweepTus)."""
    comments, header, rows = split_csv(path)
    need = ("tus", "rays_per_s", "mem_utilisation", "dram_bytes_per_ray")
    miss = [c for c in need if c not in header]
    if miss:
        raise UserError(f"{path} lacks column(s) {','.join(miss)}; rerun the TU sweep")
    try:
        cols = {c: np.array([float(r[header.index(c)]) for r in rows]) for c in need}
    except (ValueError, IndexError):
        raise UserError(f"{path}: a TU sweep row has a missing or non-numeric value; rerun the TU sweep")
    return comments, cols


def read_roofline(path):
    """(provenance, last row as {column: text}) of a roofline.csv (rtaccel.cli.RooflineCmd)."""
    comments, header, rows = split_csv(path)
    row = dict(zip(header, rows[-1]))
    for c in ("tus", "rays", "rays_per_s", "memory_bound", "compute_bound", "dram_bytes_per_ray"):
        try:
            float(row.get(c, ""))
        except ValueError:
            raise UserError(f"{path}: column {c} is missing or not a number; rerun make roofline")
    return comments, row


def read_json(path):
    try:
        return last_json_file(path)
    except (OSError, NoJsonResult) as e:
        raise UserError(f"{path}: no JSON result line ({e}); rerun make bench")


class Report:
    def __init__(self, run, scenes):
        self.run, self.scenes = run, scenes
        self.prov = []  # (file, provenance line) in the order read
        self.nodes = {}  # scene -> BVH nodes at MPPL 4 (from make analyze), for the differences' wording
        self.lines = []

    def w(self, text=""):
        self.lines.append(text)

    def note_prov(self, path, comments):
        if comments and all(p != path for p, _ in self.prov):
            self.prov.append((path, comments[0]))

    def link(self, s, key, caption):
        p = s.pngs.get(key)
        if p and os.path.isfile(p):
            self.w(f"![{caption}]({os.path.relpath(p, self.run.out)})\n")

    def skipped(self, step, what):
        why = self.run.skipped_steps.get(step, "its step was not run")
        self.w(f"*{what}: not run ({why}).*\n")

    # ------------------------------------------------------------------ sections
    def head(self):
        r = self.run
        self.w(f"# {P.PAPER}, reproduced (`make paper`)\n")
        self.w(f"rtaccel **{r.version}**; scenes: " + ", ".join(f"`{s.mesh}`" for s in self.scenes) +
               (f"; wall time {r.wall_s:.0f} s" if r.wall_s is not None else "") + ".\n")
        for s in r.skipped_scenes:
            self.w(f"- skipped (absent): `{s}`")
        if r.skipped_scenes:
            self.w()
        self.w("Settings: " + ", ".join(f"{k}={v}" for k, v in r.settings.items()) + ".\n")
        self.w("Our scenes stand for the paper's by kind: sponza_dabrovic for Sponza (the same 66k-triangle model), "
               "any other closed scene (camera inside) for Kitchen and Classroom, a hairball for Hairball. "
               "Every CSV's provenance line (scene, config, rtaccel version) is listed at the end.\n")

    def table1(self):
        self.w("## Table 1 — scene statistics (QBVH, MPPL 4; Section 5.1)\n")
        rows = []
        for s in self.scenes:
            if not s.analyze_dir:
                continue
            _, d = read_csv(os.path.join(s.analyze_dir, "bandwidth_vs_mppl.csv"), BANDWIDTH_COLUMNS)
            i = int(np.argmin(np.abs(d["mppl"] - 4)))
            tri = self.triangles(s)
            self.nodes[s.name] = int(d["nodes"][i])
            rows.append([f"{s.name} (ours)", tri, int(d["nodes"][i]), int(d["depth"][i]), int(d["rays"][i])])
        for n in P.SCENES:
            p, nodes, depth = P.TABLE1[n]
            rows.append([f"{n} (paper)", g(p), g(nodes), depth, "—"])
        self.w(table(["scene", "primitives", "nodes", "max depth", "rays (ours: camera + 5 bounces)"], rows))
        self.w("Difference: only sponza_dabrovic is one of the paper's models (its Sponza); the other meshes stand "
               "in by kind, and our frames are far smaller than its 10-second renders, which the per-ray figures "
               "below do not depend on but the caches' cold misses do.\n")

    def triangles(self, s):
        c, _ = read_csv(os.path.join(s.analyze_dir, "bandwidth_vs_mppl.csv"), BANDWIDTH_COLUMNS)
        for t in (c[0].split() if c else []):
            if t.startswith("triangles="):
                return t.split("=", 1)[1]
        return "—"

    def fig4(self):
        self.w("## Fig 4 — DRAM bytes per ray vs MPPL, no cache (Section 5.2, `make analyze`)\n")
        self.w(f"Paper (plot): {P.SHAPES['fig4']}.\n")
        for s in self.scenes:
            if not s.analyze_dir:
                self.skipped("analyze", f"{s.name}: Fig 4")
                continue
            path = os.path.join(s.analyze_dir, "bandwidth_vs_mppl.csv")
            c, d = read_csv(path, BANDWIDTH_COLUMNS)
            self.note_prov(path, c)
            ratio = d["node_bytes_per_ray"] / np.maximum(d["prim_bytes_per_ray"], 1e-9)
            paper = "1.5–3×" if P.counterpart(s.name) == ("Hairball",) else "≈10×"
            rows = [[int(m), g(nb), g(pb), g(t), f"{r:.1f}×", paper] for m, nb, pb, t, r in
                    zip(d["mppl"], d["node_bytes_per_ray"], d["prim_bytes_per_ray"], d["total_bytes_per_ray"], ratio)]
            self.w(f"**{s.name}** (paper counterpart: {', '.join(P.counterpart(s.name))})\n")
            self.w(table(["MPPL", "node B/ray", "prim B/ray", "total B/ray", "node/prim (ours)", "node/prim (paper)"], rows))
            best = int(d["mppl"][int(np.argmin(d["total_bytes_per_ray"]))])
            mono = bool(np.all(np.diff(d["node_bytes_per_ray"]) <= 0) and np.all(np.diff(d["prim_bytes_per_ray"]) >= 0))
            lo, hi = (1.5, 3) if paper == "1.5–3×" else (7, 13)
            if ratio.min() < lo:
                low = ", ".join(str(int(m)) for m, r in zip(d["mppl"], ratio) if r < lo)
                why = (f"ours is lower at MPPL {low}: our rays are a camera frame with diffuse bounces, not LuxRender's Metropolis "
                       "paths, and more of them end in leaves that each cost 64 B per triangle, so primitive bytes "
                       "weigh more")
            elif ratio.min() > hi:
                why = "ours is higher: our trees are deeper than the paper's for their size, so each ray visits more nodes"
            else:
                why = "none in kind; the exact ratio follows our rays (camera frame + diffuse bounces) and SAH build"
            self.w(f"Ours: node/prim {ratio.min():.1f}–{ratio.max():.1f}× (paper {paper}); lowest total at MPPL {best}; "
                   f"node bytes fall and primitive bytes rise with MPPL: {'yes' if mono else 'not strictly'}. "
                   f"Difference: {why}.\n")
            self.link(s, "fig4", f"{s.name} Fig 4")

    def fig5_6(self):
        self.w("## Figs 5–6 — node accesses by BVH level (Section 5.3, `make analyze`, MPPL 4)\n")
        self.w(f"Paper (plot): {P.SHAPES['fig5_6']}; caching levels 0–4 (at most 341 QBVH nodes) holds "
               + ", ".join(f"{n} {100 * a:.2g} % of nodes / {100 * b:.0f} % of accesses" for n, (a, b) in P.TOP_SHARE.items())
               + ".\n")
        rows, why = [], []
        for s in self.scenes:
            if not s.analyze_dir:
                self.skipped("analyze", f"{s.name}: Figs 5–6")
                continue
            path = os.path.join(s.analyze_dir, "levels.csv")
            c, d = read_csv(path, LEVEL_COLUMNS)
            self.note_prov(path, c)
            top = d["level"] < P.TOP_LEVELS
            k = int(np.flatnonzero(top)[-1]) if top.any() else 0
            peak_nodes, peak_acc = int(d["level"][np.argmax(d["nodes"])]), int(d["level"][np.argmax(d["accesses"])])
            paper = "; ".join(f"{n}: {100 * P.TOP_SHARE[n][0]:.2g} % / {100 * P.TOP_SHARE[n][1]:.0f} %" for n in P.counterpart(s.name))
            rows.append([s.name, int(d["nodes"][top].sum()), pct(d["cum_node_share"][k]), pct(d["cum_access_share"][k]),
                         paper, f"{peak_acc} / {peak_nodes}"])
            ref = np.mean([P.TOP_SHARE[n][1] for n in P.counterpart(s.name)])
            ours = d["cum_access_share"][k]
            if d["cum_node_share"][k] >= 0.999:
                why.append(f"{s.name}: the whole tree ({int(d['nodes'].sum())} nodes) lies in levels 0–4, so the share is all accesses")
            elif ours < ref - 0.05:
                why.append(f"{s.name}: fewer accesses in the top levels than the paper's {100 * ref:.0f} %: our diffuse "
                           "bounces start deep inside the scene, and a ray that starts inside descends fewer shared "
                           "upper nodes than one of the paper's long Metropolis paths")
            elif ours > ref + 0.05:
                why.append(f"{s.name}: more accesses in the top levels than the paper's {100 * ref:.0f} %: our tree "
                           f"({int(d['nodes'].sum())} nodes) is smaller, so levels 0–4 are a larger part of every path")
            else:
                why.append(f"{s.name}: within 5 points of the paper's {100 * ref:.0f} %")
        if rows:
            self.w(table(["scene", "nodes in levels 0–4", "share of nodes", "share of accesses",
                          "paper (nodes / accesses)", "peak level: accesses / nodes"], rows))
            self.w("Difference: " + "; ".join(why) + ".\n")
        for s in self.scenes:
            self.link(s, "fig5_6", f"{s.name} Figs 5-6")

    def bytes_table(self, s):
        path = os.path.join(s.caches_dir, "fig8_9_bytes_per_ray.csv")
        c, mppls, v = read_bytes(path)
        self.note_prov(path, c)
        return mppls, v

    def fig8(self):
        self.w("## Fig 8 — bytes per ray with the 2^13-entry DM node cache (Section 6.3, `make paper-caches`)\n")
        self.w(f"Paper (plot): {P.SHAPES['fig8']}.\n")
        for s in self.scenes:
            if not s.caches_dir:
                self.skipped("paper-caches", f"{s.name}: Fig 8")
                continue
            mppls, v = self.bytes_table(s)
            nc, nd = v["nocache"], v["node"]
            cut = nc["node_bytes_per_ray"] / np.maximum(nd["node_bytes_per_ray"], 1e-9)
            paper = " / ".join(f"{n} up to {P.NODE_CACHE_CUT[n]}×" for n in P.counterpart(s.name))
            rows = [[int(m), g(a), g(b), g(p), f"{x:.1f}×", pct(mr)] for m, a, b, p, x, mr in
                    zip(mppls, nc["node_bytes_per_ray"], nd["node_bytes_per_ray"], nd["prim_bytes_per_ray"], cut,
                        nd["node_miss_rate"])]
            self.w(f"**{s.name}** (paper: {paper})\n")
            self.w(table(["MPPL", "node B/ray, no cache", "node B/ray, cache", "prim B/ray", "node cut (ours)",
                          "node miss rate"], rows))
            ref = max(P.NODE_CACHE_CUT[n] for n in P.counterpart(s.name))
            nodes = self.nodes.get(s.name)
            tree = f"{nodes}-node tree (MPPL 4)" if nodes else "tree"
            if cut.max() > 1.5 * ref:
                why = (f"ours is larger: our {tree} is {'within' if nodes and nodes <= 8192 else 'not far above'} the "
                       "cache's 8192 entries, so few conflict misses remain beside the cold ones")
            elif cut.max() < ref / 1.5:
                why = (f"ours is smaller: every node of our {tree} misses once when first used, and a short frame pays "
                       "those cold misses over far fewer rays than the paper's 10-second renders")
            else:
                why = "within 1.5x of the paper's"
            self.w(f"Ours: node bytes cut {cut.min():.1f}–{cut.max():.1f}× (paper {paper}); primitive bytes now "
                   f"{'dominate' if np.all(nd['prim_bytes_per_ray'] > nd['node_bytes_per_ray']) else 'do not dominate everywhere'}. "
                   f"Difference: {why}.\n")
            self.link(s, "fig8_9", f"{s.name} Figs 4, 8, 9")

    def fig9(self):
        self.w("## Fig 9 — node cache 4096 DM + primitive cache 4096 DM (Section 6.3, `make paper-caches`)\n")
        self.w(f"Paper (plot): {P.SHAPES['fig9']}.\n")
        for s in self.scenes:
            if not s.caches_dir:
                self.skipped("paper-caches", f"{s.name}: Fig 9")
                continue
            mppls, v = self.bytes_table(s)
            nd, np_ = v["node"], v["node_prim"]
            rows = [[int(m), g(a), g(b), g(c), g(d), pct(pm)] for m, a, b, c, d, pm in
                    zip(mppls, nd["dram_bytes_per_ray"], np_["node_bytes_per_ray"], np_["prim_bytes_per_ray"],
                        np_["dram_bytes_per_ray"], np_["prim_miss_rate"])]
            lower = int(np.sum(np_["dram_bytes_per_ray"] < nd["dram_bytes_per_ray"]))
            expect = "higher (slightly)" if P.counterpart(s.name) == ("Hairball",) else "lower"
            self.w(f"**{s.name}** (paper: total {expect} than the node cache alone)\n")
            self.w(table(["MPPL", "total B/ray, node 8192", "node B/ray, split", "prim B/ray, split", "total B/ray, split",
                          "prim miss rate"], rows))
            agrees = (lower == len(mppls)) if expect == "lower" else (lower == 0)
            why = ("none in direction" if agrees else
                   "our primitive cache holds 4096/MPPL leaf-wide lines indexed by first primitive, so whether it "
                   "saves more than the halved node cache loses depends on how full our leaves are and how often "
                   "the smaller node cache now conflicts")
            self.w(f"Ours: the split total is lower at {lower} of {len(mppls)} MPPL values (paper: {expect}). "
                   f"Difference: {why}.\n")

    def fig11(self):
        self.w("## Fig 11 — node-cache miss rate vs size: DM, LRP0–6, breadth-first (Section 7.3, `make paper-caches`)\n")
        self.w(f"Paper (plot): {P.SHAPES['fig11']}.\n")
        for s in self.scenes:
            if not s.caches_dir:
                self.skipped("paper-caches", f"{s.name}: Fig 11")
                continue
            path = os.path.join(s.caches_dir, "fig11_miss_rate.csv")
            c, sizes, rates = read_fig11(path)
            self.note_prov(path, c)
            keys = [k for k in rates if k in ("dm", "bf") or (k.startswith("lrp") and k[3:].isdigit())]
            self.w(f"**{s.name}**\n")
            self.w(table(["policy"] + [str(int(x)) for x in sizes],
                         [[k] + [f"{100 * x:.2f} %" for x in rates[k]] for k in keys]))
            lrps = [k for k in keys if k[3:].isdigit()]  # LRP0..6 of the paper; the 4-way rows stay in the table
            best = min(lrps, key=lambda k: rates[k][0])
            small = rates[best][0] < rates["dm"][0]
            gap_big = rates["dm"][-1] - min(rates[k][-1] for k in lrps)
            flat = all(np.allclose(rates[k], rates["dm"]) for k in lrps)
            if flat:
                why = (f"our tree fits in the smallest cache ({int(sizes[0])} entries), so every policy only takes cold "
                       "misses and the curves coincide")
            elif small and best != "lrp6":
                why = (f"the paper's best is LRP6, ours {best}: which MAX_LEVEL wins depends on the tree's depth and "
                       "our LRP is our reading of Section 7.2 (Section 7.1 is missing from our copy; docs/caches.md)")
            elif not small:
                why = ("LRP does not beat DM here even at the smallest size: our frame reuses upper nodes less "
                       "between misses than the paper's renders (Section 7.1's exact rule is missing from our copy)")
            else:
                why = "none in shape"
            self.w(f"Ours: at {int(sizes[0])} entries the best LRP is {best} ({100 * rates[best][0]:.2f} % vs DM "
                   f"{100 * rates['dm'][0]:.2f} %: {'better' if small else 'not better'}); at {int(sizes[-1])} entries "
                   f"the best LRP is {100 * gap_big:+.2f} points below DM; breadth-first "
                   f"{100 * rates['bf'][-1]:.2f} % at {int(sizes[-1])}. Difference: {why}.\n")
            self.link(s, "fig11", f"{s.name} Fig 11")

    def fig12_13(self):
        self.w("## Figs 12–13 — RTL rays/s and memory utilisation vs TUs, without and with cache (Section 8)\n")
        self.w(f"Paper (plot): {P.SHAPES['fig12_13']}.\n")
        for s in self.scenes:
            sweeps = {}
            for key, path in (("no cache", s.nocache_csv), ("2^13 DM", s.cache_tus_csv)):
                if path:
                    c, d = read_tus(path)
                    self.note_prov(path, c)
                    sweeps[key] = d
            if not sweeps:
                self.skipped("tus", f"{s.name}: Figs 12–13")
                continue
            tus = sorted(set().union(*(set(d["tus"].astype(int)) for d in sweeps.values())))
            rows = []
            for t in tus:
                r = [t]
                for key in ("no cache", "2^13 DM"):
                    d = sweeps.get(key)
                    i = np.flatnonzero(d["tus"] == t) if d is not None else []
                    r += [g(d["rays_per_s"][i[0]]), pct(d["mem_utilisation"][i[0]])] if len(i) else ["—", "—"]
                rows.append(r)
            self.w(f"**{s.name}**\n")
            self.w(table(["TUs", "rays/s, no cache", "utilisation", "rays/s, 2^13 DM", "utilisation"], rows))
            parts = []
            if "no cache" in sweeps:
                d = sweeps["no cache"]
                parts.append(f"without cache {g(d['rays_per_s'][0])} → {g(d['rays_per_s'][-1])} rays/s from "
                             f"{int(d['tus'][0])} to {int(d['tus'][-1])} TUs, utilisation at most {pct(d['mem_utilisation'].max())} "
                             f"(paper: flat, not far above 50 %)")
            if "2^13 DM" in sweeps:
                d = sweeps["2^13 DM"]
                parts.append(f"with the cache {g(d['rays_per_s'][0])} → {g(d['rays_per_s'][-1])} rays/s "
                             f"({d['rays_per_s'][-1] / d['rays_per_s'][0]:.1f}×), utilisation at most {pct(d['mem_utilisation'].max())}")
            diff = []
            if "no cache" in sweeps:
                diff.append("our DRAM model delivers exactly 50 % of 1.2 GB/s with a fixed 40-cycle latency, so the "
                            "uncached curve flattens as soon as a few TUs hide that latency, where the paper's real DDR2 "
                            "needed more TUs; the plateau is the same 50 %")
            if "2^13 DM" in sweeps:
                d = sweeps["2^13 DM"]
                u = d["mem_utilisation"].max()
                bpr = d["dram_bytes_per_ray"][-1]
                diff.append("with the cache our utilisation stays well below the 50 % plateau, as on the paper's "
                            "closed scenes" if u < 0.4 else
                            f"with the cache ours approaches the 50 % plateau at the most TUs ({bpr:.0f} DRAM B/ray "
                            "after the cache in a short frame whose misses are mostly compulsory), the paper's Hairball "
                            "behaviour rather than its Kitchen" if u < 0.49 else
                            f"with the cache ours reaches the 50 % plateau ({bpr:.0f} DRAM B/ray after the cache), "
                            "as the paper's Hairball does after 16 TUs")
            self.w("Ours: " + "; ".join(parts) + ". Difference: " + "; ".join(diff) + ".\n")
            self.link(s, "fig12_13", f"{s.name} Figs 12-13")

    def table2(self):
        self.w(f"## Table 2 — rays/s at the paper's settings (Section 9)\n")
        self.w(f"Ours: the RTL (Verilator, every ray checked against the model) of the paper2017 preset with "
               f"{self.run.settings.get('Table 2 TUs', P.TABLE2_TUS)} TUs (the paper's {P.TABLE2_TUS}), the 2^13-entry DM node cache and {P.FPGA_GBPS} GB/s DDR2 at "
               f"50 % sustained (`make roofline`), at the paper's {P.CLOCK_MHZ} MHz and at the clock the same circuit "
               "reaches (`CLOCK_MHZ=fmax`: routed by `make timing` where a result exists, else `make area`'s LUT-level "
               "proxy, which is a proxy: no placement or routing); the memory stays at its GB/s, so a faster clock gets "
               "fewer bytes per cycle. Embree and our reference model measured on this machine in the same "
               "run (`make bench`, one thread each).\n")
        rows = [[f"paper {k}"] + [g(P.TABLE2[k][n]) for n in P.SCENES] for k in ("CPU", "GPU", "FPGA")]
        self.w(table(["platform"] + list(P.SCENES), rows))
        rows, notes = [], []
        for s in self.scenes:
            rl = self.roofline(s)
            fm = self.roofline(s, fmax=True)
            b = self.bench(s)
            paper = " / ".join(f"{n} {g(P.TABLE2['FPGA'][n])}" for n in P.counterpart(s.name))
            ours = float(rl["rays_per_s"]) if rl else None
            at = (f"{g(float(fm['rays_per_s']))} at {fm['clock_mhz']:.0f} MHz ({fm['clock_source']})" if fm else "—")
            rows.append([s.name, g(ours), at, paper, g(float(rl["memory_bound"])) if rl else "—",
                         g(float(rl["compute_bound"])) if rl else "—", rl.get("binding", "—") if rl else "—",
                         g(float(rl["dram_bytes_per_ray"])) if rl else "—",
                         g(b[1]["embree_rays_per_s_median"]) if b else "—", g(b[0]["model_rays_per_s_median"]) if b else "—"])
            if rl:
                ref = np.mean([P.TABLE2["FPGA"][n] for n in P.counterpart(s.name)])
                tus, bpr, bind = int(float(rl["tus"])), float(rl["dram_bytes_per_ray"]), rl.get("binding", "?")
                why = {"memory": f"the memory's sustained 0.6 GB/s over our {bpr:.0f} DRAM B/ray after the cache",
                       "compute": f"one IU's beat port serving all {tus} TUs",
                       }.get(bind, f"latency: {tus} TUs keep too few requests in flight to reach either roof "
                                   f"(memory bound {g(float(rl['memory_bound']))}, compute bound {g(float(rl['compute_bound']))})")
                reached = (f" ({float(fm['rays_per_s']) / ref:.2f}× at the {fm['clock_mhz']:.0f} MHz it reaches by "
                           f"{fm['clock_source']})" if fm else "")
                notes.append(f"{s.name}: ours {ours / ref:.2f}× the paper's FPGA at {tus} TUs and {P.CLOCK_MHZ} MHz"
                             f"{reached}; ours is bound by {why}, "
                             "and our DRAM model has none of the row conflicts and refreshes the paper's DDR2 pays, "
                             "while the paper's frame was a 10-second Metropolis render on a different tree.")
        if not any(s.table2_csv for s in self.scenes):
            self.skipped("table2", "our RTL row")
        elif not any(s.table2_fmax_csv for s in self.scenes):
            self.skipped("table2-fmax", "our row at the reached clock")
        self.w(table(["scene", f"ours RTL rays/s at {P.CLOCK_MHZ} MHz", "ours at the reached clock", "paper FPGA",
                      "memory bound", "compute bound", "binding",
                      "DRAM B/ray", "Embree 1 thread (this machine)", "our model 1 thread"], rows))
        for n in notes:
            self.w(f"- {n}")
        self.w("\nDifference to the paper's CPU row: the paper's CPU is LuxRender's SSE QBVH on four threads of an "
               "i5-3470; ours is Embree on one thread of this machine (`make bench` pins it), rays from the same frame.\n")

    def roofline(self, s, fmax=False):
        """The last row of a Table 2 roofline.csv (at the paper's clock, or with `fmax` at the reached one), with
        the clock its provenance line names (clock_mhz, clock_source), or None when that run was not made."""
        csv = s.table2_fmax_csv if fmax else s.table2_csv
        if not csv:
            return None
        c, row = read_roofline(csv)
        self.note_prov(csv, c)
        words = dict(w.split("=", 1) for line in c for w in line.lstrip("# ").split() if "=" in w)
        try:
            row["clock_mhz"], row["clock_source"] = float(words["clock_mhz"]), words["clock_source"]
        except (KeyError, ValueError):
            raise UserError(f"{csv}: its first line names no clock_mhz/clock_source; rerun make roofline")
        return row

    def bench(self, s):
        if not s.bench_dir:
            return None
        m, e = (read_json(os.path.join(s.bench_dir, f)) for f in ("model.json", "embree.json"))
        keys = ("scene", "triangles", "rays", "config", "threads", "rtaccel")
        self.note_prov(os.path.join(s.bench_dir, "model.json"), [" ".join(f"{k}={m[k]}" for k in keys if k in m)])
        return m, e

    def fig15(self):
        r = self.run
        self.w("## Fig 15 — rays/s per GB/s of available bandwidth (Section 9)\n")
        self.w(f"Paper: FPGA {P.FPGA_GBPS} GB/s, CPU {P.CPU_GBPS} GB/s, GPU {P.GPU_GBPS} GB/s; FPGA over CPU "
               + ", ".join(f"{n} {P.FIG15_TEXT[n]} (Table 2: {P.fig15_ratio(n):.1f}×)" for n in P.SCENES) + ".\n")
        self.w(f"This machine: {g(r.machine_gbps) if r.machine_gbps else '—'} GB/s ({r.machine_gbps_how}).\n")
        rows = []
        for s in self.scenes:
            rl, b = self.roofline(s), self.bench(s)
            ours = float(rl["rays_per_s"]) / P.FPGA_GBPS if rl else None
            emb = b[1]["embree_rays_per_s_median"] / r.machine_gbps if b and r.machine_gbps else None
            ratio = ours / emb if ours and emb else None
            paper = " / ".join(f"{n} {P.fig15_ratio(n):.1f}×" for n in P.counterpart(s.name))
            rows.append([s.name, g(ours), g(emb), f"{ratio:.1f}×" if ratio else "—", paper])
        self.w(table(["scene", f"ours RTL per GB/s (at {P.FPGA_GBPS} GB/s)", "Embree 1 thread per GB/s (this machine)",
                      "ours / Embree", "paper FPGA / CPU"], rows))
        self.w("Difference: Embree runs one thread here against the paper's four, and this machine's bandwidth is "
               "what one thread measured (or MACHINE_GBPS), not the DIMMs' peak the paper divides by, so our ratio "
               "moves with both; the FPGA side uses the paper's own 1.2 GB/s peak.\n")

    def not_reproduced(self):
        self.w("## Not reproduced\n")
        self.w("- Figs 1–3, 7, 10: diagrams and renders, no data.\n- Fig 14 (rays per joule): we measure no power.\n"
               "- Kitchen and Classroom meshes are not in the project; closed scenes of ours stand for them.\n")

    def steps(self):
        self.w("## How this report was made\n")
        rows = [[st, sc, how, f"{sec:.0f} s"] for st, sc, how, sec in self.run.steps]
        if rows:
            self.w(table(["step", "scene", "ran / reused", "wall"], rows))
        for k, why in self.run.skipped_steps.items():
            self.w(f"- {k}: skipped ({why})")
        self.w("\nProvenance (first line of every file read):\n")
        for path, line in self.prov:
            self.w(f"- `{os.path.relpath(path, self.run.out) if os.path.isabs(path) else path}`: `{line}`")
        self.w()


def render(run, scenes):
    if not scenes:
        raise UserError("no scene to report on")
    r = Report(run, scenes)
    for section in (r.head, r.table1, r.fig4, r.fig5_6, r.fig8, r.fig9, r.fig11, r.fig12_13, r.table2, r.fig15,
                    r.not_reproduced, r.steps):
        section()
    return "\n".join(r.lines) + "\n"
