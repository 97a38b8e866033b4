"""The fidelity ladder of `make dse`: what each rung asks the JVM, and what a design point's answer means.

  cachesim  trace-driven cache model (rtaccel.cli.CacheSim): DRAM bytes per ray after the caches, the MVA
            rays/s prediction and the bandwidth bound; per point x scene; seconds
  area      FPGA cost from the fitted model (`make area FIDELITY=model`): LUT/FF/DSP/BRAM36 and "fits";
            per point (no scene); refused with status 2 by a build without the model: recorded as skipped
  yosys     FPGA cost from a real synthesis (`make area FIDELITY=yosys`, cached per circuit in build/area-cache):
            per point; minutes; only for the points the sweep would confirm (and each board's best) whose model
            cost is within [fidelity] yosys_margin of a limit; its numbers re-decide their verdict
  rtl       the platform RTL under Verilator (rtaccel.cli.Simulate), checked ray by ray against the model;
            per point x scene; minutes; only for the predicted front plus a margin
"""
import math
import os

from . import knobs, store
from .knobs import boards, flags

COST_RUNGS = ("area", "yosys")  # per point, no scene; the same command and answer, another fidelity
RESOURCES = ("lut", "ff", "dsp", "bram36")  # what a board's capacity and a space's max_* limits bound

# make area's refusals that mean "no cost model in this build or checkout" (a build before FIDELITY=model, or
# boards/cost-model.json not made yet by make cost-model), not "this configuration is bad"
UNAVAILABLE = ("FIDELITY=model is not available", "cost model ", "FIDELITY=model")


def fit_preset(config):
    """The preset make area prices for CONFIG=fit (area synthesizes a preset; fit is that preset before fitting):
    paper2017, or paper2017-lrp when a level-aware node cache needs the level field in the node refs (paper2017's
    refs have none, so area would refuse every LRP or hybrid point). An absent NODE_CACHE is the preset's 8192."""
    level = config.get("NODE_POLICY") in knobs.LEVEL_AWARE and int(config.get("NODE_CACHE", 1)) > 0
    return "paper2017-lrp" if level else "paper2017"


def task_args(fidelity, config, scene, out, board=None):
    """(cmd, args) of one run. `scene` is a prepared scene dict (tris, rays, label); None for the cost rungs."""
    if fidelity in COST_RUNGS:
        c = dict(config)
        if c.get("CONFIG", "fit") == "fit":
            c["CONFIG"] = fit_preset(c)
        if board:
            c["BOARD"] = board
        model = "model" if fidelity == "area" else "yosys"
        return "area", flags(c) + ["--fidelity", model, "--out", os.path.join(out, fidelity, store.point_id(config))]
    inputs = ["--tris", scene["tris"], "--rays", scene["rays"], "--scene-label", scene["label"]]
    if fidelity == "cachesim":
        return "cachesim", inputs + flags(config)
    return "simulate", inputs + flags(config) + ["--out", os.path.join(out, "rtl", f"{store.point_id(config)}-{scene['name']}")]


def classify(fidelity, answer):
    """(status, error) of a run from the server's answer. An area run that says "does not fit" (status 3 with its
    result) is a measured cost of an infeasible point, not a failure; an area model this build lacks is skipped."""
    st, err, res = answer.get("status"), answer.get("error"), answer.get("result")
    if fidelity in COST_RUNGS:
        if st == 3 and isinstance(res, dict) and res.get("fits") is False:
            return "infeasible", err
    if fidelity == "area":
        if st == 2 and err and any(w in err for w in UNAVAILABLE):
            return store.SKIPPED, f"cost rung unavailable: {err}"
    if st == 0 and not isinstance(res, dict):
        return store.CRASHED, "status 0 but no JSON result"
    return store.STATUS_OF_EXIT.get(st, store.CRASHED), err


def metrics(fidelity, result):
    """The figures a rung measured, under the names objectives and the report use."""
    if fidelity in COST_RUNGS:
        return {k: result.get(k) for k in ("lut", "lutram", "ff", "dsp", "bram36", "fits", "board")}
    if fidelity == "cachesim":
        bpr = result["dram_bytes_per_ray"]
        return {"rays_per_s": result["predicted_rays_per_s"], "bw_bound_rays_per_s": result["bandwidth_bound_rays_per_s"],
                "dram_bytes_per_ray": bpr, "rays_per_dram_byte": 1 / bpr if bpr > 0 else math.inf,
                "node_miss_rate": result["node_cache"]["miss_rate"], "prim_miss_rate": result["prim_cache"]["miss_rate"],
                "cache_kib": cache_kib(result), **clock(result)}
    bpr = result.get("dram_bytes_per_ray") or 0.0
    return {"rays_per_s": result["rays_per_s_at_clock"], "dram_bytes_per_ray": bpr,
            "rays_per_dram_byte": 1 / bpr if bpr > 0 else math.inf,
            "node_miss_rate": (result.get("node_cache") or {}).get("miss_rate"), **clock(result)}


def clock(result):
    """The clock a rays/s figure is at and where it comes from (given, board, proxy, routed)."""
    return {"clock_mhz": result.get("clock_mhz"), "clock_source": result.get("clock_source")}


def limits(constraints, cost):
    """{resource: [(limit name, used, limit)]} that bound a cost (rungs.metrics of a cost rung): its board's
    capacity (LUT sites hold logic LUTs and LUT RAM, as make area checks) and the space's max_* constraints."""
    out = {r: [] for r in RESOURCES}
    cap = boards().get(cost.get("board") or "")
    for r in RESOURCES:
        if cap and cost.get(r) is not None:
            used = cost[r] + (cost.get("lutram") or 0) if r == "lut" else cost[r]
            out[r].append((cost["board"], used, cap[r]))
        if f"max_{r}" in constraints and cost.get(r) is not None:
            out[r].append((f"max_{r}", cost[r], constraints[f"max_{r}"]))
    return out


def near_limit(constraints, cost, margin):
    """The (resource, limit name, used, limit) of a cost within `margin` (a fraction) of a limit, below or above."""
    return [(r, name, used, lim) for r, ls in limits(constraints, cost).items() for name, used, lim in ls
            if abs(used - lim) <= margin * lim]


def cache_kib(result):
    """On-chip cache storage of a cachesim result: entries x bytes per access of each cache."""
    n = result["node_accesses"] or 1
    node_bytes = result["node_bytes_per_ray_nocache"] * result["rays"] / n
    prim_bytes = 64  # one primitive access (PlatformParams.primAccessBytes default)
    return (result["node_cache"]["entries"] * node_bytes + result["prim_cache"]["entries"] * prim_bytes) / 1024


def geomean(xs):
    xs = list(xs)
    if not xs or any(x is None or x <= 0 for x in xs):
        return None
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if all(math.isfinite(x) for x in xs) else math.inf
