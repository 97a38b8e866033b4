"""python -m dse.studies.bench_caches OUT.csv NAME DIR — the cache model against the RTL, one `make bench-caches` run.

DIR holds, per TU count N, `sim-tuN.json` (make simulate, last line) and `model-tuN.json` (make cachesim with
the same rays, caches and TUS=N, last line). For each N: node-cache miss rate of the RTL vs the fast model's
N-TU interleaving, rays/s of the RTL vs the model's prediction (MVA, rtaccel.cache.Throughput) and bandwidth bound, and wall time per ray of each (RTL:
simulation only, build excluded; model: the replay, median of its repeats, and trace + replay). Prints a table
and, last, one JSON line; writes OUT.csv with a provenance line. Bad input: one `error:` line, exit 2.
A run whose JSON says "ok": false (its own check failed) is refused with one `error:` line, exit 3.
"""
import json
import os
import re
import sys

from scenes.cli import run

from ..common import NoJsonResult, exit_check_failed, failures_text, last_json_file, provenance_line, write_text


def last_json(path):
    try:
        j = last_json_file(path)
    except (OSError, NoJsonResult) as e:
        raise SystemExit(f"error: {path}: no JSON result line ({e}); rerun make bench-caches")
    if j.get("ok") is False:  # a failed simulation's cycles and miss rates are no figures to compare
        exit_check_failed(f"{path}: the run's check failed ({failures_text(j)}); fix it and rerun make bench-caches")
    return j


def rows(d):
    tus = sorted(int(m.group(1)) for f in os.listdir(d) if (m := re.fullmatch(r"sim-tu(\d+)\.json", f)))
    if not tus:
        raise SystemExit(f"error: no sim-tuN.json in {d}; rerun make bench-caches")
    out = []
    for n in tus:
        s, m = last_json(os.path.join(d, f"sim-tu{n}.json")), last_json(os.path.join(d, f"model-tu{n}.json"))
        if s["rays"] != m["rays"] or s["tus"] != m["tus"]:
            raise SystemExit(f"error: TUS={n}: RTL and model ran different rays or TU counts")
        sc, mc = s["node_cache"], m["node_cache"]
        if sc.get("entries", 0) == 0 or sc["entries"] != mc["entries"] or sc["policy"] != mc["policy"]:
            raise SystemExit(f"error: TUS={n}: RTL and model must simulate the same node cache")
        rays = s["rays"]
        sim_wall = s["sim_wall_s"]
        out.append({
            "tus": n, "rays": rays, "policy": sc["policy"], "entries": sc["entries"],
            "rtl_miss_rate": sc["miss_rate"], "model_miss_rate": mc["miss_rate"],
            "miss_rate_diff_points": 100 * (mc["miss_rate"] - sc["miss_rate"]),
            "rtl_counts_match_model_same_order": s["cache_counts_match_model"],
            "rtl_rays_per_s": s["rays_per_s_at_clock"], "model_bw_bound_rays_per_s": m["bandwidth_bound_rays_per_s"],
            "model_predicted_rays_per_s": m["predicted_rays_per_s"],
            "predicted_over_rtl": m["predicted_rays_per_s"] / s["rays_per_s_at_clock"],
            "rtl_dram_bytes_per_ray": s["dram_bytes_per_ray"], "model_dram_bytes_per_ray": m["dram_bytes_per_ray"],
            "rtl_sim_wall_s": sim_wall, "rtl_us_per_ray": 1e6 * sim_wall / rays,
            "model_replay_us_per_ray": 1e6 * m["wall_s"] / rays,
            "model_trace_replay_us_per_ray": 1e6 * (m["trace_s"] + m["wall_s"]) / rays,
            "model_accesses_per_s": m["accesses_per_s"], "model_repeat": m.get("repeat", 1),
            "scene": s["scene"], "config": s["config"], "rtaccel": s["rtaccel"]})
    return out


def main(out_csv, name, d):
    rs = rows(d)
    cols = list(rs[0].keys())
    prov = provenance_line(rs[0]["scene"], rs[0]["config"], rs[0]["rtaccel"],
                           fields={"node_cache": f"{rs[0]['entries']}x{rs[0]['policy']}"})
    write_text(out_csv, prov + ",".join(cols) + "\n" + "".join(
        ",".join(f"{r[c]:.6g}" if isinstance(r[c], float) else str(r[c]) for c in cols) + "\n" for r in rs))
    print(f"[bench-caches] {name}: {rs[0]['rays']} rays, node cache {rs[0]['entries']} {rs[0]['policy']}; "
          f"RTL = Verilator simulation (build excluded), model = trace-driven replay (median of {rs[0]['model_repeat']})")
    print(f"  {'TUs':>4} {'miss RTL':>9} {'model':>8} {'diff pp':>8} {'rays/s RTL':>11} {'predicted':>10} {'pred/RTL':>8} {'BW bound':>9} "
          f"{'us/ray RTL':>10} {'model':>7} {'+trace':>7} {'RTL/model':>9} {'accesses/s':>10}")
    for r in rs:
        print(f"  {r['tus']:>4} {100 * r['rtl_miss_rate']:8.3f}% {100 * r['model_miss_rate']:7.3f}% "
              f"{r['miss_rate_diff_points']:+8.3f} {r['rtl_rays_per_s']:11.4g} {r['model_predicted_rays_per_s']:10.4g} "
              f"{r['predicted_over_rtl']:8.2f} {r['model_bw_bound_rays_per_s']:9.4g} "
              f"{r['rtl_us_per_ray']:10.1f} {r['model_replay_us_per_ray']:7.3f} {r['model_trace_replay_us_per_ray']:7.2f} "
              f"{r['rtl_us_per_ray'] / r['model_replay_us_per_ray']:8.0f}x {r['model_accesses_per_s']:10.3g}")
    print(json.dumps({"scene": name, "csv": out_csv, "rows": rs}))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        raise SystemExit("error: usage: python -m dse.studies.bench_caches OUT.csv NAME DIR")
    run(lambda _: main(*sys.argv[1:4]))  # an unwritable OUT.csv: one error line, like every other bad input
