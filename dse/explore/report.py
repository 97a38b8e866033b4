"""What `make dse` leaves behind: per-point summaries, CSVs, Pareto plots, the front, the best configuration per
board with its `make verilog` command, and how far each cheap rung was from the RTL on the confirmed points.

Only runs with status ok are figures; a refused, crashed or check-failed run (exit 3) is listed with its error
and never plotted or ranked.
"""
import os
import statistics
import sys

from . import pareto, rungs, store as st
from ..common import save_png, write_text
from .knobs import KNOBS, verilog_command
from .space import LIMITS

AREA_OK = (st.OK, "infeasible")


def summarise(sp, config, scenes, rows):
    """One point's figures: cachesim aggregated over the scenes (geometric mean of rays/s and rays per byte),
    its cost from the area rung, whether it meets the constraints, and why not."""
    pid = st.point_id(config)
    s = {"point": pid, "config": config, "metrics": {}, "errors": [], "feasible": True, "notes": []}
    per = [rows["cachesim"].get((pid, sc["name"])) for sc in scenes]
    bad = [(sc["name"], r) for sc, r in zip(scenes, per) if r is None or r["status"] != st.OK]
    if bad:
        s["feasible"] = False
        s["errors"] += [f"cachesim {n}: {r['status'] if r else 'missing'}: {r['error'] if r else ''}" for n, r in bad]
    else:
        m = [rungs.metrics("cachesim", r["result"]) for r in per]
        s["metrics"]["cachesim"] = {
            "rays_per_s": rungs.geomean(x["rays_per_s"] for x in m),
            "bw_bound_rays_per_s": rungs.geomean(x["bw_bound_rays_per_s"] for x in m),
            "rays_per_dram_byte": rungs.geomean(x["rays_per_dram_byte"] for x in m),
            "dram_bytes_per_ray": statistics.fmean(x["dram_bytes_per_ray"] for x in m),
            "node_miss_rate": statistics.fmean(x["node_miss_rate"] for x in m),
            "cache_kib": m[0]["cache_kib"], "clock_mhz": m[0].get("clock_mhz"), "clock_source": m[0].get("clock_source"),
            "per_scene": {sc["name"]: x for sc, x in zip(scenes, m)}}
    a = rows.get("area", {}).get((pid, ""))
    if a is not None:
        if a["status"] in AREA_OK:
            s["metrics"]["area"] = rungs.metrics("area", a["result"])
            over = violations(sp, s["metrics"]["area"])
            if over:
                s["feasible"] = False
                s["notes"] += over
        elif a["status"] == st.SKIPPED:
            s["notes"].append(f"cost not known ({a['error']}); constraints unchecked")
        else:
            s["feasible"] = False
            s["errors"].append(f"area: {a['status']}: {a['error']}")
    cheap = {**s["metrics"].get("cachesim", {}), **s["metrics"].get("area", {})}
    s["objectives"] = {o: cheap.get(o) for o, _ in sp.objectives if cheap.get(o) is not None}
    return s


def violations(sp, cost):
    """Why a cost (rungs.metrics of a cost rung) breaks the space's constraints; [] when it meets them."""
    out = ["does not fit the board"] if "fits" in sp.constraints and cost.get("fits") is False else []
    for lim, key in LIMITS.items():
        if lim in sp.constraints and cost.get(key) is not None and cost[key] > sp.constraints[lim]:
            out.append(f"{key} {cost[key]:g} > {lim} {sp.constraints[lim]:g}")
    return out


def with_yosys(sp, s, row):
    """A point's summary with its board verdict re-decided from a real synthesis (the yosys rung's row): the
    constraints are checked on Yosys's numbers instead of the model's; the objectives stay the model's, so every
    point is still ranked on one fidelity. A failed synthesis keeps the model's verdict, with a note."""
    s = {**s, "metrics": dict(s["metrics"]), "notes": list(s["notes"]), "errors": list(s["errors"])}
    s["model_feasible"] = s["feasible"]
    if row["status"] not in AREA_OK:
        s["notes"].append(f"Yosys: {row['status']}: {row['error']}; the model's verdict is kept")
        s["yosys"] = {"status": row["status"]}
        return s
    y = rungs.metrics("yosys", row["result"])
    s["metrics"]["yosys"] = y
    model_over = violations(sp, s["metrics"]["area"])
    over = violations(sp, y)
    s["notes"] = [n for n in s["notes"] if n not in model_over] + [f"Yosys: {n}" for n in over]
    s["feasible"] = not s["errors"] and "cachesim" in s["metrics"] and not over
    s["yosys"] = {"status": row["status"], "overturned": s["feasible"] != s["model_feasible"]}
    if s["yosys"]["overturned"]:
        s["notes"].append("the cost model said it meets the constraints, Yosys says it does not: left the front"
                          if s["model_feasible"] else "the cost model said it breaks the constraints, Yosys says it meets them")
    return s


def cost_errors(sp, sums):
    """Per synthesized point x resource: the cost model against Yosys (relative error model / Yosys - 1), the
    limit it was near, and both verdicts; and per resource the mean and max |error|."""
    out = []
    for s in sums:
        y = s["metrics"].get("yosys")
        if y is None:
            continue
        m = s["metrics"]["area"]
        lims = rungs.limits(sp.constraints, m)
        for r in rungs.RESOURCES:
            if m.get(r) is None or y.get(r) is None:
                continue
            out.append({"point": s["point"], "resource": r, "model": m[r], "yosys": y[r],
                        "rel_err": (m[r] - y[r]) / y[r] if y[r] else None,
                        "limits": ", ".join(f"{n} {lim:g}" for n, _, lim in lims[r]),
                        "model_feasible": s["model_feasible"], "yosys_feasible": s["feasible"]})
    summary = {}
    for r in rungs.RESOURCES:
        xs = [abs(e["rel_err"]) for e in out if e["resource"] == r and e["rel_err"] is not None]
        if xs:
            summary[r] = {"mean_abs": statistics.fmean(xs), "max_abs": max(xs), "n": len(xs)}
    return out, summary


def active_objectives(sp, sums):
    """The space's objectives that every feasible point has a value for (a cost objective drops out, with a
    note, when the cost rung is unavailable)."""
    ok = [s for s in sums if s["feasible"]]
    return [(o, d) for o, d in sp.objectives if ok and all(o in s["objectives"] for s in ok)]


def predicted_front(sp, sums):
    objs = active_objectives(sp, sums)
    cand = [s for s in sums if s["feasible"]]
    if not objs or not cand:
        return [], objs
    idx = pareto.front([[s["objectives"][o] for o, _ in objs] for s in cand], [d for _, d in objs])
    return [cand[i] for i in idx], objs


def rtl_view(s, scenes, rtl):
    """The RTL figures of a confirmed point: geometric mean rays/s over the scenes when every run passed its
    checks; otherwise the statuses (a check-failed run is not a result)."""
    per = [rtl.get((s["point"], sc["name"])) for sc in scenes]
    if any(r is None for r in per):
        return None
    if any(r["status"] != st.OK for r in per):
        return {"status": ",".join(sorted({r["status"] for r in per})),
                "errors": [r["error"] for r in per if r["status"] != st.OK]}
    m = {sc["name"]: rungs.metrics("rtl", r["result"]) for sc, r in zip(scenes, per)}
    return {"status": st.OK, "rays_per_s": rungs.geomean(x["rays_per_s"] for x in m.values()), "per_scene": m}


def rung_errors(sums, scenes, rtl):
    """Per confirmed point x scene: relative error of the MVA prediction and the bandwidth bound against the
    RTL's rays/s, of DRAM bytes per ray, and the node miss-rate difference (model - RTL)."""
    out = []
    for s in sums:
        v = rtl_view(s, scenes, rtl)
        if not v or v["status"] != st.OK or "cachesim" not in s["metrics"]:
            continue
        for name, r in v["per_scene"].items():
            c = s["metrics"]["cachesim"]["per_scene"][name]
            rel = lambda a, b: (a - b) / b if b else None  # noqa: E731
            out.append({"point": s["point"], "scene": name, "rtl_rays_per_s": r["rays_per_s"],
                        "mva_rel_err": rel(c["rays_per_s"], r["rays_per_s"]),
                        "bw_bound_rel_err": rel(c["bw_bound_rays_per_s"], r["rays_per_s"]),
                        "dram_bytes_rel_err": rel(c["dram_bytes_per_ray"], r["dram_bytes_per_ray"]),
                        "node_miss_rate_diff": (c["node_miss_rate"] - r["node_miss_rate"]) if r["node_miss_rate"] is not None else None})
    summary = {}
    for k in ("mva_rel_err", "bw_bound_rel_err", "dram_bytes_rel_err", "node_miss_rate_diff"):
        xs = [abs(e[k]) for e in out if e[k] is not None]
        if xs:
            summary[k] = {"mean_abs": statistics.fmean(xs), "max_abs": max(xs), "n": len(xs)}
    return out, summary


def best_per_board(sp, sums, scenes, rtl):
    """The feasible point with the most predicted rays/s per board (one fidelity for every candidate, so they
    compare), skipping points whose RTL run failed; the RTL's figure is attached where it was confirmed."""
    boards = sp.axes.get("BOARD") or ([sp.base["BOARD"]] if "BOARD" in sp.base else
                                      [sp.constraints["fits"]] if sp.constraints.get("fits", "BOARD") != "BOARD" else [""])
    out = {}
    for b in boards:
        best = None
        for s in sums:
            if not s["feasible"] or "cachesim" not in s["metrics"] or (b and s["config"].get("BOARD", b) != b):
                continue
            v = rtl_view(s, scenes, rtl)
            if v and v["status"] != st.OK:
                continue  # the RTL disagreed with the model or failed: not a configuration to recommend
            rps, kib = s["metrics"]["cachesim"]["rays_per_s"], s["metrics"]["cachesim"]["cache_kib"]
            # equal rays/s (a compute-bound point): the smaller cache is the better recommendation
            if best is None or rps > best["rays_per_s"] * (1 + 1e-9) or (rps >= best["rays_per_s"] * (1 - 1e-9) and kib < best["cache_kib"]):
                best = {"point": s["point"], "config": s["config"], "rays_per_s": rps, "cache_kib": kib,
                        "rtl_rays_per_s": v["rays_per_s"] if v else None,
                        "constraints_checked": "area" in s["metrics"] or not sp.constraints, "make": verilog_command(s["config"])}
        out[b or "any"] = best
    return out


def _fmt(v):
    return "" if v is None else f"{v:.6g}" if isinstance(v, float) else str(v)


def provenance(sp, scenes, version):
    base = ",".join(f"{k}={v}" for k, v in sp.base.items()) or "-"
    return (f"# space={sp.name} file={os.path.relpath(sp.path)} scenes={','.join(s['label'] for s in scenes)} "
            f"rays={','.join(s['rays_id'] for s in scenes)} config={base} rtaccel={version}\n")


def time_split(times, stats):
    """Seconds per part of the runs made in this invocation: JVM start-up (all workers), and for the cache
    model the scene load, BVH build, trace and replay inside the server (0 where a worker kept them)."""
    out = {"jvm_start_s": sum(w["jvm_start_s"] for w in stats), "jvm_starts": sum(w["jvm_starts"] for w in stats)}
    for fid, t in times.items():
        out[fid] = {k: round(v, 4) if isinstance(v, float) else v for k, v in t.items()}
    return out


def write(sp, scenes, out, version, sums, rtl, confirmed, counts, stats, times):
    prov = provenance(sp, scenes, version)
    front, objs = predicted_front(sp, sums)
    on_front = {s["point"] for s in front}
    knobs = [k for k in KNOBS if any(k in s["config"] for s in sums)]
    mcols = ["rays_per_s", "bw_bound_rays_per_s", "rays_per_dram_byte", "dram_bytes_per_ray", "node_miss_rate", "cache_kib",
             "clock_mhz", "clock_source"]
    acols = ["lut", "lutram", "ff", "dsp", "bram36", "fits"]
    cols = ["point", *knobs, "feasible", "on_front", "confirmed", *[f"model_{c}" for c in mcols], *[f"area_{c}" for c in acols],
            *[f"yosys_{c}" for c in acols], "rtl_status", "rtl_rays_per_s", "notes", "errors"]
    lines = []
    for s in sums:
        v = rtl_view(s, scenes, rtl) or {}
        m, a, y = s["metrics"].get("cachesim", {}), s["metrics"].get("area", {}), s["metrics"].get("yosys", {})
        row = [s["point"], *[s["config"].get(k, "") for k in knobs], s["feasible"], s["point"] in on_front,
               s["point"] in confirmed, *[m.get(c) for c in mcols], *[a.get(c) for c in acols], *[y.get(c) for c in acols],
               v.get("status", ""),
               v.get("rays_per_s"), "; ".join(s["notes"]), "; ".join(s["errors"])]
        lines.append(",".join(_csv(_fmt(x)) for x in row))
    csv_path = os.path.join(out, "points.csv")
    write_text(csv_path, prov + ",".join(cols) + "\n" + "".join(l + "\n" for l in lines))
    runs = st.Store(os.path.join(out, "store.sqlite"))
    try:
        rr = [r for r in runs.rows(sp.name) if r["point"] in {s["point"] for s in sums}]
    finally:
        runs.close()
    write_text(os.path.join(out, "runs.csv"), prov + "point,scene,fidelity,status,exit,wall_s,error\n" + "".join(
        ",".join(_csv(_fmt(x)) for x in (r["point"], r["scene"], r["fidelity"], r["status"], r["exit"], r["wall_s"], r["error"])) + "\n"
        for r in rr))
    errs, err_summary = rung_errors(sums, scenes, rtl)
    cerrs, cerr_summary = cost_errors(sp, sums)
    best = best_per_board(sp, sums, scenes, rtl)
    pareto_json = [{"point": s["point"], "config": s["config"], **s["objectives"],
                    "rtl": (lambda v: {k: v[k] for k in ("status", "rays_per_s") if k in v} if v else None)(rtl_view(s, scenes, rtl))}
                   for s in front]
    split = time_split(times, stats)
    md = _markdown(sp, prov, front, objs, confirmed, errs, err_summary, best, counts, stats, sums, split, cerrs, cerr_summary)
    write_text(os.path.join(out, "front.md"), prov.replace("# ", "<!-- ", 1).rstrip() + " -->\n" + md["front"])
    write_text(os.path.join(out, "report.md"), prov.replace("# ", "<!-- ", 1).rstrip() + " -->\n" + md["report"])
    print(md["front"], file=sys.stderr)
    _plots(sp, out, prov, sums, on_front, set(confirmed), scenes, rtl)
    return {"pareto": pareto_json, "rung_error": err_summary, "best_per_board": best, "csv": csv_path, "time_split": split,
            "cost_rung_error": cerr_summary, "yosys_overturned": [s["point"] for s in sums if (s.get("yosys") or {}).get("overturned")]}


def _csv(s):
    return f'"{s}"' if ("," in s or '"' in s) else s


def _markdown(sp, prov, front, objs, confirmed, errs, err_summary, best, counts, stats, sums, split, cerrs, cerr_summary):
    names = [o for o, _ in objs]
    f = [f"## Predicted Pareto front ({', '.join(f'{d}imize {o}' for o, d in objs) or 'no objective measured'})\n",
         "| point | configuration | " + " | ".join(names) + " | RTL rays/s |", "|---|---|" + "---|" * len(names) + "---|"]
    for s in front:
        f.append(f"| {s['point']} | {' '.join(f'{k}={v}' for k, v in s['config'].items())} | "
                 + " | ".join(_fmt(s["objectives"].get(o)) for o in names) + f" | {_rtl_cell(s, confirmed)} |")
    dropped = [o for o, _ in sp.objectives if o not in names]
    if dropped:
        f.append(f"\nNot ranked on {', '.join(dropped)}: not measured ({_first_note(sums)}).")
    r = [f"# Design-space exploration: {sp.name}\n", sp.description + "\n" if sp.description else "", "\n".join(f), "\n",
         "## Best configuration per board\n", "| board | point | predicted rays/s | RTL rays/s | constraints | command |", "|---|---|---|---|---|---|"]
    for b, v in best.items():
        r.append(f"| {b} | {v['point']} | {v['rays_per_s']:.4g} | {_fmt(v['rtl_rays_per_s']) or 'not confirmed'} | "
                 f"{'met' if v['constraints_checked'] else 'unchecked (no cost)'} | `{v['make']}` |" if v else f"| {b} | none feasible | | | | |")
    r += ["\n## Cheap rungs against the RTL (confirmed points)\n"]
    if errs:
        r += ["| point | scene | RTL rays/s | MVA error | bandwidth-bound error | DRAM bytes/ray error | node miss rate diff |",
              "|---|---|---|---|---|---|---|"]
        pct = lambda x: "" if x is None else f"{100 * x:+.1f} %"  # noqa: E731
        for e in errs:
            r.append(f"| {e['point']} | {e['scene']} | {e['rtl_rays_per_s']:.4g} | {pct(e['mva_rel_err'])} | {pct(e['bw_bound_rel_err'])} | "
                     f"{pct(e['dram_bytes_rel_err'])} | {_fmt(e['node_miss_rate_diff'])} |")
        r.append("\n" + "; ".join(f"{k}: mean |err| {v['mean_abs']:.3g}, max {v['max_abs']:.3g} (n={v['n']})" for k, v in err_summary.items()))
    else:
        r.append("No point was confirmed with the RTL (fidelity rtl = false, or no feasible point).")
    if sp.fidelity.get("yosys_margin") is not None:
        r += _yosys_section(sp, sums, cerrs, cerr_summary)
    r += ["\n## Runs\n", "| fidelity | evaluated | reused from the store | failed |", "|---|---|---|---|"]
    r += [f"| {k} | {v['evaluated']} | {v['skipped']} | {v['failed']} |" for k, v in counts.items()]
    r += ["\nWorkers: " + ", ".join(f"{w['worker']} ({w['jvm_starts']} JVM start(s), {w['jvm_start_s']:.1f} s)" for w in stats)]
    c = split.get("cachesim")
    if c:
        r.append(f"\nCache-model runs made now: {c['runs']} in {c['worker_s']:.1f} worker-s; inside the server: scene load "
                 f"{c.get('load_s', 0):.2f} s, BVH {c.get('bvh_s', 0):.2f} s, trace {c.get('trace_s', 0):.2f} s, replay "
                 f"{c.get('replay_s', 0):.2f} s (kept scenes, trees and traces cost 0)")
    failed = [s for s in sums if s["errors"]]
    if failed:
        r += ["\n## Failed points (data, not results)\n"] + [f"- {s['point']}: {'; '.join(s['errors'])}" for s in failed]
    return {"front": "\n".join(f) + "\n", "report": "\n".join(r) + "\n"}


def _yosys_section(sp, sums, cerrs, cerr_summary):
    m = sp.fidelity["yosys_margin"]
    r = [f"\n## Cost model against Yosys (points within {100 * m:g} % of a limit)\n"]
    tried = [s for s in sums if "yosys" in s]
    if not tried:
        return r + ["No point the sweep would confirm (nor a board's best) had a model cost that close to a limit."]
    verdict = lambda ok: "meets" if ok else "breaks"  # noqa: E731
    r += ["| point | resource | model | Yosys | model error | limits | verdict (model → Yosys) |", "|---|---|---|---|---|---|---|"]
    for e in cerrs:
        err = "" if e["rel_err"] is None else f"{100 * e['rel_err']:+.1f} %"
        r.append(f"| {e['point']} | {e['resource']} | {e['model']:g} | {e['yosys']:g} | {err} | {e['limits']} | "
                 f"{verdict(e['model_feasible'])} → {verdict(e['yosys_feasible'])} |")
    if cerr_summary:
        r.append("\n" + "; ".join(f"{k}: mean |err| {v['mean_abs']:.3g}, max {v['max_abs']:.3g} (n={v['n']})" for k, v in cerr_summary.items()))
    out = [s for s in tried if s["yosys"].get("overturned")]
    if out:
        r.append("\nRe-decided by Yosys: " + "; ".join(f"{s['point']} ({s['notes'][-1]})" for s in out) + ".")
    bad = [s for s in tried if s["yosys"]["status"] not in AREA_OK]
    if bad:
        r.append("\nSynthesis failed (the model's verdict kept): " + ", ".join(s["point"] for s in bad) + ".")
    return r


def _first_note(sums):
    return next((n for s in sums for n in s["notes"]), "rung unavailable")


def _rtl_cell(s, confirmed):
    return "confirmed" if s["point"] in confirmed else "not confirmed"


def _plots(sp, out, prov, sums, on_front, confirmed, scenes, rtl):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [s for s in sums if "cachesim" in s["metrics"]]
    has_cost = any("area" in s["metrics"] for s in ok)
    xs = [("lut", "LUTs"), ("bram36", "BRAM36")] if has_cost else [("cache_kib", "on-chip cache (KiB)")]
    for key, label in xs:
        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        pts = [(s, {**s["metrics"]["cachesim"], **s["metrics"].get("area", {})}) for s in ok]
        pts = [(s, m) for s, m in pts if m.get(key) is not None]
        for grp, style in (("rest", dict(c="0.7", marker="o", s=18)), ("front", dict(c="C0", marker="o", s=36))):
            sel = [(s, m) for s, m in pts if (s["point"] in on_front) == (grp == "front") and s["feasible"]]
            ax.scatter([m[key] for _, m in sel], [m["rays_per_s"] for _, m in sel], label=f"model ({grp})", **style)
        inf = [(s, m) for s, m in pts if not s["feasible"]]
        if inf:
            ax.scatter([m[key] for _, m in inf], [m["rays_per_s"] for _, m in inf], c="C3", marker="x", s=24, label="infeasible")
        conf = [(m[key], v["rays_per_s"]) for s, m in pts if s["point"] in confirmed
                for v in [rtl_view(s, scenes, rtl)] if v and v["status"] == st.OK]
        if conf:
            ax.scatter(*zip(*conf), c="C2", marker="*", s=90, label="RTL (confirmed)")
        ax.set_xlabel(label)
        ax.set_ylabel("rays/s (geometric mean over scenes)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{sp.name}: rays/s vs {label}")
        fig.text(0.01, 0.005, prov[2:].strip()[:150], fontsize=5, color="0.4")
        save_png(fig, os.path.join(out, f"pareto_{key}.png"))
        plt.close(fig)
