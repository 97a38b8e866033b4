import json
import os

import numpy as np
import pytest

from golden.io import HIT_DTYPE
from scenes import procedural
from scenes.tests.helpers import run_cli

META_KEYS = {"scene", "sha256", "triangles", "embreex_version", "embree_version", "scene_flags", "params", "camera",
             "rays_per_depth", "rtaccel_version", "bounce_offset"}


@pytest.fixture(scope="module")
def scenes_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("scenes")
    for n in ("cornell", "hairball"):
        procedural.write_obj(n, str(d / f"{n}.obj"))
    return d


def _export(scene, out, *extra):
    return run_cli("golden.export", "--scene", str(scene), "--out", str(out), *extra)


def _load(out):
    return (np.load(out / "rays.npy"), np.load(out / "hits.npy"), json.loads((out / "meta.json").read_text()))


def test_format_and_meta(scenes_dir, tmp_path):
    out = tmp_path / "g"
    r = _export(scenes_dir / "cornell.obj", out, "--width", "16", "--height", "12", "--depth", "3")
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(out)) == ["hits.npy", "meta.json", "rays.npy"]
    rays, hits, meta = _load(out)
    assert rays.dtype == np.float32 and rays.ndim == 2 and rays.shape[1] == 8
    assert hits.dtype == HIT_DTYPE and hits.shape == (len(rays),)
    assert META_KEYS <= set(meta)
    assert meta["params"] == {"width": 16, "height": 12, "depth": 3, "seed": 1}
    assert meta["triangles"] == 396 and meta["scene_flags"] == ["RTC_SCENE_FLAG_ROBUST"]
    assert meta["embreex_version"] == "4.4.0.post1" and meta["rtaccel_version"]
    # closed room: every path survives every bounce
    assert meta["rays_per_depth"] == [192] * 4 and sum(meta["rays_per_depth"]) == len(rays)
    assert np.all(rays[:, 6] == 0) and np.all(np.isposinf(rays[:, 7]))
    np.testing.assert_allclose(np.linalg.norm(rays[:, 3:6].astype(np.float64), axis=1), 1, atol=1e-6)
    assert np.all(rays[:192, 0:3] == np.array(meta["camera"]["eye"], np.float32))
    assert np.all(hits["prim"] >= 0) and np.all(np.isfinite(hits["t"])) and np.all(hits["t"] > 0)


def test_depth_counts_and_misses(scenes_dir, tmp_path):
    out = tmp_path / "h"
    r = _export(scenes_dir / "hairball.obj", out, "--depth", "2")
    assert r.returncode == 0, r.stderr
    rays, hits, meta = _load(out)
    per = meta["rays_per_depth"]
    assert per[0] == 64 * 48 and len(per) == 3 and sum(per) == len(rays)
    # each bounce level has exactly one ray per hit of the previous level (no zero-area triangles here)
    start = np.cumsum([0] + per)
    for k in range(2):
        assert per[k + 1] == int(np.sum(hits["prim"][start[k]:start[k + 1]] >= 0))
    miss = hits["prim"] == -1
    assert miss.any() and np.all(np.isposinf(hits["t"][miss]))
    assert np.all(hits["u"][miss] == 0) and np.all(hits["v"][miss] == 0)
    # a bounce ray starts off the surface: just above the previous hit point
    k0 = np.nonzero(hits["prim"][:per[0]] >= 0)[0][0]
    p = rays[k0, 0:3].astype(np.float64) + hits["t"][k0] * rays[k0, 3:6]
    assert 0 < np.linalg.norm(rays[per[0], 0:3] - p) < 1e-3


def test_seeded_reproducibility(scenes_dir, tmp_path):
    outs = []
    for name, seed in (("a", "5"), ("b", "5"), ("c", "6")):
        r = _export(scenes_dir / "cornell.obj", tmp_path / name, "--width", "8", "--height", "8", "--seed", seed)
        assert r.returncode == 0, r.stderr
        outs.append(_load(tmp_path / name))
    assert np.array_equal(outs[0][0], outs[1][0]) and np.array_equal(outs[0][1], outs[1][1])
    assert not np.array_equal(outs[0][0], outs[2][0])
    assert np.array_equal(outs[0][0][:64], outs[2][0][:64])  # camera rays do not depend on the seed


@pytest.mark.parametrize("args", [["--width", "0"], ["--height", "-3"], ["--depth", "-1"], ["--seed", "-1"],
                                  ["--width", "abc"], ["--bogus"]])
def test_bad_parameters_write_nothing(scenes_dir, tmp_path, args):
    out = tmp_path / "out"
    r = _export(scenes_dir / "cornell.obj", out, *args)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert os.listdir(tmp_path) == []


def test_bad_scene_keeps_previous_output(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 nan\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("old")
    r = _export(bad, out)
    assert r.returncode == 2 and r.stderr.startswith("error: ") and len(r.stderr.strip().splitlines()) == 1
    assert os.listdir(out) == ["keep.txt"]
    assert sorted(os.listdir(tmp_path)) == ["bad.obj", "out"]
