import json

import numpy as np
import pytest

from golden.check import CLASSES, classify, ray_classes, summary_text
from golden.io import HIT_DTYPE, GoldenError, check_hits, miss_hits
from scenes.tests.helpers import run_cli

# 0, 1: unit square z=1 split along its diagonal x=y; 2: duplicate of 0; 3: zero-area (collinear) at y=5;
# 4: copy of 0 moved 2e-5 further; 5: plane tilted about the line x=0.3 (crosses 0 there); 6: far triangle
TRIS = np.array([
    [[-1, -1, 1], [1, -1, 1], [1, 1, 1]],
    [[-1, -1, 1], [1, 1, 1], [-1, 1, 1]],
    [[-1, -1, 1], [1, -1, 1], [1, 1, 1]],
    [[5, 5, 1], [6, 5, 1], [7, 5, 1]],
    [[-1, -1, 1.00002], [1, -1, 1.00002], [1, 1, 1.00002]],
    [[0.3, -1, 1], [0.3, 1, 1], [2.3, 0, 2]],
    [[10, 10, 3], [11, 10, 3], [10, 11, 3]],
], np.float32)

CASES = []  # (origin, direction, golden (prim, t), model (prim, t), expected class)


def case(o, d, g, m, expect):
    CASES.append((o, d, g, m, expect))


up = (0, 0, 1)
case((0.5, -0.5, 0), up, (0, 1.0), (0, 1.0), "agree")              # same prim, same t
case((0.5, -0.5, 0), up, (0, 1.0), (0, 1.000005), "agree")         # same prim, t within 1e-5 (max_rel_t_err)
case((20, 20, 0), up, (-1, np.inf), (-1, np.inf), "agree")         # both miss
case((0.5, -0.5, 0), up, (0, 1.0), (2, 1.0), "agree")              # coincident duplicate
case((0.5, -0.5, 0), up, (0, 1.0), (6, 1.0 * (1 + 0.9e-5)), "agree")  # within 1e-5 relative t
case((0.5, -0.5, 0), up, (0, 1.0), (3, 1.5), "degenerate")         # model reports the zero-area triangle
case((0.25, 0.25, 0), up, (0, 1.0), (1, 1.0 + 2e-3), "edge")       # on the shared edge x=y
case((0.25, 0.25, 0), up, (0, 1.0), (-1, np.inf), "edge")          # one side misses on the edge
case((-1.5, 0.5, 1 - 1e-4), (1, 0, 1e-4), (1, 1.0), (-1, np.inf), "grazing")  # nearly parallel, not near an edge
case((0.5, -0.5, 0), up, (0, 1.0), (4, 1.00002), "tie")            # nearly coincident, 2e-5 > 1e-5
case((0.3001, -0.5, 0), up, (0, 1.0), (5, 1.7), "tie")             # model's prim also hit at golden's t
case((6, 5, 0), up, (-1, np.inf), (0, 1.0), "degenerate")          # passes through the zero-area triangle
case((0.5, -0.5, 0), up, (0, 1.0), (-1, np.inf), "unexplained")    # plain miss
case((0.5, -0.5, 0), up, (0, 1.0), (6, 3.0), "unexplained")        # wrong prim far away
case((0.5, -0.5, 0), up, (0, 1.0), (6, 1.0 * (1 + 1.1e-5)), "tie")  # just beyond the agree tolerance
case((0.5, -0.5, 0), up, (0, 1.0), (0, 1.00005), "tie")            # same prim, t within the tie tolerance only
case((0.5, -0.5, 0), up, (0, 1.0), (0, 1.001), "unexplained")      # same prim at a wrong t: not an agreement


def _arrays():
    n = len(CASES)
    rays = np.zeros((n, 8), np.float32)
    g, m = miss_hits(n), miss_hits(n)
    for i, (o, d, gh, mh, _) in enumerate(CASES):
        d = np.asarray(d, np.float64)
        rays[i, 0:3], rays[i, 3:6], rays[i, 7] = o, d / np.linalg.norm(d), np.inf
        for h, (p, t) in ((g, gh), (m, mh)):
            h[i]["prim"], h[i]["t"] = p, t
    return rays, g, m


def test_each_class_and_agree_rules():
    rays, g, m = _arrays()
    res = classify(TRIS, rays, g, m)
    expect = [c[4] for c in CASES]
    assert res["rays"] == len(CASES)
    assert res["agree"] == expect.count("agree")
    for cls in ("tie", "edge", "grazing", "degenerate"):
        want = [i for i, e in enumerate(expect) if e == cls]
        assert res["classified"][cls] == len(want), cls
        assert res["examples"][cls] == want, cls
    unexplained = [i for i, e in enumerate(expect) if e == "unexplained"]
    assert res["unexplained"] == len(unexplained)
    assert [u["ray"] for u in res["unexplained_rays"]] == unexplained
    assert res["max_rel_t_err"] == pytest.approx(0.001 / 1.001, rel=1e-4)


def test_ray_classes_match_classify():
    rays, g, m = _arrays()
    per = ray_classes(TRIS, rays, g, m)
    assert list(per) == [c[4] for c in CASES]
    res = classify(TRIS, rays, g, m)
    assert sum(per == "agree") == res["agree"] and sum(per == "unexplained") == res["unexplained"]
    assert {k: int(sum(per == k)) for k in CLASSES} == res["classified"]


# Rays that would agree (0), be an edge case (6), degenerate (5) or a plain miss (12) but the model faulted on.
FAULTED = ((0, -2), (6, -3), (5, -2), (12, -3), (2, -4))


def _faulted():
    rays, g, m = _arrays()
    for i, code in FAULTED:
        m[i]["prim"], m[i]["t"] = code, np.inf
    return rays, g, m


def test_faults_never_agree_and_count_as_unexplained():
    rays, g, m = _faulted()
    res = classify(TRIS, rays, g, m)
    base = classify(TRIS, *_arrays())
    assert res["faults"] == {"read_error": 2, "overflow": 2, "step_limit": 1}
    faulted = {i for i, _ in FAULTED}
    expect = [("fault" if i in faulted else c[4]) for i, c in enumerate(CASES)]
    assert res["agree"] == expect.count("agree") == base["agree"] - 2
    for cls in CLASSES:
        assert res["examples"][cls] == [i for i, e in enumerate(expect) if e == cls], cls
    want = sorted(faulted | {i for i, e in enumerate(expect) if e == "unexplained"})
    assert res["unexplained"] == len(want) == expect.count("unexplained") + len(FAULTED)
    assert [u["ray"] for u in res["unexplained_rays"]] == want
    assert list(res) == list(base) == ["rays", "agree", "classified", "unexplained", "max_rel_t_err", "disagree",
                                       "nonfinite_t_same_prim", "examples", "unexplained_rays", "faults"]
    assert base["faults"] == {"read_error": 0, "overflow": 0, "step_limit": 0}
    per = ray_classes(TRIS, rays, g, m)
    assert [per[i] for i, _ in FAULTED] == ["read_error", "overflow", "read_error", "overflow", "step_limit"]
    text = summary_text(res)
    assert "model faults: read error 2, stack overflow 2, step limit 1" in text.splitlines()[0]
    assert "unexplained ray 6 (model fault: stack overflow)" in text
    assert "unexplained ray 2 (model fault: step limit)" in text
    assert "unexplained ray 13: " in text  # a wrong prim is not called a fault


def test_hits_fault_codes_accepted_below_refused():
    h = miss_hits(4)
    h["prim"] = [-1, -2, -3, -4]
    assert check_hits(h) is h
    h["prim"][2] = -5
    with pytest.raises(GoldenError, match=r"prim -5 below -4 \(ray 2\); use -1 for a miss, -2 for a memory read "
                                          r"error, -3 for a stack overflow, -4 for the step limit"):
        check_hits(h)


def test_golden_with_fault_codes_refused():
    rays, g, m = _arrays()
    g[3]["prim"] = -3
    with pytest.raises(GoldenError, match="golden hits: ray 3 has fault code -3"):
        classify(TRIS, rays, g, m)


def test_identical_hits_all_agree():
    rays, g, _ = _arrays()
    res = classify(TRIS, rays, g, g.copy())
    assert res["agree"] == len(rays) and res["unexplained"] == 0 and res["max_rel_t_err"] == 0


def test_rejects_bad_inputs():
    rays, g, m = _arrays()
    with pytest.raises(GoldenError, match="records but there are"):
        classify(TRIS, rays, g, m[:-1])
    with pytest.raises(GoldenError, match="dtype"):
        classify(TRIS, rays, g, m.astype([("t", "<f8"), ("prim", "<i4"), ("u", "<f4"), ("v", "<f4")]))
    with pytest.raises(GoldenError, match="shape"):
        classify(TRIS, rays[:, :7].copy(), g, m)
    with pytest.raises(GoldenError, match="triangles"):
        classify(TRIS[:3], rays, g, m)
    with pytest.raises(GoldenError, match="shape"):
        classify(TRIS.reshape(-1, 9), rays, g, m)


def test_cli_json_last_line_and_errors(tmp_path):
    rays, g, m = _arrays()
    (tmp_path / "gold").mkdir()
    np.save(tmp_path / "gold" / "rays.npy", rays)
    np.save(tmp_path / "gold" / "hits.npy", g)
    np.save(tmp_path / "model.npy", m)
    np.save(tmp_path / "tris.npy", TRIS)
    args = ["golden.check", "--tris", str(tmp_path / "tris.npy"), "--golden", str(tmp_path / "gold"),
            "--hits", str(tmp_path / "model.npy")]
    r = run_cli(*args)
    assert r.returncode == 3, r.stderr  # unexplained rays: ran, but the check failed
    assert run_cli(*args, "--report-only").returncode == 0
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert list(out)[:6] == ["rays", "agree", "classified", "unexplained", "max_rel_t_err", "disagree"] or \
        list(out)[:5] == ["rays", "agree", "classified", "unexplained", "max_rel_t_err"]
    assert out["unexplained"] == [c[4] for c in CASES].count("unexplained") > 0 and "unexplained ray" in r.stderr
    np.save(tmp_path / "short.npy", m[:-2])
    np.save(tmp_path / "wrong.npy", np.zeros((len(m), 4), np.float32))
    for bad in ("short.npy", "wrong.npy", "missing.npy"):
        r = run_cli(*args[:-1], str(tmp_path / bad))
        assert r.returncode == 2, bad
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: ") and r.stdout == ""


def test_cli_reports_faults(tmp_path):
    rays, g, m = _faulted()
    (tmp_path / "gold").mkdir()
    np.save(tmp_path / "gold" / "rays.npy", rays)
    np.save(tmp_path / "gold" / "hits.npy", g)
    np.save(tmp_path / "tris.npy", TRIS)
    only = g.copy()  # faults alone must fail the check too
    only[0]["prim"] = -2
    only[0]["t"] = np.inf
    np.save(tmp_path / "model.npy", only)
    r = run_cli("golden.check", "--tris", str(tmp_path / "tris.npy"), "--golden", str(tmp_path / "gold"),
                "--hits", str(tmp_path / "model.npy"))
    assert r.returncode == 3, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["faults"] == {"read_error": 1, "overflow": 0, "step_limit": 0} and out["unexplained"] == 1
    assert out["agree"] == len(rays) - 1 and "model fault: read error" in r.stderr
