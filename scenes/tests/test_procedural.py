import json
import os

import numpy as np
import pytest

from scenes import procedural
from scenes.catalog import camera_for, fallback_camera, load_catalog
from scenes.load import load_triangles
from scenes.tests.helpers import run_cli, shared_scene


def test_deterministic_and_seed_dependent():
    for name in procedural.NAMES:
        assert procedural.obj_text(name, seed=7) == procedural.obj_text(name, seed=7)
    for name in ("hairball", "soup", "extreme"):
        assert procedural.obj_text(name, seed=1) != procedural.obj_text(name, seed=2)


@pytest.mark.parametrize("name,count", [("cornell", 396), ("hairball", 19200), ("soup", 2000), ("extreme", 366)])
def test_counts_and_exact_round_trip(tmp_path, name, count):
    p = tmp_path / f"{name}.obj"
    procedural.write_obj(name, str(p), seed=1)
    tris = load_triangles(str(p))
    assert tris.shape == (count, 3, 3)
    np.testing.assert_array_equal(tris, procedural.triangles(name, seed=1))


def test_scale_is_exact_float32_multiple(tmp_path):
    base = procedural.triangles("extreme")
    for s in (1e30, 1e-30):
        p = tmp_path / f"x{s}.obj"
        procedural.write_obj("extreme", str(p), scale=s)
        tris = load_triangles(str(p))
        v, f = procedural.generate("extreme", scale=s)
        np.testing.assert_array_equal(tris, v[f])
        np.testing.assert_allclose(tris.astype(np.float64), base.astype(np.float64) * s, rtol=1e-6)


def test_cornell_is_closed_and_shares_vertices():
    v, f = procedural.generate("cornell")
    # closed 2-manifold pieces: every undirected edge is used by exactly two triangles
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert np.all(counts == 2)
    assert len(v) < 3 * len(f) / 4  # vertices are shared
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert np.all(np.sum(np.abs(n) > 0, axis=1) == 1)  # axis-aligned faces


def test_cornell_every_camera_and_inside_ray_hits():
    from golden.export import camera_rays
    from golden.trace import embree_trace
    tris = procedural.triangles("cornell")
    cam = camera_for("cornell.obj", tris)
    assert cam["source"] == "catalog"
    rays = camera_rays(cam, 64, 48)
    rng = np.random.default_rng(0)
    inner = np.zeros((5000, 8), np.float32)
    inner[:, 0:3] = rng.uniform([-0.95, 1.3, -0.95], [0.95, 1.95, 0.95], (5000, 3))
    d = rng.normal(size=(5000, 3))
    inner[:, 3:6] = d / np.linalg.norm(d, axis=1, keepdims=True)
    inner[:, 7] = np.inf
    hits = embree_trace(tris, np.concatenate([rays, inner]))
    assert np.all(hits["prim"] >= 0)


def test_extreme_contents():
    from golden.check import degenerate_mask
    tris = procedural.triangles("extreme")
    deg = degenerate_mask(tris)
    assert deg.sum() >= 60
    t = tris.astype(np.float64)
    edges = np.linalg.norm(np.stack([t[:, 1] - t[:, 0], t[:, 2] - t[:, 1], t[:, 0] - t[:, 2]], 1), axis=2)
    ratio = edges.min(1) / np.maximum(edges.max(1), 1e-300)
    assert np.sum((ratio < 1e-3) & ~deg) >= 10  # needles
    assert edges.max() > 50 and np.sum(edges.max(1)[~deg] < 1e-3) >= 50  # huge and tiny


def test_cli_all_and_errors(tmp_path):
    r = run_cli("scenes.procedural", "--all", str(tmp_path))
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(tmp_path)) == sorted(n + ".obj" for n in procedural.NAMES)
    assert (tmp_path / "soup.obj").read_text() == procedural.obj_text("soup")
    for args in (["bogus", str(tmp_path / "b.obj")], ["soup", str(tmp_path / "b.obj"), "--scale", "1e39"],
                 ["soup", str(tmp_path / "nodir" / "b.obj")], ["--all", str(tmp_path / "nodir")]):
        r = run_cli("scenes.procedural", *args)
        assert r.returncode == 2, args
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert not (tmp_path / "b.obj").exists()


def test_catalog_entries():
    cat = load_catalog()
    for k in ("cornell_box_original", "teapot", "dragon_res4", "sponza_dabrovic", "stanford_bunny", "conference",
              *procedural.NAMES):
        e = cat[k]
        assert len(e["eye"]) == len(e["look_at"]) == len(e["up"]) == 3 and 0 < e["fov_deg"] < 180
        lo, hi = np.array(e["bbox"])
        if e["kind"].startswith("closed"):
            assert np.all(lo < e["eye"]) and np.all(np.array(e["eye"]) < hi), k


def test_fallback_and_scaled_cameras():
    tris = procedural.triangles("soup")
    cam = camera_for("something_unknown.obj", tris)
    assert cam == fallback_camera(tris) and cam["source"] == "fallback"
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    assert np.any((np.array(cam["eye"]) < lo) | (np.array(cam["eye"]) > hi))
    np.testing.assert_allclose(cam["look_at"], (lo.astype(float) + hi) / 2)
    big = procedural.triangles("extreme", scale=1e30)
    c1, c2 = camera_for("extreme.obj", procedural.triangles("extreme")), camera_for("extreme.obj", big)
    assert c2["source"] == "catalog-scaled"
    np.testing.assert_allclose(c2["eye"], np.array(c1["eye"]) * 1e30, rtol=1e-5)
    # a different mesh under a known name gets the fallback camera
    assert camera_for("conference.obj", tris)["source"] == "fallback"


@pytest.mark.parametrize("name", ["cornell_box_original", "sponza_dabrovic", "conference"])
def test_closed_real_scenes_camera_hits_everything(name):
    from golden.export import camera_rays
    from golden.trace import embree_trace
    p = shared_scene(name + ".obj")
    tris = load_triangles(p)
    cam = camera_for(p, tris)
    assert cam["source"] == "catalog"
    hits = embree_trace(tris, camera_rays(cam, 64, 48))
    assert np.mean(hits["prim"] >= 0) == 1.0
