import json

import numpy as np

from golden.export import camera_rays
from scenes import procedural
from scenes.catalog import camera_for
from scenes.tests.helpers import run_cli


def test_bench_single_thread_json(tmp_path):
    procedural.write_obj("soup", str(tmp_path / "soup.obj"))
    tris = procedural.triangles("soup")
    np.save(tmp_path / "rays.npy", camera_rays(camera_for("soup.obj", tris), 32, 24))
    r = run_cli("golden.bench", "--scene", str(tmp_path / "soup.obj"), "--rays", str(tmp_path / "rays.npy"),
                "--repeat", "2")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["rays"] == 768 and out["triangles"] == 2000 and out["threads"] == 1
    assert out["embree_build_s_median"] > 0 and out["embree_rays_per_s_median"] > 1000


def test_bench_errors(tmp_path):
    procedural.write_obj("soup", str(tmp_path / "soup.obj"))
    np.save(tmp_path / "bad.npy", np.zeros((4, 6), np.float32))
    for args in (["--rays", str(tmp_path / "bad.npy")], ["--rays", str(tmp_path / "bad.npy"), "--repeat", "0"]):
        r = run_cli("golden.bench", "--scene", str(tmp_path / "soup.obj"), *args)
        assert r.returncode == 2
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: ")
