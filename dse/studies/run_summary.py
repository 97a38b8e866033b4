"""python -m dse.studies.run_summary RUN_DIR — the readable end of `make run`.

Reads the last JSON line of RUN_DIR/check.log (model vs Embree) and RUN_DIR/analyze.log (memory-access
analysis), and of RUN_DIR/simulate.log (RTL) when there is one, prints a short report, and as its last line one
JSON object with the headline metrics. Exit status 3 when the simulation's own check failed ("ok": false): the
report still shows its numbers and failures, then one `error:` line.
"""
import json
import sys
from pathlib import Path

from ..common import NoJsonResult, exit_check_failed, failures_text, last_json_file


def last_json(path: Path) -> dict:
    try:
        return last_json_file(path)
    except NoJsonResult:
        raise SystemExit(f"error: no JSON result line in {path}; the step that writes it failed")


def main(run_dir: str) -> None:
    d = Path(run_dir)
    check, analysis = last_json(d / "check.log"), last_json(d / "analyze.log")
    sim = last_json(d / "simulate.log") if (d / "simulate.log").exists() else None
    meta = json.loads((d / "golden" / "meta.json").read_text())
    bpr = analysis["bytes_per_ray"]
    k = str(analysis["levels_for_mppl"])
    print(f"scene       {meta.get('scene')}  ({meta.get('triangles')} triangles)")
    print(f"rays        {check['rays']}  (camera + path-traced bounces, per depth {meta.get('rays_per_depth')})")
    print(f"vs Embree   agree {check['agree']}, classified {check['classified']}, unexplained {check['unexplained']}, "
          f"max rel t err {check['max_rel_t_err']:.2e}")
    faults = check.get("faults") or {}
    if any(faults.values()):  # already counted in unexplained
        print(f"            model faults: read error {faults.get('read_error', 0)}, "
              f"stack overflow {faults.get('overflow', 0)}, step limit {faults.get('step_limit', 0)}")
    print("bytes/ray   MPPL: node / prim / total")
    for mppl, v in sorted(bpr.items(), key=lambda kv: int(kv[0])):
        print(f"            {int(mppl):>4}: {v['node']:9.1f} / {v['prim']:8.1f} / {v['total']:9.1f}")
    print(f"top 4 levels (MPPL {k}): {analysis['top4_levels_nodes']} nodes = {100 * analysis['top4_levels_node_share']:.1f}% "
          f"of nodes, {100 * analysis['top4_levels_access_share']:.1f}% of node accesses")
    if sim:
        print(f"RTL         {sim['config']}: {sim['tus']} TUs, M={sim['m']}, MPPL={sim['mppl']}: {sim['cycles']:.0f} cycles = "
              f"{sim['rays_per_s_at_clock']:.3g} rays/s at {sim['clock_mhz']:.0f} MHz, memory utilisation "
              f"{100 * sim['mem_utilisation']:.1f}% of peak")
        print(f"            vs model: mismatch {sim['mismatch_vs_model']}, lost {sim['lost']}, duplicated {sim['duplicated']}; "
              f"simulated {sim['sim_cycles_per_wall_s']:.3g} cycles per wall second")
        if "ok" in sim:
            print(f"            check: {'ok' if sim['ok'] else 'FAILED: ' + failures_text(sim)}")
        for name in ("node_cache", "prim_cache"):
            c = sim.get(name) or {}
            if c.get("entries"):
                same = c["model_same_order"]
                print(f"{name.replace('_', ' '):<11} {c['entries']} entries {c['ways']}-way {c['policy']}: hits {c['hits']:.0f}, "
                      f"misses {c['misses']:.0f} (miss rate {100 * c['miss_rate']:.2f}%); trace model on the RTL's order: "
                      f"hits {same['hits']:.0f}, misses {same['misses']:.0f}")
    print(f"outputs     {d}/golden, {d}/analysis (CSV + PNG), {d}/simulate")
    if (d / "simulate" / "image.png").exists():
        print(f"image       {d / 'simulate' / 'image.png'}")
    print(json.dumps({"scene": meta.get("scene"), "rays": check["rays"], "agree": check["agree"],
                      "unexplained": check["unexplained"], "node_bytes_per_ray": bpr[k]["node"],
                      "prim_bytes_per_ray": bpr[k]["prim"], "mppl": int(k),
                      "top4_levels_access_share": analysis["top4_levels_access_share"],
                      **({"rtl_cycles": sim["cycles"], "rtl_rays_per_s": sim["rays_per_s_at_clock"],
                          "rtl_mismatch_vs_model": sim["mismatch_vs_model"], "rtl_lost": sim["lost"],
                          "mem_utilisation": sim["mem_utilisation"],
                          "node_cache": sim.get("node_cache", {}), "prim_cache": sim.get("prim_cache", {}),
                          "cache_counts_match_model": sim.get("cache_counts_match_model"),
                          **({"rtl_ok": sim["ok"], "rtl_failures": sim.get("failures", [])} if "ok" in sim else {})}
                       if sim else {})}))
    if sim and sim.get("ok") is False:
        exit_check_failed(f"RTL simulation check failed: {failures_text(sim)}; see {d}/simulate.log")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "build/run")
