"""python -m dse.paper.paper --scenes "MESH ..." --out DIR --version V [--tus 1,2,4,8,16,32] [--table2-tus 32]
       [--width 128 --height 96] [--tus-width 32 --tus-height 24] [--depth 5] [--seed 1] [--machine-gbps X]
       [--fallback MESH] [--make CMD]

`make paper`: every figure and table of Collinson & Sinnen 2017 the project reproduces, as DIR/report.md with
its PNGs. It runs the existing targets per scene and reads what they write:

  golden         the cache-model frame (--width x --height) and the RTL frame (--tus-width x --tus-height), in
                 the folders make paper-caches keeps them in, remade only when absent or older than the mesh
  paper-nocache  Figs 12-13 without cache (RTL, --tus)                      build/paper-nocache/<scene>/
  paper-caches   Figs 8, 9, 11 (cache model) and 12-13 with cache (RTL)      build/paper-caches/<scene>/
  analyze        Fig 4, Figs 5-6 on the cache-model frame                   DIR/<scene>/analyze/
  table2         make roofline at the paper's settings (paper2017, --table2-tus TUs, 2^13 DM node cache)
                 at the paper's 150 MHz                                     DIR/<scene>/table2/
  table2-area    make area of that circuit (Yosys; its LUT-level clock proxy, cached per circuit)
                                                                            DIR/<scene>/table2-area/
  table2-fmax    make roofline again at CLOCK_MHZ=fmax, the clock that circuit reaches (--table2-fmax 0 skips
                 both)                                                      DIR/<scene>/table2-fmax/
  bench          Embree and our model, one thread each (Table 2, Fig 15)     build/bench/<scene>/

Each step's outputs are recorded in DIR/paper.sqlite (dse.explore.store) under a key of (target, arguments, scene,
rtaccel version); a rerun reuses a step whose outputs are still exactly the files it wrote (size and mtime) and
newer than the mesh, and runs the rest. Empty --tus skips the TU sweeps; --table2-tus 0 skips Table 2's RTL run.

Progress on stderr; each step's stdout in DIR/logs/. A step that exits non-zero stops the run with its exit
status; the report is written to a temporary file and moved into place only once complete, and a previous
report is removed at the start, so a failed run leaves none.
"""
import os
import shlex
import shutil
import subprocess
import sys
import time

import numpy as np

from scenes.cli import ArgParser, run
from scenes.errors import UserError

from ..common import write_text
from ..explore import store
from .report import RunInfo, SceneOutputs, render


class StepFailed(Exception):
    def __init__(self, rc, msg):
        super().__init__(msg)
        self.rc = rc


def log(msg):
    print(f"[paper] {msg}", file=sys.stderr, flush=True)


def tus_list(text):
    """"1 8" or "1,8" -> "1,8" (the comma form the sweeps take); empty stays empty."""
    parts = [t for t in text.replace(",", " ").split() if t]
    for t in parts:
        if not t.isdigit() or int(t) < 1:
            raise UserError(f"PAPER_TUS: '{t}' is not a TU count (give e.g. PAPER_TUS=\"1 2 4 8 16 32\", or empty)")
    return ",".join(parts)


def scene_name(mesh):
    n = os.path.basename(mesh)
    for ext in (".obj", ".ply"):
        if n.endswith(ext):
            n = n[: -len(ext)]
    return n


def fingerprint(paths):
    out = {}
    for p in paths:
        st = os.stat(p)
        out[p] = [st.st_size, st.st_mtime_ns]
    return out


def still_valid(fp, mesh):
    m = os.stat(mesh).st_mtime_ns
    for p, (size, mtime) in fp.items():
        try:
            st = os.stat(p)
        except OSError:
            return False
        if st.st_size != size or st.st_mtime_ns != mtime or st.st_mtime_ns < m:
            return False
    return True


class Runner:
    def __init__(self, a):
        self.a = a
        self.make = shlex.split(a.make)
        self.db = store.Store(os.path.join(a.out, "paper.sqlite"))
        self.steps = []
        # The sub-makes get exactly the arguments given here: knobs set on `make paper`'s command line would
        # otherwise reach them through MAKEFLAGS and change what the paper's settings mean.
        self.env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}

    def step(self, name, mesh, target, args, outputs, inputs=()):
        """Runs `make target args` unless the store holds a run of it whose outputs are unchanged."""
        scene = scene_name(mesh)
        config = {"target": target, "args": args, "inputs": fingerprint(inputs)}
        key = store.run_key(config, os.path.abspath(mesh), "", name, self.a.version)
        done = self.db.get(key)
        if done and done["status"] == store.OK and still_valid(done["result"]["outputs"], mesh):
            log(f"{scene}: {name}: reused (outputs unchanged since the run that made them)")
            self.steps.append((name, scene, "reused", 0.0))
            return
        os.makedirs(os.path.join(self.a.out, "logs"), exist_ok=True)
        logf = os.path.join(self.a.out, "logs", f"{scene}-{name}.log")
        cmd = self.make + ["--no-print-directory", target] + args
        log(f"{scene}: {name}: {' '.join(shlex.quote(c) for c in cmd[len(self.make):])}")
        t0 = time.time()
        with open(logf, "w") as f:
            rc = subprocess.call(cmd, stdout=f, env=self.env)
        wall = time.time() - t0
        missing = [p for p in outputs if not os.path.isfile(p)]
        if rc == 0 and missing:
            rc, err = 1, f"exited 0 but did not write {', '.join(missing)}"
        else:
            err = f"exited with status {rc}"
        if rc != 0:
            self.db.put(key, "paper", config, mesh, "", name, self.a.version, store.STATUS_OF_EXIT.get(rc, store.CRASHED),
                        rc, err, None, wall)
            with open(logf) as f:
                tail = f.read().splitlines()[-5:]
            for line in tail:
                print(f"    {line}", file=sys.stderr)
            raise StepFailed(rc, f"{scene}: {name} (make {target}) {err}; its stdout is in {logf}; no report written")
        self.db.put(key, "paper", config, mesh, "", name, self.a.version, store.OK, 0, None,
                    {"outputs": fingerprint(outputs)}, wall)
        log(f"{scene}: {name}: done in {wall:.0f} s")
        self.steps.append((name, scene, "ran", wall))

    def golden(self, mesh, d, w, h):
        rays = os.path.join(d, "rays.npy")
        if os.path.isfile(rays) and os.stat(rays).st_mtime_ns > os.stat(mesh).st_mtime_ns:
            return rays
        a = self.a
        self.step(f"golden {w}x{h}", mesh, "golden", [f"SCENE={mesh}", f"OUT={d}", f"WIDTH={w}", f"HEIGHT={h}",
                                                      f"DEPTH={a.depth}", f"SEED={a.seed}"], [rays])
        return rays

    def scene(self, mesh):
        a, n = self.a, scene_name(mesh)
        so = SceneOutputs(name=n, mesh=mesh)
        frame = f"d{a.depth}-s{a.seed}"
        caches = os.path.join("build", "paper-caches", n)
        big = self.golden(mesh, os.path.join(caches, "golden", f"{a.width}x{a.height}-{frame}"), a.width, a.height)
        small = None
        if a.tus or a.table2_tus:
            small = self.golden(mesh, os.path.join(caches, "golden", f"{a.tus_width}x{a.tus_height}-{frame}"),
                                a.tus_width, a.tus_height)
        if a.tus:
            nc = os.path.join("build", "paper-nocache", n, "tus_sweep.csv")
            self.step("paper-nocache", mesh, "paper-nocache", [f"NOCACHE_SCENES={mesh}", f"NOCACHE_TUS={a.tus}"], [nc])
            so.nocache_csv = nc
        outs = [os.path.join(caches, f) for f in ("fig11_miss_rate.csv", "fig11_miss_rate.png",
                                                  "fig8_9_bytes_per_ray.csv", "fig8_9_bytes_per_ray.png")]
        tus_outs = [os.path.join(caches, f) for f in ("tus_sweep.csv", "fig12_13_tus.png")] if a.tus else []
        self.step("paper-caches", mesh, "paper-caches",
                  [f"SCENE={mesh}", f"PAPER_TUS={a.tus}", f"PAPER_WIDTH={a.width}", f"PAPER_HEIGHT={a.height}",
                   f"PAPER_TUS_WIDTH={a.tus_width}", f"PAPER_TUS_HEIGHT={a.tus_height}", f"DEPTH={a.depth}",
                   f"SEED={a.seed}"], outs + tus_outs, inputs=[big] + ([so.nocache_csv] if so.nocache_csv else []))
        so.caches_dir = caches
        if a.tus:
            so.cache_tus_csv, so.tus_png = tus_outs
        ad = os.path.join(a.out, n, "analyze")
        self.step("analyze", mesh, "analyze", [f"SCENE={mesh}", f"GOLDEN={os.path.dirname(big)}", f"OUT={ad}"],
                  [os.path.join(ad, f) for f in ("bandwidth_vs_mppl.csv", "levels.csv", "bandwidth_vs_mppl.png", "levels.png")],
                  inputs=[big])
        so.analyze_dir = ad
        if a.table2_tus:
            knobs = ["CONFIG=paper2017", f"TUS={a.table2_tus}", "NODE_CACHE=8192", "NODE_POLICY=dm"]
            run = [f"SCENE={mesh}", f"GOLDEN={os.path.dirname(small)}"] + knobs
            td = os.path.join(a.out, n, "table2")
            self.step("table2", mesh, "roofline", run + [f"OUT={td}"],
                      [os.path.join(td, "roofline.csv"), os.path.join(td, "roofline.png")], inputs=[small])
            so.table2_csv = os.path.join(td, "roofline.csv")
            so.pngs["table2"] = os.path.join(td, "roofline.png")
            if a.table2_fmax:
                # The same circuit (PIPELINE=auto is placed for the board's 150 MHz either way) at the clock its
                # synthesis says it reaches; the memory stays at the paper's GB/s, so its bytes per cycle change too.
                ad = os.path.join(a.out, n, "table2-area")  # one circuit for every scene: the area cache answers the rest
                area = os.path.join(ad, "area.json")
                self.step("table2-area", mesh, "area", knobs + [f"OUT={ad}"], [area])
                fd = os.path.join(a.out, n, "table2-fmax")
                self.step("table2-fmax", mesh, "roofline", run + ["CLOCK_MHZ=fmax", f"OUT={fd}"],
                          [os.path.join(fd, "roofline.csv"), os.path.join(fd, "roofline.png")], inputs=[small, area])
                so.table2_fmax_csv = os.path.join(fd, "roofline.csv")
        if a.bench:
            bd = os.path.join("build", "bench", n)
            self.step("bench", mesh, "bench", [f"BENCH_SCENES={mesh}"],
                      [os.path.join(bd, "model.json"), os.path.join(bd, "embree.json")])
            so.bench_dir = bd
        # The PNGs the report shows, copied beside it so DIR is self-contained.
        od = os.path.join(a.out, n)
        os.makedirs(od, exist_ok=True)
        so.pngs["fig4"] = os.path.join(ad, "bandwidth_vs_mppl.png")
        so.pngs["fig5_6"] = os.path.join(ad, "levels.png")
        for key, src in (("fig8_9", outs[3]), ("fig11", outs[1]), ("fig12_13", so.tus_png)):
            if src:
                dst = os.path.join(od, os.path.basename(src))
                shutil.copyfile(src, dst)
                so.pngs[key] = dst
        return so


def copy_bandwidth_gbps(n=1 << 24, repeat=5):
    """One thread's copy bandwidth (read + write bytes per second) on a 128 MiB array, best of `repeat`."""
    a = np.ones(n)
    b = np.empty_like(a)
    best = min(_timed(np.copyto, b, a) for _ in range(repeat))
    return 2 * a.nbytes / best / 1e9


def _timed(f, *args):
    t0 = time.perf_counter()
    f(*args)
    return time.perf_counter() - t0


def main(argv=None):
    ap = ArgParser(prog="python -m dse.paper.paper", description="make paper: the paper's figures and tables, ours beside theirs.")
    ap.add_argument("--scenes", required=True, help="meshes, space-separated; absent ones are skipped with a note")
    ap.add_argument("--fallback", default="", help="mesh to use when none of --scenes exists")
    ap.add_argument("--out", required=True)
    ap.add_argument("--version", required=True)
    ap.add_argument("--tus", default="1,2,4,8,16,32", help="TU counts of Figs 12-13; empty skips the RTL sweeps")
    ap.add_argument("--table2-tus", type=int, default=32, help="TUs of the Table 2 RTL run; 0 skips it")
    ap.add_argument("--table2-fmax", type=int, default=1,
                    help="0 skips Table 2's run at the clock paper2017 reaches (make area: about 15 min of Yosys the first time)")
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--height", type=int, default=96)
    ap.add_argument("--tus-width", type=int, default=32)
    ap.add_argument("--tus-height", type=int, default=24)
    ap.add_argument("--depth", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bench", type=int, default=1, help="0 skips make bench (Embree and model rays/s)")
    ap.add_argument("--machine-gbps", type=float, default=None, help="this machine's available bandwidth (default: measured)")
    ap.add_argument("--make", default="make", help="the make command (tests replace it)")
    a = ap.parse_args(argv)
    a.tus = tus_list(a.tus)
    if a.table2_tus < 0:
        raise UserError(f"PAPER_TABLE2_TUS={a.table2_tus}: give a TU count, or 0 to skip Table 2's RTL run")
    for k in ("width", "height", "tus_width", "tus_height"):
        if getattr(a, k) < 1:
            raise UserError(f"--{k.replace('_', '-')} must be >= 1 (got {getattr(a, k)})")
    meshes = a.scenes.split()
    present = [m for m in meshes if os.path.isfile(m)]
    absent = [m for m in meshes if not os.path.isfile(m)]
    for m in absent:
        log(f"skip {m} (absent)")
    if not present:
        if not a.fallback or not os.path.isfile(a.fallback):
            raise UserError(f"none of the scenes exists ({a.scenes}) and no fallback mesh; give SCENES=<mesh ...>")
        log(f"no scene of SCENES exists: using the embedded room {a.fallback}")
        present = [a.fallback]
    os.makedirs(a.out, exist_ok=True)
    report = os.path.join(a.out, "report.md")
    if os.path.exists(report):
        os.unlink(report)  # a failed rerun must not leave the last run's report looking current
    t0 = time.time()
    r = Runner(a)
    try:
        outputs = [r.scene(m) for m in present]
    except StepFailed as e:
        print(f"error: make paper: {e}", file=sys.stderr)
        return e.rc
    if a.machine_gbps:
        gbps, how = a.machine_gbps, "MACHINE_GBPS as given"
    else:
        gbps, how = copy_bandwidth_gbps(), "one thread's measured copy bandwidth, best of 5 on 128 MiB; MACHINE_GBPS= overrides"
    log(f"this machine: {gbps:.1f} GB/s ({how})")
    skipped = {}
    if not a.tus:
        skipped["tus"] = "PAPER_TUS is empty"
    if not a.table2_tus:
        skipped["table2"] = "PAPER_TABLE2_TUS=0"
    if a.table2_tus and not a.table2_fmax:
        skipped["table2-fmax"] = "PAPER_TABLE2_FMAX=0"
    if not a.bench:
        skipped["bench"] = "PAPER_BENCH=0"
    settings = {"configs": "fit (= paper2017's QBVH, MPPL 4) for the cache model, analysis and bench; paper2017 for the RTL",
                "cache-model frame": f"{a.width}x{a.height}", "RTL frame": f"{a.tus_width}x{a.tus_height}",
                "bounces": a.depth, "seed": a.seed, "TUs of Figs 12-13": a.tus or "none",
                "Table 2 TUs": a.table2_tus or "none",
                "Table 2 clocks": "150 MHz (the paper's) and the reached one" if a.table2_fmax else "150 MHz (the paper's)"}
    info = RunInfo(out=a.out, version=a.version, settings=settings, machine_gbps=gbps, machine_gbps_how=how,
                   steps=r.steps, wall_s=time.time() - t0, skipped_scenes=absent, skipped_steps=skipped)
    write_text(report, render(info, outputs))
    log(f"report: {report} ({time.time() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    run(main)
