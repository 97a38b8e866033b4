"""dse.studies.bench_caches on synthetic simulate / cachesim JSON lines."""
import json

import pytest

from dse.studies import bench_caches


def sim(tus, misses, hits, cycles, wall):
    return {"rays": 1000, "tus": tus, "cycles": cycles, "sim_cycles_per_wall_s": cycles / wall, "sim_wall_s": wall,
            "rays_per_s_at_clock": 1000 / cycles * 150e6, "dram_bytes_per_ray": 300.0, "cache_counts_match_model": True,
            "node_cache": {"entries": 8192, "policy": "dm", "hits": hits, "misses": misses,
                           "miss_rate": misses / (hits + misses)},
            "scene": "s.obj", "config": "paper2017", "rtaccel": "test"}


def model(tus, misses, hits, wall, trace):
    return {"rays": 1000, "tus": tus, "node_cache": {"entries": 8192, "policy": "dm", "miss_rate": misses / (hits + misses)},
            "bandwidth_bound_rays_per_s": 2e6, "predicted_rays_per_s": 6e4, "dram_bytes_per_ray": 290.0, "wall_s": wall, "trace_s": trace,
            "accesses_per_s": 3e7, "repeat": 5}


def write(d, name, obj):
    (d / name).write_text("[log] noise\n" + json.dumps(obj) + "\n")


def test_table_csv_and_json(tmp_path, capsys):
    write(tmp_path, "sim-tu1.json", sim(1, 50, 950, 3_000_000, 12.0))
    write(tmp_path, "model-tu1.json", model(1, 50, 950, 0.002, 0.05))
    write(tmp_path, "sim-tu8.json", sim(8, 60, 940, 1_000_000, 4.0))
    write(tmp_path, "model-tu8.json", model(8, 55, 945, 0.002, 0.05))
    out = tmp_path / "bench.csv"
    bench_caches.main(str(out), "s", str(tmp_path))
    lines = out.read_text().splitlines()
    assert lines[0].startswith("# scene=s.obj config=paper2017 node_cache=8192xdm rtaccel=test")
    assert len(lines) == 4  # provenance, header, TUs 1 and 8
    j = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    r1, r8 = j["rows"]
    assert (r1["tus"], r8["tus"]) == (1, 8)
    assert r1["miss_rate_diff_points"] == pytest.approx(0.0)
    assert r8["miss_rate_diff_points"] == pytest.approx(-0.5)  # model 5.5 % vs RTL 6.0 %
    assert r1["rtl_us_per_ray"] == pytest.approx(12_000.0)
    assert r1["predicted_over_rtl"] == pytest.approx(6e4 / (1000 / 3_000_000 * 150e6))
    assert r1["model_replay_us_per_ray"] == pytest.approx(2.0)
    assert r1["model_trace_replay_us_per_ray"] == pytest.approx(52.0)


def test_refuses_mismatched_runs(tmp_path):
    write(tmp_path, "sim-tu4.json", sim(4, 50, 950, 3_000_000, 12.0))
    m = model(4, 50, 950, 0.002, 0.05)
    m["node_cache"]["entries"] = 4096
    write(tmp_path, "model-tu4.json", m)
    with pytest.raises(SystemExit, match="error: TUS=4: RTL and model must simulate the same node cache"):
        bench_caches.main(str(tmp_path / "b.csv"), "s", str(tmp_path))
    assert not (tmp_path / "b.csv").exists()


def test_refuses_empty_dir(tmp_path):
    with pytest.raises(SystemExit, match="error: no sim-tuN.json"):
        bench_caches.main(str(tmp_path / "b.csv"), "s", str(tmp_path))


@pytest.mark.parametrize("name", ["sim-tu1.json", "model-tu1.json"])
def test_refuses_a_run_whose_check_failed(tmp_path, capsys, name):
    runs = {"sim-tu1.json": sim(1, 50, 950, 3_000_000, 12.0), "model-tu1.json": model(1, 50, 950, 0.002, 0.05)}
    runs[name].update(ok=False, failures=["mismatch_vs_model=2", "lost=1"])
    for n, j in runs.items():
        write(tmp_path, n, j)
    with pytest.raises(SystemExit) as e:
        bench_caches.main(str(tmp_path / "b.csv"), "s", str(tmp_path))
    assert e.value.code == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {tmp_path / name}: the run's check failed "
                                                f"(mismatch_vs_model=2, lost=1)")
    assert not (tmp_path / "b.csv").exists()


def test_cli_check_failure_is_exit_3_and_ok_true_passes(tmp_path):
    from scenes.tests.helpers import run_cli

    s = sim(1, 50, 950, 3_000_000, 12.0)
    write(tmp_path, "sim-tu1.json", {**s, "ok": True, "failures": []})
    write(tmp_path, "model-tu1.json", model(1, 50, 950, 0.002, 0.05))
    r = run_cli("dse.studies.bench_caches", str(tmp_path / "b.csv"), "s", str(tmp_path))
    assert r.returncode == 0, r.stderr
    (tmp_path / "b.csv").unlink()
    write(tmp_path, "sim-tu1.json", {**s, "ok": False, "failures": ["lost=4"]})
    r = run_cli("dse.studies.bench_caches", str(tmp_path / "b.csv"), "s", str(tmp_path))
    assert r.returncode == 3 and r.stderr.count("\n") == 1 and "check failed (lost=4)" in r.stderr
    assert not (tmp_path / "b.csv").exists() and r.stdout == ""
