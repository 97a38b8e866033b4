"""dse.studies.run_summary on a synthetic `make run` directory."""
import json

import pytest

from scenes.tests.helpers import run_cli

CHECK = {"rays": 100, "agree": 97, "classified": {"tie": 1, "edge": 0, "grazing": 0, "degenerate": 0},
         "unexplained": 2, "max_rel_t_err": 1e-7, "faults": {"read_error": 1, "overflow": 1}}
ANALYZE = {"bytes_per_ray": {"1": {"node": 900.0, "prim": 90.0, "total": 990.0},
                             "4": {"node": 500.0, "prim": 150.0, "total": 650.0}},
           "levels_for_mppl": 4, "top4_levels_nodes": 85, "top4_levels_node_share": 0.1,
           "top4_levels_access_share": 0.6}
SIM = {"config": "paper2017", "tus": 32, "m": 4, "mppl": 4, "cycles": 12345.0, "rays_per_s_at_clock": 1.2e6,
       "clock_mhz": 150.0, "mem_utilisation": 0.4, "mismatch_vs_model": 0, "lost": 0, "duplicated": 0,
       "sim_cycles_per_wall_s": 5e3, "node_cache": {"entries": 0}, "prim_cache": {"entries": 0},
       "cache_counts_match_model": True, "ok": True, "failures": []}


@pytest.fixture
def run_dir(tmp_path):
    (tmp_path / "golden").mkdir()
    (tmp_path / "golden" / "meta.json").write_text(json.dumps({"scene": "/s/room.obj", "triangles": 12,
                                                                "rays_per_depth": [60, 40]}))
    (tmp_path / "check.log").write_text("rays 100: ...\n" + json.dumps(CHECK) + "\n")
    (tmp_path / "analyze.log").write_text(json.dumps(ANALYZE) + "\n")
    return tmp_path


def summary(d, sim=None):
    if sim is not None:
        (d / "simulate.log").write_text("[sim] progress\n" + json.dumps(sim) + "\n")
    r = run_cli("dse.studies.run_summary", str(d))
    return r, r.stdout.splitlines()


def test_without_simulation(run_dir):
    r, out = summary(run_dir)
    assert r.returncode == 0, r.stderr
    assert "            model faults: read error 1, stack overflow 1, step limit 0" in out
    assert not [l for l in out if l.startswith("image ") or "check:" in l]
    j = json.loads(out[-1])
    assert j["unexplained"] == 2 and "rtl_ok" not in j and j["node_bytes_per_ray"] == 500.0


def test_simulation_ok_and_image_line(run_dir):
    (run_dir / "simulate").mkdir()
    (run_dir / "simulate" / "image.png").write_bytes(b"\x89PNG")
    r, out = summary(run_dir, SIM)
    assert r.returncode == 0, r.stderr
    assert "            check: ok" in out
    assert f"image       {run_dir}/simulate/image.png" in out
    j = json.loads(out[-1])
    assert j["rtl_ok"] is True and j["rtl_failures"] == [] and j["rtl_cycles"] == 12345.0


def test_simulation_check_failed_is_exit_3(run_dir):
    r, out = summary(run_dir, {**SIM, "ok": False, "failures": ["mismatch_vs_model=3", "lost=1"]})
    assert r.returncode == 3
    assert "            check: FAILED: mismatch_vs_model=3, lost=1" in out
    j = json.loads(out[-1])  # the report and its JSON line are still complete
    assert j["rtl_ok"] is False and j["rtl_failures"] == ["mismatch_vs_model=3", "lost=1"]
    err = r.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: RTL simulation check failed: mismatch_vs_model=3, lost=1")


def test_older_simulate_json_without_ok_still_reads(run_dir):
    sim = {k: v for k, v in SIM.items() if k not in ("ok", "failures")}
    r, out = summary(run_dir, sim)
    assert r.returncode == 0, r.stderr
    assert "rtl_ok" not in json.loads(out[-1]) and not [l for l in out if "check:" in l]


def test_missing_json_line_is_one_error(run_dir):
    (run_dir / "analyze.log").write_text("the analysis crashed\n")
    r, _ = summary(run_dir)
    assert r.returncode == 1 and r.stderr.strip() == f"error: no JSON result line in {run_dir}/analyze.log; " \
                                                     f"the step that writes it failed"
