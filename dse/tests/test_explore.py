"""make dse (dse.explore.explore) through local Ray with 2 workers and a fake JVM server (fake_serve.py): strategies,
resuming, failing points, the RTL confirmation step and the outputs."""
import csv
import json
import os
import shlex
import sqlite3
import sys

import pytest

from dse.explore import explore, pareto, store

from . import spaces

FAKE = os.path.join(os.path.dirname(__file__), "fake_serve.py")


def java(tmp_path, **env):
    """A --java command that starts the fake server with FAKE_SERVE_* settings (Ray workers do not see the
    test's environment changes, so they travel in the command)."""
    log = tmp_path / "requests.jsonl"
    env = {"FAKE_SERVE_LOG": str(log), **{f"FAKE_SERVE_{k}": str(v) for k, v in env.items()}}
    return "env " + " ".join(f"{k}={shlex.quote(v)}" for k, v in env.items()) + f" {shlex.quote(sys.executable)} {FAKE}", log


def requests(log):
    return [json.loads(l) for l in log.read_text().splitlines()] if log.exists() else []


def dse(capsys, space, out, jv, *extra, workers=2):
    rc = explore.main(["--space", str(space), "--out", str(out), "--workers", str(workers), "--java", jv, "--version", "t1", *extra])
    lines = capsys.readouterr().out.strip().splitlines()
    return rc, (json.loads(lines[-1]) if rc == 0 else None)


def stored(out):
    with sqlite3.connect(out / "store.sqlite") as db:
        return db.execute("SELECT fidelity, status, config, error FROM runs").fetchall()


def count(out):
    """Rows in the store while a sweep may still be creating it."""
    try:
        return len(stored(out)) if (out / "store.sqlite").exists() else 0
    except sqlite3.OperationalError:
        return 0


def test_grid_then_rerun_evaluates_nothing(tmp_path, capsys, local_ray):
    sp, out = spaces.tiny(tmp_path), tmp_path / "out"
    jv, log = java(tmp_path)
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0
    assert set(j) >= {"space", "points", "evaluated", "skipped", "failed", "confirmed_rtl", "pareto", "store", "wall_s"}
    assert (j["space"], j["points"], j["evaluated"], j["skipped"], j["failed"]) == ("tiny", 9, 9, 0, 0)
    # rays/s = 1e5 TUS (1 + NODE_CACHE/256): one best point
    assert [p["config"] for p in j["pareto"]] == [{"CONFIG": "small", "TUS": 4, "NODE_CACHE": 256}]
    assert len(requests(log)) == 9
    first = (out / "points.csv").read_text().splitlines()[0]
    assert first.startswith("# space=tiny ") and first.endswith(" rtaccel=t1") and "scenes=build/scenes/cornell.obj" in first
    rc, j2 = dse(capsys, sp, out, jv)
    assert (j2["evaluated"], j2["skipped"], j2["points"]) == (0, 9, 9)
    assert len(requests(log)) == 9 and j2["pareto"] == j["pareto"]


def test_optuna_nsga2_with_a_budget(tmp_path, capsys, local_ray):
    extra = '[objectives]\nmaximize = ["rays_per_s"]\nminimize = ["lut"]\n[strategy]\nkind = "optuna"\nbudget = 6\nseed = 3\n'
    sp, out = spaces.tiny(tmp_path, extra=extra), tmp_path / "out"
    jv, log = java(tmp_path, AREA=1)
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0 and 1 <= j["points"] <= 6
    runs = requests(log)
    # each distinct point: one cachesim and one area run, never twice
    assert sum(r[0] == "cachesim" for r in runs) == j["points"] == sum(r[0] == "area" for r in runs)
    assert all(r[1]["fidelity"] == "model" for r in runs if r[0] == "area")
    # the reported front is the front of the feasible points (lut <= 3000 fits) by the brute-force definition
    rows = [r for r in csv.DictReader(l for l in (out / "points.csv").read_text().splitlines() if not l.startswith("#"))]
    feas = [r for r in rows if r["feasible"] == "True"]
    vals = [(float(r["model_rays_per_s"]), float(r["area_lut"])) for r in feas]
    want = {feas[i]["point"] for i in pareto.front(vals, ["max", "min"])}
    assert {p["point"] for p in j["pareto"]} == want
    assert all(float(r["area_lut"]) > 3000 for r in rows if r["feasible"] == "False")
    rc, j2 = dse(capsys, sp, out, jv)  # the same seed asks the same points: all from the store
    assert j2["evaluated"] == 0 and j2["points"] == j["points"]


def test_tpe_sampler_runs(tmp_path, capsys, local_ray):
    extra = '[strategy]\nkind = "optuna"\nsampler = "tpe"\nbudget = 4\n'
    rc, j = dse(capsys, spaces.tiny(tmp_path, extra=extra), tmp_path / "out", java(tmp_path)[0])
    assert rc == 0 and 1 <= j["points"] <= 4 and j["failed"] == 0


def test_killed_sweep_resumes_with_only_the_missing_runs(tmp_path, capsys, local_ray):
    sp, out = spaces.tiny(tmp_path), tmp_path / "out"
    jv, log = java(tmp_path)
    rc, _ = dse(capsys, sp, out, jv, "--stop-after", "4")
    assert rc == 1
    done = len(stored(out))
    assert 4 <= done < 9
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0 and j["evaluated"] == 9 - done and j["skipped"] == done
    cfgs = [json.dumps(r[1], sort_keys=True) for r in requests(log) if r[0] == "cachesim"]
    assert len(set(cfgs)) == 9  # no run was made twice except the ones in flight at the stop
    assert len(cfgs) - 9 <= 2


def test_failing_points_are_recorded_and_the_sweep_goes_on(tmp_path, capsys, local_ray):
    sp, out = spaces.tiny(tmp_path), tmp_path / "out"
    jv, _ = java(tmp_path, REFUSE_TUS=2, CRASH_TUS=4)
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0 and j["points"] == 9 and j["failed"] == 6
    rows = stored(out)
    by = {(json.loads(c)["TUS"], s) for _, s, c, _ in rows}
    assert by == {(1, store.OK), (2, store.REFUSED), (4, store.CRASHED)}
    assert all("refused by this fake" in e for _, s, _, e in rows if s == store.REFUSED)
    assert all("exited with status 134" in e for _, s, _, e in rows if s == store.CRASHED)
    assert [p["config"]["TUS"] for p in j["pareto"]] == [1]
    pts = {r["point"]: r for r in csv.DictReader(l for l in (out / "points.csv").read_text().splitlines() if not l.startswith("#"))}
    assert sum(1 for r in pts.values() if r["errors"]) == 6 and all(r["model_rays_per_s"] == "" for r in pts.values() if r["errors"])


def test_rtl_confirms_exactly_the_front_plus_margin(tmp_path, capsys, local_ray):
    extra = ('[objectives]\nmaximize = ["rays_per_s"]\nminimize = ["bram36"]\n'
             '[fidelity]\nrtl = true\nmargin = 1\nmax_rtl = 8\n')
    sp, out = spaces.tiny(tmp_path, extra=extra), tmp_path / "out"
    jv, log = java(tmp_path, AREA=1, CHECK_FAIL_TUS=1)
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0
    rows = [r for r in csv.DictReader(l for l in (out / "points.csv").read_text().splitlines() if not l.startswith("#"))]
    feas = [r for r in rows if r["feasible"] == "True"]
    vals = [(float(r["model_rays_per_s"]), float(r["area_bram36"])) for r in feas]
    rk = pareto.ranks(vals, ["max", "min"])
    front = {feas[i]["point"] for i in range(len(feas)) if rk[i] == 0}
    second = sorted((-vals[i][0], feas[i]["point"]) for i in range(len(feas)) if rk[i] == 1)
    assert set(j["confirmed_rtl"]) == front | {second[0][1]}
    simulated = {store.point_id({"CONFIG": "small", "TUS": int(r[1]["tus"]), "NODE_CACHE": int(r[1]["node-cache"])})
                 for r in requests(log) if r[0] == "simulate"}
    assert simulated == set(j["confirmed_rtl"])
    # the fake RTL runs at 0.8 x the prediction: the MVA rung is 25 % optimistic on every passing confirmed point
    assert j["rung_error"]["mva_rel_err"]["max_abs"] == pytest.approx(0.25)
    # a TUS=1 RTL run failed its check: listed, never a figure
    for p in j["pareto"]:
        if p["config"]["TUS"] == 1 and p["point"] in j["confirmed_rtl"]:
            assert p["rtl"] == {"status": "check_failed"}
    rtl_col = {r["point"]: r for r in rows}
    assert all(rtl_col[p]["rtl_rays_per_s"] == "" for p in j["confirmed_rtl"] if rtl_col[p]["TUS"] == "1")
    for png in ("pareto_lut.png", "pareto_bram36.png"):
        assert (out / png).read_bytes()[:4] == b"\x89PNG"
    report = (out / "report.md").read_text()
    assert "make verilog CONFIG=small" in report and "Cheap rungs against the RTL" in report
    # no yosys_margin: the cost model alone decides, as before
    assert j["confirmed_yosys"] == [] and j["yosys_overturned"] == [] and "yosys" not in j["by_fidelity"]
    assert all(r[1]["fidelity"] == "model" for r in requests(log) if r[0] == "area")
    assert "Cost model against Yosys" not in report


def test_cost_rung_unavailable_is_recorded_as_skipped(tmp_path, capsys, local_ray):
    extra = '[objectives]\nmaximize = ["rays_per_s"]\nminimize = ["lut"]\n'
    sp, out = spaces.tiny(tmp_path, axes="TUS = [1, 2]", extra=extra), tmp_path / "out"
    rc, j = dse(capsys, sp, out, java(tmp_path)[0])
    assert rc == 0 and j["failed"] == 0
    assert {(f, s) for f, s, _, _ in stored(out)} == {("cachesim", store.OK), ("area", store.SKIPPED)}
    assert all("FIDELITY=model" in e for f, _, _, e in stored(out) if f == "area")
    assert [p["config"]["TUS"] for p in j["pareto"]] == [2]  # ranked on rays/s alone, with a note
    assert "Not ranked on lut" in (out / "front.md").read_text()
    assert (out / "pareto_cache_kib.png").exists()


def test_random_strategy_draws_n_distinct_points_reproducibly(tmp_path, capsys, local_ray):
    sp = spaces.tiny(tmp_path, extra='[strategy]\nkind = "random"\nn = 5\nseed = 7\n')
    jv, log = java(tmp_path)
    rc, j = dse(capsys, sp, tmp_path / "a", jv)
    first = sorted(json.dumps(r[1], sort_keys=True) for r in requests(log))
    rc2, j2 = dse(capsys, sp, tmp_path / "b", jv)  # another store: evaluated again, the same 5 points
    assert rc == rc2 == 0 and j["points"] == j2["points"] == 5 and j2["evaluated"] == 5
    assert len(set(first)) == 5 and sorted(json.dumps(r[1], sort_keys=True) for r in requests(log)[5:]) == first


def test_a_sweep_killed_by_a_signal_resumes(tmp_path, capsys):
    """SIGKILL of the driver mid-sweep (inline worker, WORKERS=0): every run committed before the kill is
    reused, only the rest is evaluated."""
    import signal
    import subprocess
    import time

    from dse.explore.knobs import ROOT

    sp, out = spaces.tiny(tmp_path), tmp_path / "out"
    jv, log = java(tmp_path, SLEEP=0.3)
    p = subprocess.Popen([sys.executable, "-m", "dse.explore.explore", "--space", str(sp), "--out", str(out), "--workers", "0",
                          "--java", jv, "--version", "t1"], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.time()
    while time.time() - t0 < 60 and count(out) < 3:
        time.sleep(0.1)
    p.send_signal(signal.SIGKILL)
    p.wait()
    done = len(stored(out))
    assert 3 <= done < 9
    rc, j = dse(capsys, sp, out, java(tmp_path)[0], workers=0)
    assert rc == 0 and (j["evaluated"], j["skipped"]) == (9 - done, done)


YOSYS_SPACE = ('[constraints]\nmax_lut = 3300\n[objectives]\nmaximize = ["rays_per_s"]\nminimize = ["lut"]\n'
               '[fidelity]\nrtl = true\nmargin = 1\nmax_rtl = 8\nyosys_margin = 0.1\n')


def test_yosys_synthesizes_exactly_the_confirmed_points_near_a_limit_and_re_decides_them(tmp_path, capsys, local_ray):
    # model: lut = 1000 TUS + NODE_CACHE, rays/s = 1e5 TUS (1 + NODE_CACHE/256); Yosys: lut x 1.09
    #   A (2,0) 2000 2e5 | B (2,64) 2064 2.5e5 | C (2,256) 2256 4e5 | D (3,0) 3000 3e5 | E (3,64) 3064 3.75e5 | F (3,256) 3256 6e5
    # all meet max_lut 3300 by the model; front A B C F, margin 1 adds E (rank 1, more rays/s than D); within 10 %
    # of 3300 are D E F. Yosys: E 3340 and F 3549 break the limit, so they leave; then D enters the confirm set
    # (rank 1 behind A B C), is near the limit too and is synthesized: 3270 meets it.
    sp, out = spaces.tiny(tmp_path, axes="TUS = [2, 3]\nNODE_CACHE = [0, 64, 256]", extra=YOSYS_SPACE), tmp_path / "out"
    jv, log = java(tmp_path, AREA=1, YOSYS_SCALE=1.09)
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0
    pid = {(t, n): store.point_id({"CONFIG": "small", "TUS": t, "NODE_CACHE": n}) for t in (2, 3) for n in (0, 64, 256)}
    A, B, C, D, E, F = (pid[k] for k in [(2, 0), (2, 64), (2, 256), (3, 0), (3, 64), (3, 256)])
    assert j["confirmed_yosys"] == [E, F, D]
    synth = [r[1] for r in requests(log) if r[0] == "area" and r[1]["fidelity"] == "yosys"]
    assert sorted((int(a["tus"]), int(a["node-cache"])) for a in synth) == [(3, 0), (3, 64), (3, 256)]
    assert sorted(j["yosys_overturned"]) == sorted([E, F])
    assert {p["point"] for p in j["pareto"]} == {A, B, C}
    assert set(j["confirmed_rtl"]) == {A, B, C, D}  # no RTL run of a point Yosys rejected
    assert j["best_per_board"]["any"]["point"] == C
    assert j["cost_rung_error"]["lut"]["n"] == 3
    assert j["cost_rung_error"]["lut"]["max_abs"] == pytest.approx(max(1 - 3000 / 3270, 1 - 3064 / 3340, 1 - 3256 / 3549))
    assert j["by_fidelity"]["yosys"] == {"evaluated": 3, "skipped": 0, "failed": 0}
    rows = {r["point"]: r for r in csv.DictReader(l for l in (out / "points.csv").read_text().splitlines() if not l.startswith("#"))}
    assert (rows[F]["feasible"], rows[F]["area_lut"], rows[F]["yosys_lut"]) == ("False", "3256", "3549")
    assert (rows[D]["feasible"], rows[D]["yosys_lut"], rows[A]["yosys_lut"]) == ("True", "3270", "")
    assert "Yosys: lut 3549 > max_lut 3300" in rows[F]["notes"] and "left the front" in rows[F]["notes"]
    report = (out / "report.md").read_text()
    assert "## Cost model against Yosys" in report
    assert f"| {F} | lut | 3256 | 3549 | -8.3 % | max_lut 3300 | meets → breaks |" in report
    assert f"| {D} | lut | 3000 | 3270 | -8.3 % | max_lut 3300 | meets → meets |" in report
    assert "Re-decided by Yosys: " in report
    # a rerun finds every synthesis in the store
    n = len(requests(log))
    rc, j2 = dse(capsys, sp, out, jv)
    assert rc == 0 and j2["evaluated"] == 0 and len(requests(log)) == n
    assert j2["by_fidelity"]["yosys"] == {"evaluated": 0, "skipped": 3, "failed": 0}
    assert (j2["confirmed_yosys"], j2["pareto"], j2["confirmed_rtl"]) == (j["confirmed_yosys"], j["pareto"], j["confirmed_rtl"])


def test_clock_fmax_ranks_at_the_measured_clock_and_names_it(tmp_path, capsys, local_ray):
    sp, out = spaces.tiny(tmp_path, axes='TUS = [1, 2]\nCLOCK_MHZ = ["fmax", 200]'), tmp_path / "out"
    jv, _ = java(tmp_path, FMAX_MHZ=123.5)
    rc, j = dse(capsys, sp, out, jv)
    assert rc == 0 and j["failed"] == 0, stored(out)
    rows = list(csv.DictReader(l for l in (out / "points.csv").read_text().splitlines() if not l.startswith("#")))
    clocks = {(r["TUS"], r["CLOCK_MHZ"]): (r["model_clock_mhz"], r["model_clock_source"]) for r in rows}
    assert clocks[("1", "fmax")] == ("123.5", "proxy") and clocks[("2", "200")] == ("200", "given"), clocks
    # without a measured clock the JVM refuses the point: recorded as failed with its message, the sweep goes on
    out2 = tmp_path / "out2"
    jv2, _ = java(tmp_path)
    rc, j = dse(capsys, sp, out2, jv2)
    assert rc == 0 and j["failed"] == 2, j
    assert any("CLOCK_MHZ=fmax" in (e or "") for _, _, _, e in stored(out2))
