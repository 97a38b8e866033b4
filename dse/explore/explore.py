"""python -m dse.explore.explore --space FILE [--out DIR] [--workers N] [--ray-address ADDR] [--java CMD] [--version V]

`make dse SPACE=<file>`: the design points of a space file (space.py) evaluated rung by rung (rungs.py) on Ray
workers that each keep one JVM (worker.py, pool.py), every run stored as it ends (store.py), and only the
predicted Pareto front plus a margin confirmed with the RTL; each module named here is in dse/explore/. Writes into
DIR (default build/dse/<space>): store.sqlite, points.csv, runs.csv, front.md, report.md, pareto_*.png (report.py);
the last stdout line is
{"space","points","evaluated","skipped","failed","confirmed_rtl","pareto","store","wall_s",...}. With [fidelity]
yosys_margin, the points it would confirm (and each board's best) whose model cost is near a limit are first
synthesized with Yosys and their verdict re-decided (yosys_pass).
Exit 0 when the sweep completed (failed points are data), 2 on a bad space file or arguments (nothing written).
"""
import argparse
import hashlib
import itertools
import json
import os
import random
import subprocess
import sys
import time

from scenes.cli import ArgParser, run
from scenes.errors import UserError

from . import pareto, report, rungs, space as spacefile, store as st
from .knobs import ROOT
from .pool import Pool


def log(msg):
    print(f"[dse] {msg}", file=sys.stderr, flush=True)


def file_hash(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for b in iter(lambda: f.read(1 << 20), b""):
            h.update(b)
    return h.hexdigest()[:16]


def _py(*args):
    r = subprocess.run([sys.executable, "-m", *args], cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        errs = [l for l in r.stderr.splitlines() if l.startswith("error:")]
        raise UserError(f"python -m {' '.join(args[:1])}: {errs[-1][6:].strip() if errs else r.stderr.strip()[-300:]}")


def prepare_scene(s):
    """The inputs every worker reads: the mesh (made when procedural), its triangles and the rays."""
    if s.procedural and not os.path.isfile(s.mesh):
        os.makedirs(os.path.dirname(s.mesh), exist_ok=True)
        _py("scenes.procedural", s.procedural, s.mesh)
    r = subprocess.run([os.path.join(ROOT, "tools", "tris"), s.mesh], cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        raise UserError(f"scene {s.mesh}: {r.stderr.strip()}")
    rays = s.rays
    if not rays:
        g = os.path.join(ROOT, "build", "dse", "golden", f"{s.name}-{file_hash(s.mesh)}-{s.width}x{s.height}-d{s.depth}-s{s.seed}")
        if not os.path.isfile(os.path.join(g, "rays.npy")):
            log(f"golden frame {s.width}x{s.height} depth {s.depth} seed {s.seed} of {s.name}")
            os.makedirs(os.path.dirname(g), exist_ok=True)
            _py("golden.export", "--scene", s.mesh, "--out", g, "--width", str(s.width), "--height", str(s.height),
                "--depth", str(s.depth), "--seed", str(s.seed))
        rays = os.path.join(g, "rays.npy")
    label = os.path.relpath(s.mesh, ROOT) if s.mesh.startswith(ROOT) else s.mesh
    return {"name": s.name, "tris": r.stdout.strip(), "rays": rays, "label": label,
            "id": f"{s.name}:{file_hash(s.mesh)}", "rays_id": file_hash(rays)}


def grid(sp):
    keys = list(sp.axes)
    return [{**sp.base, **dict(zip(keys, vs))} for vs in itertools.product(*(sp.axes[k] for k in keys))]


def random_points(sp):
    """n distinct points of the grid, drawn without building it (mixed-radix indices)."""
    keys = list(sp.axes)
    sizes = [len(sp.axes[k]) for k in keys]
    total = 1
    for n in sizes:
        total *= n
    out = []
    for i in random.Random(sp.strategy["seed"]).sample(range(total), min(sp.strategy["n"], total)):
        c = dict(sp.base)
        for k, n in zip(reversed(keys), reversed(sizes)):
            c[k] = sp.axes[k][i % n]
            i //= n
        out.append(c)
    return out


class StopAfter(Exception):
    """--stop-after K: the sweep stops as if killed after K new runs (tests of resuming)."""


class Sweep:
    def __init__(self, sp, scenes, out, pool, version, stop_after=None):
        self.sp, self.scenes, self.out, self.pool, self.version = sp, scenes, out, pool, version
        self.store = st.Store(os.path.join(out, "store.sqlite"))
        self.stop_after = stop_after
        self.counts = {}  # fidelity -> {"evaluated", "skipped", "failed"}
        self.bar, self.done, self.wanted = None, {}, {}
        self.summaries = {}  # point id -> its cheap-rung summary
        self.time = {}

    def _count(self, fid, what):
        c = self.counts.setdefault(fid, {"evaluated": 0, "skipped": 0, "failed": 0})
        c[what] += 1

    def _bar(self, total):
        """One progress bar over every run; its postfix shows done/failed per fidelity."""
        from tqdm import tqdm

        if self.bar is None:
            self.bar = tqdm(total=0, desc="[dse]", unit="run", file=sys.stderr, dynamic_ncols=True, mininterval=1.0)
        self.bar.total += total
        self.bar.refresh()
        return self.bar

    def _tick(self, fid):
        self.done[fid] = self.done.get(fid, 0) + 1
        self.bar.set_postfix_str(" ".join(
            f"{f} {self.done.get(f, 0)}/{self.wanted[f]}" + (f" ({c['failed']} failed)" if c["failed"] else "")
            for f, c in self.counts.items()), refresh=False)
        self.bar.update(1)

    def _time(self, fid, r, res):
        """Where the time of the runs made now went (report: time split), per fidelity."""
        t = self.time.setdefault(fid, {"runs": 0, "worker_s": 0.0, "server_s": 0.0})
        t["runs"] += 1
        t["worker_s"] += r["wall_s"]
        t["server_s"] += r["answer"].get("wall_s") or 0.0
        if fid == "cachesim" and isinstance(res, dict):
            for k, name in (("load_s", "load_s"), ("bvh_build_s", "bvh_s"), ("trace_s", "trace_s"), ("wall_s", "replay_s")):
                t[name] = t.get(name, 0.0) + (res.get(k) or 0.0)

    def board_for_area(self, config):
        f = self.sp.constraints.get("fits")
        return config.get("BOARD") if f in (None, "BOARD") else f

    def runs(self, fid, points):
        """Evaluates `fid` for every point (x scene) not yet in the store; returns {(pid, scene): row}."""
        want = []
        for c in points:
            for s in ([None] if fid in rungs.COST_RUNGS else self.scenes):
                scene_id, rays_id = (s["id"], s["rays_id"]) if s else ("", "")
                key = st.run_key(c, scene_id, rays_id, fid, self.version)
                want.append((key, c, s, scene_id, rays_id))
        out, todo = {}, []
        bar = self._bar(len(want))
        self.wanted[fid] = self.wanted.get(fid, 0) + len(want)
        for key, c, s, scene_id, rays_id in want:
            row = self.store.get(key)
            if row is not None:
                self._count(fid, "skipped")
                if row["status"] in st.FAILED:
                    self._count(fid, "failed")
                out[(st.point_id(c), s["name"] if s else "")] = row
                self._tick(fid)
            else:
                cmd, args = rungs.task_args(fid, c, s, self.out, self.board_for_area(c))
                todo.append({"key": key, "cmd": cmd, "args": args, "meta": (c, s, scene_id, rays_id)})
        meta = {t["key"]: t.pop("meta") for t in todo}
        for r in self.pool.map(todo):
            c, s, scene_id, rays_id = meta[r["key"]]
            status, err = rungs.classify(fid, r["answer"])
            res = r["answer"].get("result")
            self._time(fid, r, res)
            self.store.put(r["key"], self.sp.name, c, scene_id, rays_id, fid, self.version, status,
                           r["answer"].get("status"), err, res, r["wall_s"])
            out[(st.point_id(c), s["name"] if s else "")] = {"status": status, "error": err, "result": res, "wall_s": r["wall_s"]}
            self._count(fid, "evaluated")
            if status in st.FAILED:
                self._count(fid, "failed")
                bar.write(f"[dse] {fid} {st.point_id(c)} {s['name'] if s else ''}: {status}: {err}")
            self._tick(fid)
            if self.stop_after is not None and sum(v["evaluated"] for v in self.counts.values()) >= self.stop_after:
                raise StopAfter()
        return out

    def cheap(self, points):
        """Runs the cheap rungs of `points`; returns one summary per point (report.summarise). A point asked for
        again (Optuna repeats itself) is answered from memory, not counted twice."""
        new = list({st.point_id(c): c for c in points if st.point_id(c) not in self.summaries}.values())
        if new:
            rows = {"cachesim": self.runs("cachesim", new)}
            if self.sp.needs_area():
                rows["area"] = self.runs("area", new)
            for c in new:
                self.summaries[st.point_id(c)] = report.summarise(self.sp, c, self.scenes, rows)
        return [self.summaries[st.point_id(c)] for c in points]

    def close(self):
        if self.bar is not None:
            self.bar.close()
        self.store.close()


def explore(sp, sweep):
    """The points and their cheap-rung summaries, by the space's strategy."""
    kind = sp.strategy["kind"]
    if kind in ("grid", "random"):
        points = grid(sp) if kind == "grid" else random_points(sp)
        return points, sweep.cheap(points)
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    seed = sp.strategy["seed"]
    # the study ranks on what the rungs can measure: probe the first grid point (trial 0) for the cost rung
    first = grid_first(sp)
    objs = report.active_objectives(sp, sweep.cheap([first])) or sp.objectives
    sampler = optuna.samplers.NSGAIISampler(seed=seed) if sp.strategy["sampler"] == "nsga2" else optuna.samplers.TPESampler(seed=seed)
    study = optuna.create_study(directions=["maximize" if d == "max" else "minimize" for _, d in objs], sampler=sampler)
    study.enqueue_trial({k: first[k] for k in sp.axes})
    points, sums, seen = [], [], set()
    left = sp.strategy["budget"]
    while left > 0:
        # one batch per pool width; told in ask order, so the same seed asks the same points on a rerun
        trials = [study.ask() for _ in range(min(left, sweep.pool.size))]
        cfgs = [{**sp.base, **{k: t.suggest_categorical(k, v) for k, v in sp.axes.items()}} for t in trials]
        got = sweep.cheap(cfgs)
        for t, c, s in zip(trials, cfgs, got):
            vals = [s["objectives"].get(o) for o, _ in objs]
            if s["feasible"] and all(v is not None for v in vals):
                study.tell(t, vals)
            else:
                study.tell(t, state=optuna.trial.TrialState.FAIL)
            if st.point_id(c) not in seen:
                seen.add(st.point_id(c))
                points.append(c)
                sums.append(s)
        left -= len(trials)
    return points, sums


def grid_first(sp):
    return {**sp.base, **{k: v[0] for k, v in sp.axes.items()}}


def confirm_set(sp, sums):
    """Point ids to confirm with the RTL: the predicted front of the feasible points, then `margin` more by
    non-dominated rank (best first objective first), at most max_rtl in all."""
    objs = report.active_objectives(sp, sums)
    cand = [s for s in sums if s["feasible"]]
    if not cand or not objs:
        return []
    dirs = [d for _, d in objs]
    vals = [[s["objectives"][o] for o, _ in objs] for s in cand]
    rk = pareto.ranks(vals, dirs)
    first, sign = objs[0][0], (-1 if objs[0][1] == "max" else 1)
    order = sorted(range(len(cand)), key=lambda i: (rk[i], sign * cand[i]["objectives"][first], cand[i]["point"]))
    n_front = sum(1 for r in rk if r == 0)
    take = min(n_front + sp.fidelity["margin"], sp.fidelity["max_rtl"])
    return [cand[i]["point"] for i in order[:take]]


def yosys_candidates(sp, sums, margin, scenes):
    """Point ids to synthesize now: of the points the sweep would confirm with the RTL (confirm_set, whether or
    not rtl = true) and each board's best, those not synthesized yet whose model cost of any resource is within
    `margin` of a limit (rungs.near_limit)."""
    want = set(confirm_set(sp, sums)) | {b["point"] for b in report.best_per_board(sp, sums, scenes, {}).values() if b}
    return [s["point"] for s in sums if s["point"] in want and "yosys" not in s and "area" in s["metrics"]
            and rungs.near_limit(sp.constraints, s["metrics"]["area"], margin)]


def yosys_pass(sp, sweep, sums):
    """The summaries with the verdicts of the points near a limit re-decided by Yosys, and the synthesized ids.
    A point that leaves lets others into the confirm set or a board's best: they are checked in turn, until
    every point the sweep would confirm that is near a limit has been synthesized."""
    margin = sp.fidelity.get("yosys_margin")
    done = []
    while margin is not None:
        new = yosys_candidates(sp, sums, margin, sweep.scenes)
        if not new:
            break
        rows = sweep.runs("yosys", [s["config"] for s in sums if s["point"] in new])
        sums = [report.with_yosys(sp, s, rows[(s["point"], "")]) if s["point"] in new else s for s in sums]
        done += new
    return sums, done


def main(argv=None):
    ap = ArgParser(prog="make dse", description=__doc__.splitlines()[0])
    ap.add_argument("--space", required=True)
    ap.add_argument("--out", default="")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--ray-address", default="")
    ap.add_argument("--java", default=os.environ.get("RTACCEL_JAVA", ""))
    ap.add_argument("--version", default=os.environ.get("RTACCEL_VERSION", "unknown"))
    ap.add_argument("--stop-after", type=int, default=None, help=argparse.SUPPRESS)  # tests: a kill after K runs
    a = ap.parse_args(argv)
    t0 = time.time()
    sp = spacefile.load(a.space)
    if a.workers < 0:
        raise UserError(f"WORKERS={a.workers}: give 0 (inline, no Ray) or more workers")
    if not a.java:
        raise UserError("give --java '<java command on the rtaccel classpath>' (make dse passes it)")
    out = os.path.abspath(a.out or os.path.join(ROOT, "build", "dse", sp.name))
    scenes = [prepare_scene(s) for s in sp.scenes]
    os.makedirs(out, exist_ok=True)
    pool = Pool(a.workers, a.ray_address, a.java, os.path.join(out, "logs"))
    sweep = Sweep(sp, scenes, out, pool, a.version, a.stop_after)
    try:
        points, sums = explore(sp, sweep)
        sums, synthesized = yosys_pass(sp, sweep, sums)
        confirmed = confirm_set(sp, sums) if sp.fidelity["rtl"] else []
        rtl = sweep.runs("rtl", [s["config"] for s in sums if s["point"] in confirmed]) if confirmed else {}
        stats = pool.stats()
    except StopAfter:
        log(f"stopped after {a.stop_after} new runs (--stop-after); rerun to resume")
        return 1
    finally:
        pool.close()
        sweep.close()
    summary = report.write(sp, scenes, out, a.version, sums, rtl, confirmed, sweep.counts, stats, sweep.time)
    c = sweep.counts
    print(json.dumps({
        "space": sp.name, "points": len(points),
        "evaluated": sum(v["evaluated"] for v in c.values()), "skipped": sum(v["skipped"] for v in c.values()),
        "failed": sum(v["failed"] for v in c.values()), "confirmed_rtl": confirmed, "pareto": summary["pareto"],
        "store": os.path.join(out, "store.sqlite"), "wall_s": round(time.time() - t0, 3),
        "by_fidelity": c, "rung_error": summary["rung_error"], "best_per_board": summary["best_per_board"],
        "csv": summary["csv"], "time_split": summary["time_split"], "workers": len(stats), "rtaccel": a.version,
        "confirmed_yosys": synthesized, "cost_rung_error": summary["cost_rung_error"],
        "yosys_overturned": summary["yosys_overturned"]}))
    return 0


if __name__ == "__main__":
    run(main)
