"""Stand-in for `java ... rtaccel.cli.Serve` in the dse.explore.explore tests (no JVM): the same JSON-lines protocol,
answers that are simple functions of the flags, so the tests can predict every figure and every front.

cachesim: predicted rays/s = 1e5 * TUS * (1 + NODE_CACHE / 256) (1.5 x that without head-of-line blocking); DRAM
bytes per ray = 1000 / (1 + NODE_CACHE / 64), node miss rate 1 / (1 + NODE_CACHE / 64).
simulate: rays/s = 0.8 x the prediction, DRAM bytes per ray 1.25 x the model's, node miss rate 0.001 below it. area: refused like a build without FIDELITY=model unless
FAKE_SERVE_AREA=1; then lut = 1000 * TUS + NODE_CACHE, bram36 = NODE_CACHE / 64, fits when lut <= 3000.
area --fidelity yosys (a real synthesis): the same figures with lut x FAKE_SERVE_YOSYS_SCALE (default 1.1), rounded.
FAKE_SERVE_REFUSE_TUS=n: every run with TUS=n is refused (status 2); FAKE_SERVE_CHECK_FAIL_TUS=n: its RTL run
fails a check (status 3); FAKE_SERVE_CRASH_TUS=n: the server process dies on its cachesim request.
FAKE_SERVE_SLEEP=s: each answer takes s seconds (so a test can kill a sweep in the middle).
Every request is appended to $FAKE_SERVE_LOG (one JSON line) so the tests see which runs were made.
"""
import json
import os
import sys
import time


def answer(cmd, a):
    tus, nc = int(a.get("tus", 32)), int(a.get("node-cache", 8192))
    env = os.environ.get
    if env("FAKE_SERVE_REFUSE_TUS") == str(tus):
        return 2, None, f"TUS={tus} is refused by this fake"
    pred = 1e5 * tus * (1 + nc / 256)
    if cmd == "cachesim":
        if env("FAKE_SERVE_CRASH_TUS") == str(tus):
            sys.exit(134)
        bpr = 1000 / (1 + nc / 64)
        clk = clock(a)
        if isinstance(clk, str):
            return 2, None, clk
        return 0, {"scene": a["scene-label"], "rtaccel": "fake-1", "config": a.get("config", "fit"), "tus": tus, "rays": 100, **clk,
                   "node_accesses": 1000, "node_bytes_per_ray_nocache": 1280.0, "predicted_rays_per_s": pred,
                   "bandwidth_bound_rays_per_s": 2 * pred, "dram_bytes_per_ray": bpr,
                   "node_cache": {"entries": nc, "miss_rate": 1 / (1 + nc / 64)}, "prim_cache": {"entries": 0, "miss_rate": 1.0},
                   "predicted_rays_per_s_no_hol": 1.5 * pred, "trace_s": 0.5, "wall_s": 0.25, "predict_s": 1e-4}, None
    if cmd == "area":
        if env("FAKE_SERVE_AREA") != "1":
            return 2, None, "FIDELITY=model is not available: only FIDELITY=yosys (a real synthesis) is built so far"
        lut = 1000 * tus + nc
        fid = a.get("fidelity", "yosys")
        if fid == "yosys":
            lut = round(lut * float(env("FAKE_SERVE_YOSYS_SCALE", "1.1")))
        j = {"config": a.get("config"), "board": a.get("board"), "family": "xc7", "fidelity": fid, "lut": lut, "lutram": 0,
             "ff": 2 * lut, "dsp": 4 * tus, "bram36": nc / 64, "fits": lut <= 3000, "first_overflow": None, "units": {}}
        return (0 if j["fits"] else 3), j, (None if j["fits"] else f"check failed: does not fit: lut {lut} > 3000")
    if cmd == "simulate":
        j = {"rays": 100, "rays_per_s_at_clock": 0.8 * pred, "dram_bytes_per_ray": 1250 / (1 + nc / 64),
             "node_cache": {"entries": nc, "miss_rate": 1 / (1 + nc / 64) - 0.001}, "prim_cache": {"entries": 0},
             "sim_wall_s": 2.0, "ok": True, "failures": []}
        if env("FAKE_SERVE_CHECK_FAIL_TUS") == str(tus):
            j.update(ok=False, failures=["mismatch_vs_model"])
            return 3, j, "check failed: mismatch_vs_model"
        return 0, j, None
    return 2, None, f"unknown cmd '{cmd}'"


def clock(a):
    """The clock a run names, as the real commands do: CLOCK_MHZ=<MHz> (given), none (board: 150 MHz) or
    CLOCK_MHZ=fmax, which the real JVM resolves from a cached measurement: FAKE_SERVE_FMAX_MHZ stands for one."""
    c = a.get("clock-mhz")
    if c == "fmax":
        f = os.environ.get("FAKE_SERVE_FMAX_MHZ")
        return ({"clock_mhz": float(f), "clock_source": "proxy"} if f else
                "CLOCK_MHZ=fmax: no measured clock of this circuit is cached; make one with `make area ...`")
    return {"clock_mhz": float(c), "clock_source": "given"} if c else {"clock_mhz": 150.0, "clock_source": "board"}


def main():
    for line in sys.stdin:
        req = json.loads(line)
        args = req["args"]
        a = {k[2:]: v for k, v in zip(args[0::2], args[1::2])}
        with open(os.environ["FAKE_SERVE_LOG"], "a") as f:
            f.write(json.dumps([req["cmd"], a]) + "\n")
        time.sleep(float(os.environ.get("FAKE_SERVE_SLEEP", "0")))
        status, result, error = answer(req["cmd"], a)
        print(json.dumps({"status": status, "result": result, "error": error, "wall_s": 0.001}), flush=True)


if __name__ == "__main__":
    main()
