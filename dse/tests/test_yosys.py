"""The Yosys rung of make dse without a JVM: which cost is near a limit (board capacities, max_* constraints),
the verdict a synthesis re-decides, and a bad [fidelity] yosys_margin refused at its line."""
import pytest

from dse.explore import report, rungs, space
from scenes.tests.helpers import run_cli

from .spaces import SCENE, line_no, refused, write


def cost(**kw):
    return {"lut": 1000, "lutram": 0, "ff": 1000, "dsp": 1, "bram36": 1, "fits": True, "board": None, **kw}


def test_near_a_board_capacity_below_or_above():
    # xc7a100t: 63,400 LUT sites, 126,800 FFs, 240 DSPs, 135 BRAM36 (boards/catalog.json)
    c = cost(board="xc7a100t", lut=58000, lutram=2000, bram36=130, dsp=10, ff=1000)
    # LUT sites: 58,000 logic + 2,000 LUT RAM = 60,000, 5.4 % below; BRAM36 3.7 % below; the others far below
    assert rungs.near_limit({}, c, 0.06) == [("lut", "xc7a100t", 60000, 63400), ("bram36", "xc7a100t", 130, 135)]
    assert rungs.near_limit({}, c, 0.05) == [("bram36", "xc7a100t", 130, 135)]
    assert rungs.near_limit({}, c, 0.03) == []
    over = cost(board="xc7a100t", lut=66000, dsp=250)  # above by 4.1 % and 4.2 %
    assert [r for r, *_ in rungs.near_limit({}, over, 0.05)] == ["lut", "dsp"]
    assert rungs.near_limit({}, over, 0.04) == []


def test_near_a_constraint_of_the_space_and_no_board():
    c = cost(dsp=10, ff=9000)
    cons = {"max_dsp": 12, "max_ff": 10000}
    assert rungs.near_limit(cons, c, 0.1) == [("ff", "max_ff", 9000, 10000)]
    assert rungs.near_limit(cons, c, 0.2) == [("ff", "max_ff", 9000, 10000), ("dsp", "max_dsp", 10, 12)]
    assert rungs.near_limit({}, c, 1.0) == []  # no board, no constraint: no limit to be near


class _Sp:
    constraints = {"fits": "BOARD"}


def summary():
    a = cost(board="xc7a100t", lut=60000)
    return {"point": "p", "config": {}, "metrics": {"cachesim": {"rays_per_s": 1.0}, "area": a}, "errors": [],
            "feasible": True, "notes": [], "objectives": {"rays_per_s": 1.0}}


def test_yosys_saying_it_does_not_fit_makes_the_point_infeasible():
    y = cost(board="xc7a100t", lut=64000, fits=False)
    s = report.with_yosys(_Sp, summary(), {"status": "infeasible", "error": "does not fit", "result": y})
    assert (s["feasible"], s["model_feasible"], s["yosys"]) == (False, True, {"status": "infeasible", "overturned": True})
    assert s["notes"][0] == "Yosys: does not fit the board" and "left the front" in s["notes"][1]
    assert s["metrics"]["yosys"]["lut"] == 64000 and s["metrics"]["area"]["lut"] == 60000
    assert s["objectives"] == {"rays_per_s": 1.0}  # still ranked on the model's figures


def test_yosys_agreeing_keeps_the_verdict_and_a_failed_synthesis_keeps_the_model_s():
    s = report.with_yosys(_Sp, summary(), {"status": "ok", "error": None, "result": cost(board="xc7a100t", lut=61000)})
    assert (s["feasible"], s["yosys"]["overturned"], s["notes"]) == (True, False, [])
    f = report.with_yosys(_Sp, summary(), {"status": "crashed", "error": "the JVM exited", "result": None})
    assert f["feasible"] and "yosys" not in f["metrics"] and "the model's verdict is kept" in f["notes"][0]


GOOD = f"""[space]
base = {{CONFIG = "small"}}
{SCENE}
[axes]
TUS = [1, 2]

[constraints]
max_lut = 3000

[fidelity]
yosys_margin = 0.1
"""


def test_a_good_yosys_margin_loads_and_the_default_is_off(tmp_path):
    assert space.load(write(tmp_path, GOOD)).fidelity["yosys_margin"] == 0.1
    assert space.load(write(tmp_path, GOOD.replace("yosys_margin = 0.1", "yosys_margin = 1"))).fidelity["yosys_margin"] == 1
    assert space.load(write(tmp_path, GOOD.replace("yosys_margin = 0.1", ""))).fidelity["yosys_margin"] is None


@pytest.mark.parametrize("value,words", [
    ("0", "yosys_margin = 0: give a fraction"), ("-0.1", "yosys_margin = -0.1: give a fraction"),
    ("1.5", "yosys_margin = 1.5: give a fraction"), ('"0.1"', "yosys_margin = '0.1': give a fraction"),
    ("true", "yosys_margin = True: give a fraction"),
])
def test_a_bad_yosys_margin_is_refused_at_its_line(tmp_path, value, words):
    text = GOOD.replace("yosys_margin = 0.1", f"yosys_margin = {value}")
    p, msg = refused(tmp_path, text)
    assert msg.startswith(f"{p}:{line_no(text, f'yosys_margin = {value}')}: {words}"), msg


def test_yosys_margin_without_the_cost_rung_is_refused(tmp_path):
    text = GOOD.replace("[constraints]\nmax_lut = 3000\n", "")
    p, msg = refused(tmp_path, text)
    assert msg.startswith(f"{p}:{line_no(text, 'yosys_margin = 0.1')}: yosys_margin compares"), msg


def test_make_dse_refuses_a_bad_yosys_margin_with_one_error_and_writes_nothing(tmp_path):
    text = GOOD.replace("yosys_margin = 0.1", "yosys_margin = 2")
    p, out = write(tmp_path, text), tmp_path / "out"
    r = run_cli("dse.explore.explore", "--space", str(p), "--out", str(out), "--java", "false")
    assert r.returncode == 2 and r.stdout == "" and not out.exists(), r.stderr
    assert r.stderr.strip().count("\n") == 0 and r.stderr.startswith(f"error: {p}:{text.splitlines().index('yosys_margin = 2') + 1}: yosys_margin = 2"), r.stderr
