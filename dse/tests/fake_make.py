"""Stand-in for `make <target> VAR=value ...` in the dse.paper.paper tests (no JVM, no Verilator).

Writes, for the targets make paper runs (golden, paper-nocache, paper-caches, analyze, roofline, area, bench), files of
the shape the real targets write, with numbers chosen so a test can find them in the report. Appends one line
per call to $FAKE_MAKE_CALLS. FAKE_MAKE_FAIL=<target> makes that target print an error and exit 3, as a
sub-make whose own check failed.
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fake_java import SWEEP  # noqa: E402

PROV = "# scene={s} triangles=66450 config={c} M=4 rays=1000 rtaccel=fake-1{x}\n"
RTL_RAYS_PER_S = 287654.0  # our Table 2 number, easy to find in the report
FMAX_MHZ = 156.25  # the clock make area's proxy gives the Table 2 circuit
FMAX_RAYS_PER_S = 298765.0  # our Table 2 number at that clock
EMBREE_RAYS_PER_S = 2.5e6


def put(path, text):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w" if isinstance(text, str) else "wb") as f:
        f.write(text)


def png(path):
    put(path, b"\x89PNG\r\n\x1a\n")


def name(mesh):
    return os.path.splitext(os.path.basename(mesh))[0]


def analyze(out, scene):
    rows = "".join(f"{m},1000,{500 // m},{300 // m},12,{40000 - 1000 * m},{3000 + 100 * m},{4000 + 300 * m},"
                   f"{2600 - 10 * m:.3f},{300 + 15 * m:.3f},{2900 + 5 * m:.3f}\n" for m in (1, 2, 4, 8, 16))
    put(os.path.join(out, "bandwidth_vs_mppl.csv"), PROV.format(s=scene, c="fit", x="") +
        "mppl,rays,nodes,leaves,depth,node_accesses,leaf_accesses,prim_accesses,node_bytes_per_ray,"
        "prim_bytes_per_ray,total_bytes_per_ray\n" + rows)
    nodes = [1, 4, 16, 60, 200, 400, 300, 100]
    acc = [1000, 3000, 5000, 6000, 5000, 3000, 1000, 200]
    cn, ca = [sum(nodes[: i + 1]) / sum(nodes) for i in range(8)], [sum(acc[: i + 1]) / sum(acc) for i in range(8)]
    put(os.path.join(out, "levels.csv"), PROV.format(s=scene, c="fit", x=" levels_for_mppl=4") +
        "level,nodes,accesses,accesses_per_node,cum_node_share,cum_access_share\n" +
        "".join(f"{i},{nodes[i]},{acc[i]},{acc[i] / nodes[i]:.4f},{cn[i]:.6f},{ca[i]:.6f}\n" for i in range(8)))
    png(os.path.join(out, "bandwidth_vs_mppl.png"))
    png(os.path.join(out, "levels.png"))


def tus_csv(path, scene, cache, tus):
    rows = "".join(f"{t},1000,{100000 // t},{(90000.0 if cache == 'none' else 100000.0) * min(t, 4 if cache == 'none' else t)},"
                   f"{min(0.5, 0.12 * t) if cache == 'none' else 0.02 * t:.4f},28.5,443.1,0,0,1,471.6,0.01,,0.01,\n"
                   for t in tus)
    put(path, f"# scene={scene} rays=1000 config=paper2017 M=4 MPPL=4 node_cache={cache} prim_cache=none rtaccel=fake-1\n"
        "tus,rays,cycles,rays_per_s,mem_utilisation,node_bytes_per_ray,prim_bytes_per_ray,stall_memory_data,"
        "tu_busy_cycles,sim_cycles_per_wall_s,dram_bytes_per_ray,node_cache_miss_rate,prim_cache_miss_rate,"
        "model_node_miss_rate,model_prim_miss_rate\n" + rows)


def caches(d, scene, tus):
    put(os.path.join(d, "fig11_miss_rate.csv"), PROV.format(s=scene, c="fit", x=" figure=11") + SWEEP)
    rows = []
    for m in (1, 2, 4, 8, 16):
        nb, pb = 2600.0 / m, 400.0 + 10 * m
        rows += [f"{m},nocache,{nb:.3f},{pb:.3f},{nb + pb:.3f},,", f"{m},node,{nb * 0.04:.3f},{pb:.3f},{nb * 0.04 + pb:.3f},0.04000,",
                 f"{m},node_prim,{nb * 0.07:.3f},{pb * 0.5:.3f},{nb * 0.07 + pb * 0.5:.3f},0.07000,0.50000"]
    put(os.path.join(d, "fig8_9_bytes_per_ray.csv"), PROV.format(s=scene, c="fit", x=" figures=4,8,9") +
        "mppl,variant,node_bytes_per_ray,prim_bytes_per_ray,dram_bytes_per_ray,node_miss_rate,prim_miss_rate\n" +
        "\n".join(rows) + "\n")
    png(os.path.join(d, "fig11_miss_rate.png"))
    png(os.path.join(d, "fig8_9_bytes_per_ray.png"))
    if tus:
        tus_csv(os.path.join(d, "tus_sweep.csv"), scene, "8192x1-dm", tus)
        png(os.path.join(d, "fig12_13_tus.png"))


def roofline(out, scene, tus, clock):
    """At CLOCK_MHZ=fmax only after make area wrote the circuit's result (the real command refuses otherwise)."""
    if clock == "fmax" and not os.path.isfile(os.path.join(os.path.dirname(out), "table2-area", "area.json")):
        print("error: CLOCK_MHZ=fmax: no measured clock of this circuit is cached; make one with `make area ...`",
              file=sys.stderr)
        return 2
    mhz, src, rps = (FMAX_MHZ, "proxy", FMAX_RAYS_PER_S) if clock == "fmax" else (150.0, "board", RTL_RAYS_PER_S)
    put(os.path.join(out, "roofline.csv"), f"# scene={scene} config=paper2017 clock_mhz={mhz} clock_source={src} "
        "ius=1 mem_channels=1 rtaccel=fake-1\n"
        "tus,rays,cycles,rays_per_s,memory_bound,compute_bound,binding,dram_bytes_per_ray,util_memory\n"
        f"{tus},1000,52146,{rps},310000,900000,memory,180.5,0.93\n")
    png(os.path.join(out, "roofline.png"))


def bench(scene):
    d = os.path.join("build", "bench", name(scene))
    put(os.path.join(d, "model.json"), json.dumps({"rays": 1000, "model_rays_per_s_median": 5e5, "rtaccel": "fake-1",
                                                   "config": "fit", "model_build_s_median": 1.0}) + "\n")
    put(os.path.join(d, "embree.json"), json.dumps({"rays": 1000, "embree_rays_per_s_median": EMBREE_RAYS_PER_S,
                                                    "embree_build_s_median": 0.1}) + "\n")


def main(argv):
    args = [a for a in argv if not a.startswith("-")]
    target, v = args[0], dict(a.split("=", 1) for a in args[1:])
    calls = os.environ.get("FAKE_MAKE_CALLS")
    if calls:
        with open(calls, "a") as f:
            f.write(" ".join(args) + "\n")
    if os.environ.get("FAKE_MAKE_FAIL") == target:
        print(f"error: {target}: TUS=8 mismatch 3 rays", file=sys.stderr)
        return 3
    tus = [int(t) for t in v.get("PAPER_TUS", v.get("NOCACHE_TUS", "")).split(",") if t]
    if target == "golden":
        put(os.path.join(v["OUT"], "rays.npy"), b"\x93NUMPY")
    elif target == "paper-nocache":
        s = v["NOCACHE_SCENES"]
        tus_csv(os.path.join("build", "paper-nocache", name(s), "tus_sweep.csv"), s, "none", tus)
    elif target == "paper-caches":
        caches(os.path.join("build", "paper-caches", name(v["SCENE"])), v["SCENE"], tus)
    elif target == "analyze":
        analyze(v["OUT"], v["SCENE"])
    elif target == "roofline":
        rc = roofline(v["OUT"], v["SCENE"], v["TUS"], v.get("CLOCK_MHZ"))
        if rc:
            return rc
    elif target == "area":
        put(os.path.join(v["OUT"], "area.json"), json.dumps({"config": v["CONFIG"], "fmax_mhz_proxy": FMAX_MHZ}) + "\n")
    elif target == "bench":
        bench(v["BENCH_SCENES"])
    else:
        print(f"fake make: unknown target {target}", file=sys.stderr)
        return 2
    print(f"fake make {target} done")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
