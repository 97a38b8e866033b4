"""make fidelity (dse.studies.fidelity) on the procedural Cornell room with the fake JVM server (fake_serve.py), inline
(no Ray): the CSV's columns, every error taken against the RTL row of the same point and scene, the store reused
by a rerun, and exit 3 (no plot of it, no error from it) when an RTL run fails its check."""
import csv
import json

import pytest

from dse.studies import fidelity

from .test_explore import java, requests

ARGS = ["--scenes", "cornell", "--tus", "1,4", "--caches", "none,dm", "--mppls", "4", "--node-cache", "256",
        "--width", "8", "--height", "6", "--depth", "0", "--workers", "0", "--version", "t1"]


def run(capsys, tmp_path, jv):
    rc = fidelity.main([*ARGS, "--out", str(tmp_path / "fid"), "--java", jv])
    j = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    with open(tmp_path / "fid" / "fidelity.csv") as f:
        head = f.readline()
        rows = list(csv.DictReader(f))
    return rc, j, head, rows


def test_ladder_errors_against_the_rtl_row_and_a_rerun_from_the_store(tmp_path, capsys):
    jv, log = java(tmp_path)
    rc, j, head, rows = run(capsys, tmp_path, jv)
    assert rc == 0 and j["configurations"] == 4 and j["scenes"] == ["cornell"] and j["failed"] == []
    assert head.startswith("# scene=") and "rtaccel=t1" in head and "frame=8x6" in head
    assert list(rows[0]) == fidelity.COLUMNS and len(rows) == 4
    assert {(r["cache"], int(r["tus"])) for r in rows} == {("none", 1), ("none", 4), ("dm", 1), ("dm", 4)}
    for r in rows:
        nc, tus = int(r["node_cache"]), int(r["tus"])
        assert nc == (256 if r["cache"] == "dm" else 0)
        pred = 1e5 * tus * (1 + nc / 256)
        # the fake RTL: 0.8 x the prediction, 1.25 x the DRAM bytes, the miss rate 0.001 below the model's
        assert float(r["rtl_rays_per_s"]) == pytest.approx(0.8 * pred)
        assert float(r["mva_err"]) == pytest.approx(0.25)
        assert float(r["mva_no_hol_err"]) == pytest.approx(1.5 / 0.8 - 1)
        assert float(r["bw_bound_err"]) == pytest.approx(2 / 0.8 - 1)
        assert float(r["dram_bytes_err"]) == pytest.approx(1 / 1.25 - 1)
        if nc:
            assert float(r["node_miss_diff"]) == pytest.approx(0.001)
        else:
            assert r["node_miss_diff"] == ""  # no node cache: nothing to compare
        assert r["prim_miss_diff"] == ""  # no primitive cache: nothing to compare
        assert float(r["cachesim_wall_s_per_ray"]) == pytest.approx(0.75 / 100)
        assert r["cachesim_status"] == r["rtl_status"] == "ok"
    m = j["rungs"]["mva"]
    assert m["median_abs_err"] == pytest.approx(0.25) and m["max_abs_err"] == pytest.approx(0.25) and m["n"] == 4
    assert j["rungs"]["cachesim"]["dram_bytes_err"]["max_abs_err"] == pytest.approx(0.2)
    assert j["rungs"]["mva"]["wall_s_per_ray"] == pytest.approx(1e-6)
    assert set(j["mva_by_tus"]) == {"1", "4"} and j["png"].endswith("fidelity.png")
    md = (tmp_path / "fid" / "fidelity.md").read_text()
    assert "| mva | rays_per_s |" in md and "| 25.0 % | 25.0 % | 4 |" in md and "| 4 | 25.0 % |" in md
    assert len(requests(log)) == 8  # 4 cache-model runs and 4 RTL runs
    # a rerun finds every run in the store and makes none
    rc2, j2, _, rows2 = run(capsys, tmp_path, jv)
    assert rc2 == 0 and j2["evaluated"] == 0 and j2["skipped"] == 8 and len(requests(log)) == 8
    assert rows2 == rows


def test_a_failed_rtl_check_exits_3_and_is_left_out_of_errors_and_plot(tmp_path, capsys):
    jv, _ = java(tmp_path, CHECK_FAIL_TUS=4)
    rc, j, _, rows = run(capsys, tmp_path, jv)
    assert rc == 3
    bad = [r for r in rows if r["rtl_status"] != "ok"]
    assert {(r["cache"], r["tus"]) for r in bad} == {("none", "4"), ("dm", "4")}
    assert all(r["rtl_status"] == "check_failed" and r["mva_err"] == "" and r["rtl_rays_per_s"] == "" and
               "mismatch_vs_model" in r["error"] for r in bad)
    assert len(j["failed"]) == 2 and j["rungs"]["mva"]["n"] == 2 and set(j["mva_by_tus"]) == {"1"}


def test_bad_grid_is_one_input_error(tmp_path, capsys):
    jv, log = java(tmp_path)
    with pytest.raises(fidelity.UserError, match="unknown cache kind 'lru'"):
        fidelity.main([*ARGS[:4], "--caches", "lru", "--out", str(tmp_path / "x"), "--java", jv])
    with pytest.raises(fidelity.UserError, match="FIDELITY_TUS"):
        fidelity.main(["--tus", "0", "--out", str(tmp_path / "x"), "--java", jv])
    assert not (tmp_path / "x").exists() and requests(log) == []
