"""Stand-in for `java ... rtaccel.cli.<Main>` in the dse.paper.caches tests (no JVM needed).

Speaks the entry points' contract: `--key value` arguments, CacheSim's last stdout line is its JSON (and
--sweep-out writes the miss-rate CSV), SweepTus writes OUT/tus_sweep.csv. The numbers are simple functions
of MPPL and the cache sizes so the tests can predict every output cell. FAKE_JAVA_MODE=refuse makes it fail
like an entry point refusing input (one `error:` line, status 2); crash = a JVM exception (status 1);
nocache = a SweepTus built before the RTL cache (ignores --node-cache); check-fails = the run completes but a
check of its own fails (JSON line with "ok": false and "failures", `error: check failed` line, status 3), for
every entry point, or only for SweepTus with check-fails-tus; check-fails-nojson = status 3 without that line.
"""
import json
import os
import sys

SWEEP = """config,256,512,1024,2048,4096,8192
dm,0.27415,0.19988,0.11812,0.06450,0.02890,0.01094
bf,0.25747,0.19675,0.12642,0.07348,0.02950,0.00512
lrp0,0.27272,0.19905,0.11796,0.06437,0.02886,0.01094
lrp1,0.26796,0.19618,0.11754,0.06407,0.02875,0.01092
lrp2,0.25389,0.18973,0.11637,0.06336,0.02850,0.01091
lrp3,0.24493,0.18387,0.11121,0.06182,0.02783,0.01082
lrp4,0.24164,0.17492,0.10556,0.05802,0.02646,0.01032
lrp5,0.24331,0.17764,0.11163,0.05861,0.02491,0.00983
lrp6,0.24527,0.18035,0.11415,0.06240,0.02695,0.00913
lru_4way,0.22402,0.14872,0.08963,0.04666,0.01912,0.00666
# 90 replays, 128420640 node accesses in 3.22 s
"""


def cachesim(a):
    mppl = int(a["mppl"])
    node_c, prim_c = int(a.get("node-cache", 0)), int(a.get("prim-cache", 0))
    node_nc, prim_nc = 2600.0 / mppl, 400.0 + 10 * mppl  # bytes per ray without caches
    node_mr = 0.01 if node_c == 8192 else 0.03 if node_c else 1.0
    prim_mr = 0.4 if prim_c else 1.0
    if "sweep-out" in a:
        with open(a["sweep-out"], "w") as f:
            f.write(SWEEP)
        sys.stderr.write(SWEEP)  # CacheSim echoes the grid on stderr
    j = {"scene": a["scene-label"], "rtaccel": "fake-1", "config": a["config"], "m": int(a["m"]), "mppl": mppl,
         "tus": 1, "rays": 1000, "nodes": 500, "node_cache": {"entries": node_c, "miss_rate": node_mr},
         "prim_cache": {"entries": prim_c, "miss_rate": prim_mr},
         "node_bytes_per_ray": node_nc * node_mr, "prim_bytes_per_ray": prim_nc * prim_mr,
         "dram_bytes_per_ray": node_nc * node_mr + prim_nc * prim_mr,
         "node_bytes_per_ray_nocache": node_nc, "prim_bytes_per_ray_nocache": prim_nc}
    print("some log line")
    print(json.dumps(j))


def sweeptus(a, mode):
    cache = "none" if mode == "nocache" else f"{a['node-cache']}x1-{a['node-policy']}"
    rows = []
    for t in a["tus-list"].split(","):
        sys.stderr.write(f"[sweep] {a['scene-label']}: TUs={t}\n")
        rows.append(f"{t},1000,{100000 // int(t)},{1500.0 * int(t)},{min(0.5, 0.05 * int(t))},28.5,443.1,0,0,1,"
                    f"471.6,0.01094,,0.01090,")
    os.makedirs(a["out"], exist_ok=True)
    with open(os.path.join(a["out"], "tus_sweep.csv"), "w") as f:
        f.write(f"# scene={a['scene-label']} rays=1000 config={a['config']} M=4 MPPL=4 node_cache={cache} "
                f"prim_cache=none rtaccel=fake-1\n"
                "tus,rays,cycles,rays_per_s,mem_utilisation,node_bytes_per_ray,prim_bytes_per_ray,stall_memory_data,"
                "tu_busy_cycles,sim_cycles_per_wall_s,dram_bytes_per_ray,node_cache_miss_rate,prim_cache_miss_rate,"
                "model_node_miss_rate,model_prim_miss_rate\n" + "\n".join(rows) + "\n")
    print(json.dumps({"scene": a["scene-label"]}))


def main():
    main_class, rest = sys.argv[1], sys.argv[2:]
    a = dict(zip(rest[0::2], rest[1::2]))
    a = {k[2:]: v for k, v in a.items()}
    mode = os.environ.get("FAKE_JAVA_MODE", "")
    with open(os.environ["FAKE_JAVA_LOG"], "a") as f:  # the tests check which runs were made
        f.write(json.dumps([main_class, a]) + "\n")
    if mode == "refuse":
        print("error: MPPL 4 does not fit the 2-bit leaf count field", file=sys.stderr)
        sys.exit(2)
    if mode == "check-fails" or (mode == "check-fails-tus" and main_class == "rtaccel.cli.SweepTus"):
        failures = ["mismatch_vs_model=3", "lost=1"]
        print("some log line")
        print(json.dumps({"scene": a.get("scene-label"), "rtaccel": "fake-1", "ok": False, "failures": failures}))
        print(f"error: check failed: {', '.join(failures)}", file=sys.stderr)
        sys.exit(3)
    if mode == "check-fails-nojson":
        print("error: check failed: lost=1", file=sys.stderr)
        sys.exit(3)
    if mode == "crash":
        print('Exception in thread "main" java.lang.OutOfMemoryError: Java heap space\n\tat rtaccel.X', file=sys.stderr)
        sys.exit(1)
    {"rtaccel.cli.CacheSim": cachesim, "rtaccel.cli.SweepTus": lambda a: sweeptus(a, mode)}[main_class](a)


if __name__ == "__main__":
    main()
