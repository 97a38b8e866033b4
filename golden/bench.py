"""python -m golden.bench --scene MESH --rays RAYS.npy [--repeat 5] [--all-threads]

Embree baseline: scene build time and closest-hit throughput (embreex, rtcIntersect1 per ray), median over
--repeat runs; every run builds a new scene. The last stdout line is JSON:
  {"rays", "triangles", "embree_build_s_median", "embree_rays_per_s_median", "embree_rays_per_cpu_s_median",
   "threads", ...}
Rays/s are given per wall second and per second of the tracing thread's CPU time (time.thread_time: the serial
rtcIntersect1 loop runs in this thread), which a loaded, shared machine disturbs least.

Threads: embreex creates its Embree device without a config string (so "threads=1" cannot be passed) and
Embree's TBB takes its default concurrency from the process CPU affinity. Unless --all-threads is given, the
process is pinned to one CPU with sched_setaffinity before Embree starts, so build and trace use one thread.
Tracing through embreex is a serial loop over rays in any case.
"""
import json
import os
import statistics
import sys
import time

from scenes.cli import ArgParser, run

from .io import GoldenError, load_rays


def _pin_one_cpu():
    """Pin this process to one CPU; returns the CPU number, or None where affinity is not supported."""
    if not hasattr(os, "sched_setaffinity"):
        return None
    cpu = sorted(os.sched_getaffinity(0))[0]
    os.sched_setaffinity(0, {cpu})
    return cpu


def _os_threads():
    try:
        return len(os.listdir("/proc/self/task"))
    except OSError:
        return None


def main(argv=None):
    ap = ArgParser(prog="python -m golden.bench", description="Embree build time and trace throughput.")
    ap.add_argument("--scene", required=True, help="mesh file (.obj or .ply)")
    ap.add_argument("--rays", required=True, help="float32 (N,8) rays, e.g. DIR/rays.npy of golden.export")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--all-threads", action="store_true", help="do not pin to one CPU (TBB uses all CPUs)")
    a = ap.parse_args(argv)
    if a.repeat < 1:
        raise GoldenError(f"--repeat {a.repeat} must be >= 1")
    if "embreex" in sys.modules and not a.all_threads:
        raise GoldenError("embreex was imported before the CPU pinning; run golden.bench as its own process")
    cpu = None if a.all_threads else _pin_one_cpu()
    threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()

    from scenes.load import load_triangles
    from .trace import build_scene, trace_scene, versions

    tris = load_triangles(a.scene)
    rays = load_rays(a.rays)
    builds, rates, cpu_rates = [], [], []
    threads_seen = 0
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        scene, keep = build_scene(tris)
        t1 = time.perf_counter()
        threads_seen = max(threads_seen, _os_threads() or 0)
        c1 = time.thread_time()
        trace_scene(scene, rays)
        t2, c2 = time.perf_counter(), time.thread_time()
        builds.append(t1 - t0)
        rates.append(len(rays) / (t2 - t1))
        cpu_rates.append(len(rays) / max(c2 - c1, 1e-9))
        del scene, keep
    res = {
        "rays": int(len(rays)),
        "triangles": int(len(tris)),
        "embree_build_s_median": statistics.median(builds),
        "embree_rays_per_s_median": statistics.median(rates),
        "embree_rays_per_cpu_s_median": statistics.median(cpu_rates),
        "threads": threads,
        "thread_control": (f"sched_setaffinity to CPU {cpu} (TBB follows the affinity mask)" if cpu is not None
                           else "none (all CPUs of the affinity mask)"),
        "os_threads_max": threads_seen,
        "repeat": a.repeat,
        "embreex_version": versions()["embreex"],
        "embree_version": versions()["embree"],
    }
    print(f"{len(tris)} triangles, {len(rays)} rays, {threads} thread(s): build {res['embree_build_s_median']:.3f} s, "
          f"{res['embree_rays_per_s_median'] / 1e6:.2f} Mrays/s (median of {a.repeat})", file=sys.stderr)
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    run(main)
