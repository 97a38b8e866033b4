"""dse.paper.caches (driven by a fake JVM, dse/tests/fake_java.py) and dse.plots.caches on synthetic CSVs."""
import csv
import json
import os
import shlex
import sys

import numpy as np
import pytest

from dse.plots import caches as plot_caches
from scenes.tests.helpers import run_cli

from .fake_java import SWEEP

FAKE = f"{shlex.quote(sys.executable)} {shlex.quote(os.path.join(os.path.dirname(__file__), 'fake_java.py'))}"
PNG = b"\x89PNG\r\n\x1a\n"


def assert_png(path):
    data = open(path, "rb").read()
    assert data[:8] == PNG and len(data) > 5000, path


def one_error_line(r):
    lines = r.stderr.strip().splitlines()
    assert [l for l in lines if not l.lstrip().startswith("[")] == [lines[-1]] and lines[-1].startswith("error: "), r.stderr
    return lines[-1]


@pytest.fixture
def inputs(tmp_path, monkeypatch):
    """tris.npy, golden rays.npy + meta.json, and a log of the fake JVM's invocations."""
    np.save(tmp_path / "tris.npy", np.zeros((1, 9), np.float32))
    g = tmp_path / "golden"
    g.mkdir()
    np.save(g / "rays.npy", np.zeros((2, 8), np.float32))
    (g / "meta.json").write_text(json.dumps({"params": {"width": 128, "height": 96, "depth": 5, "seed": 1}}))
    monkeypatch.setenv("FAKE_JAVA_LOG", str(tmp_path / "java.log"))
    return tmp_path


def drive(t, *extra, out="out"):
    return run_cli("dse.paper.caches", "--scene", "/scenes/room.obj", "--tris", str(t / "tris.npy"),
                   "--rays", str(t / "golden" / "rays.npy"), "--out", str(t / out), "--java", FAKE, *extra)


def java_runs(t):
    return [json.loads(l) for l in (t / "java.log").read_text().splitlines()] if (t / "java.log").exists() else []


def test_cache_figures_from_cachesim(inputs):
    t = inputs
    r = drive(t, "--mppl-list", "1,4,16")
    assert r.returncode == 0, r.stderr
    out = t / "out"
    assert sorted(os.listdir(out)) == ["cachesim.jsonl", "fig11_miss_rate.csv", "fig11_miss_rate.png",
                                       "fig8_9_bytes_per_ray.csv", "fig8_9_bytes_per_ray.png"]
    # One sweep run, then per MPPL the node-only and the node+prim run, with the paper's cache sizes.
    runs = java_runs(t)
    assert [(m, a["mppl"], a.get("node-cache"), a.get("prim-cache"), "sweep-out" in a) for m, a in runs] == [
        ("rtaccel.cli.CacheSim", "4", None, None, True)] + [
        ("rtaccel.cli.CacheSim", k, n, p, False) for k in ("1", "4", "16") for n, p in (("8192", None), ("4096", "4096"))]
    assert all(a["config"] == "fit" and a["m"] == "4" and a["scene-label"] == "/scenes/room.obj" for _, a in runs)
    assert runs[2][1]["prim-policy"] == "dm" and runs[1][1]["node-policy"] == "dm"

    # Fig 11: provenance first, then CacheSim's CSV unchanged (its trailing comment included).
    f11 = (out / "fig11_miss_rate.csv").read_text()
    first, body = f11.split("\n", 1)
    assert first.startswith("# scene=/scenes/room.obj rays=1000 golden=128x96 depth=5 seed=1 config=fit M=4 ")
    assert first.endswith("rtaccel=fake-1") and "MPPL=4" in first
    assert body == SWEEP
    comments, sizes, rates = plot_caches.read_fig11(str(out / "fig11_miss_rate.csv"))
    assert list(sizes) == [256, 512, 1024, 2048, 4096, 8192]
    assert rates["lrp4"][2] == pytest.approx(0.10556) and rates["bf"][-1] == pytest.approx(0.00512)
    assert "lru_4way" in rates and comments[-1].startswith("90 replays")

    # Figs 8-9: 3 variants x 3 MPPL, numbers as CacheSim reported them; no cache = the *_nocache fields.
    text = (out / "fig8_9_bytes_per_ray.csv").read_text()
    assert text.startswith("# scene=/scenes/room.obj ") and "rtaccel=fake-1" in text.splitlines()[0]
    assert " nodes_by_mppl=1:500,4:500,16:500 " in text.splitlines()[0]
    rows = list(csv.DictReader(l for l in text.splitlines() if not l.startswith("#")))
    assert [(r["mppl"], r["variant"]) for r in rows] == [
        (k, v) for k in ("1", "4", "16") for v in ("nocache", "node", "node_prim")]
    by = {(int(r["mppl"]), r["variant"]): r for r in rows}
    assert float(by[4, "nocache"]["node_bytes_per_ray"]) == pytest.approx(650.0)
    assert float(by[4, "nocache"]["prim_bytes_per_ray"]) == pytest.approx(440.0)
    assert by[4, "nocache"]["node_miss_rate"] == "" and by[4, "node"]["prim_miss_rate"] == ""
    assert float(by[16, "node"]["node_bytes_per_ray"]) == pytest.approx(162.5 * 0.01)
    assert float(by[1, "node_prim"]["dram_bytes_per_ray"]) == pytest.approx(2600 * 0.03 + 410 * 0.4)
    assert float(by[1, "node_prim"]["prim_miss_rate"]) == pytest.approx(0.4)
    _, mppls, d = plot_caches.read_bytes(str(out / "fig8_9_bytes_per_ray.csv"))
    assert list(mppls) == [1, 4, 16] and np.isnan(d["nocache"]["node_miss_rate"]).all()
    assert len((out / "cachesim.jsonl").read_text().splitlines()) == 7
    for png in ("fig11_miss_rate.png", "fig8_9_bytes_per_ray.png"):
        assert_png(out / png)
    assert "Figs 12-13 skipped" in r.stderr


def test_tus_step_with_cache_and_uncached_comparison(inputs):
    t = inputs
    nocache = t / "nocache.csv"
    nocache.write_text("# scene=/scenes/room.obj rays=50 config=paper2017 node_cache=none rtaccel=x\n"
                       "tus,rays,cycles,rays_per_s,mem_utilisation\n1,50,900,100000,0.2\n2,50,600,150000,0.4\n")
    r = drive(t, "--mppl-list", "4", "--tus-list", "1,8", "--nocache-csv", str(nocache))
    assert r.returncode == 0, r.stderr
    tus = [a for m, a in java_runs(t) if m == "rtaccel.cli.SweepTus"]
    assert len(tus) == 1 and tus[0]["tus-list"] == "1,8" and tus[0]["node-cache"] == "8192"
    assert tus[0]["node-policy"] == "dm" and tus[0]["config"] == "paper2017"
    csv_text = (t / "out" / "tus_sweep.csv").read_text()
    assert "node_cache=8192x1-dm" in csv_text.splitlines()[0] and len(csv_text.splitlines()) == 4
    assert "[sweep] /scenes/room.obj: TUs=8" in r.stderr  # the JVM's progress reaches the user
    assert_png(t / "out" / "fig12_13_tus.png")
    assert not [f for f in os.listdir(t / "out") if f.startswith(".tmp")]


def test_tus_step_refuses_an_uncached_sweep(inputs, monkeypatch):
    t = inputs
    assert drive(t, "--mppl-list", "4").returncode == 0
    monkeypatch.setenv("FAKE_JAVA_MODE", "nocache")
    r = drive(t, "--mppl-list", "4", "--tus-list", "1")
    assert r.returncode == 1
    assert "did not simulate the 8192x1-dm node cache" in one_error_line(r)
    assert not (t / "out" / "tus_sweep.csv").exists() and not (t / "out" / "fig12_13_tus.png").exists()


@pytest.mark.parametrize("args, words", [
    (("--mppl-list", "1,3"), "power of two"),
    (("--mppl-list", "1,x"), "comma-separated integers"),
    (("--mppl-list", ""), "--mppl-list is empty"),
    (("--tus-list", "0,2"), "1..1024"),
    (("--tus-list", "2,2"), "twice"),
    (("--m", "3"), "--m must be 2, 4 or 8"),
    (("--java", " "), "no JVM command"),
    (("--bogus", "1"), "unrecognized arguments"),
])
def test_bad_arguments_refused_before_any_run(inputs, args, words):
    t = inputs
    r = drive(t, *args)
    assert r.returncode == 2
    assert words in one_error_line(r)
    assert java_runs(t) == [] and not (t / "out").exists()


def test_bad_input_files_refused(inputs):
    t = inputs
    (t / "golden" / "rays.npy").write_text("not numpy")
    r = drive(t)
    assert r.returncode == 2 and "--rays" in one_error_line(r) and "is not a .npy file" in one_error_line(r)
    (t / "golden" / "rays.npy").unlink()
    r = drive(t)
    assert r.returncode == 2 and "rays.npy does not exist" in one_error_line(r)
    np.save(t / "golden" / "rays.npy", np.zeros((2, 8), np.float32))
    r = drive(t, out="missing/out")
    assert r.returncode == 2 and "missing of --out does not exist" in one_error_line(r)
    assert java_runs(t) == [] and sorted(os.listdir(t)) == ["golden", "tris.npy"]


@pytest.mark.parametrize("mode, status, words", [
    ("refuse", 2, "Fig 11 sweep, MPPL=4: MPPL 4 does not fit the 2-bit leaf count field"),
    ("crash", 1, "exited with status 1: Exception in thread \"main\" java.lang.OutOfMemoryError"),
])
def test_jvm_failure_is_one_line_and_writes_nothing(inputs, monkeypatch, mode, status, words):
    t = inputs
    monkeypatch.setenv("FAKE_JAVA_MODE", mode)
    r = drive(t)
    assert r.returncode == status
    assert words in one_error_line(r)
    assert os.listdir(t / "out") == []  # the scratch sweep file is gone too


def test_jvm_check_failure_names_its_failures_and_writes_nothing(inputs, monkeypatch):
    t = inputs
    monkeypatch.setenv("FAKE_JAVA_MODE", "check-fails")
    r = drive(t)
    assert r.returncode == 3
    line = one_error_line(r)
    assert "Fig 11 sweep, MPPL=4: rtaccel.cli.CacheSim check failed: mismatch_vs_model=3, lost=1" in line
    assert len(java_runs(t)) == 1  # the driver stopped at the first failed check
    assert os.listdir(t / "out") == []


def test_tus_check_failure_plots_nothing_for_it(inputs, monkeypatch):
    t = inputs
    monkeypatch.setenv("FAKE_JAVA_MODE", "check-fails-tus")
    r = drive(t, "--mppl-list", "4", "--tus-list", "1,8")
    assert r.returncode == 3
    assert "Figs 12-13 sweep: rtaccel.cli.SweepTus check failed: mismatch_vs_model=3, lost=1" in one_error_line(r)
    out = sorted(os.listdir(t / "out"))
    assert "tus_sweep.csv" not in out and "fig12_13_tus.png" not in out and "fig11_miss_rate.png" in out
    assert not [f for f in out if f.startswith(".tmp")]


def test_status_3_without_a_json_line_is_a_broken_contract(inputs, monkeypatch):
    t = inputs
    monkeypatch.setenv("FAKE_JAVA_MODE", "check-fails-nojson")
    r = drive(t)
    assert r.returncode == 1
    assert "exited with status 3 (check failed) but no line starts with '{'" in one_error_line(r)
    assert os.listdir(t / "out") == []


SCENE_A = SWEEP.replace("config,", "# scene=/s/a.obj rays=9 config=fit rtaccel=v1\nconfig,", 1)
BYTES = """# scene=/s/a.obj rays=9 config=fit M=4 rtaccel=v1
mppl,variant,node_bytes_per_ray,prim_bytes_per_ray,dram_bytes_per_ray,node_miss_rate,prim_miss_rate
1,nocache,3000,300,3300,,
1,node,30,300,330,0.01,
1,node_prim,80,150,230,0.03,0.5
2,nocache,2000,350,2350,,
2,node,25,350,375,0.01,
2,node_prim,70,160,230,0.035,0.45
"""


def test_plot_caches_combined(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text(SCENE_A)
    b.write_text(SCENE_A.replace("/s/a.obj", "/s/b.obj"))
    r = run_cli("dse.plots.caches", "fig11", str(tmp_path / "f11.png"), str(a), str(b))
    assert r.returncode == 0, r.stderr
    assert_png(tmp_path / "f11.png")
    (tmp_path / "bytes.csv").write_text(BYTES)
    r = run_cli("dse.plots.caches", "bytes", str(tmp_path / "b.png"), str(tmp_path / "bytes.csv"), str(tmp_path / "bytes.csv"))
    assert r.returncode == 0, r.stderr
    assert_png(tmp_path / "b.png")
    comments, mppls, d = plot_caches.read_bytes(str(tmp_path / "bytes.csv"))
    assert plot_caches.scene_name(comments, "x") == "a" and list(mppls) == [1, 2]
    assert list(d["node_prim"]["prim_miss_rate"]) == [0.5, 0.45]
    assert list(d["node"]["dram_bytes_per_ray"]) == [330, 375]


@pytest.mark.parametrize("kind, text, words", [
    ("fig11", SCENE_A.replace("lrp3,", "lrpx,"), "lacks row(s) lrp3"),
    ("fig11", SCENE_A.replace("0.11121", "1.5"), "miss rates must be in 0..1"),
    ("fig11", SCENE_A.replace("0.11121,", ""), "has 5 values for 6 sizes"),
    ("fig11", SCENE_A.replace("config,256", "policy,256"), "header must be config"),
    ("bytes", BYTES.replace("2,node_prim,70,160,230,0.035,0.45\n", ""), "variant node_prim needs one row for every MPPL"),
    ("bytes", BYTES.replace("dram_bytes_per_ray,", ""), "lacks column(s) dram_bytes_per_ray"),
    ("bytes", BYTES.replace("1,node,30", "1,nodes,30"), "unknown variant 'nodes'"),
    ("bytes", BYTES.replace("3000", "lots"), "is 'lots', not a number"),
])
def test_plot_caches_refuses_bad_csv(tmp_path, kind, text, words):
    good = tmp_path / "good.csv"
    good.write_text(SCENE_A if kind == "fig11" else BYTES)
    (tmp_path / "bad.csv").write_text(text)
    r = run_cli("dse.plots.caches", kind, str(tmp_path / "out.png"), str(good), str(tmp_path / "bad.csv"))
    assert r.returncode == 2
    assert words in one_error_line(r)
    assert sorted(os.listdir(tmp_path)) == ["bad.csv", "good.csv"]  # the good CSV alone is not plotted either
