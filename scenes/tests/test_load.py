import csv
import os

import numpy as np
import pytest

from scenes.errors import SceneError
from scenes.load import file_sha256, load_triangles
from scenes.tests.helpers import SHARED_SCENES, run_cli, shared_scene


def _manifest():
    p = os.path.join(SHARED_SCENES, "MANIFEST.tsv")
    if not os.path.isfile(p):
        pytest.skip(f"{p} not available: real scenes are not beside the repository")
    with open(p) as f:
        return list(csv.DictReader(f, delimiter="\t"))


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"


def test_manifest_counts_and_degenerates():
    rows = _manifest()
    assert {r["name"] for r in rows} >= {"conference", "sponza_dabrovic"}
    for r in rows:
        tris = load_triangles(shared_scene(r["file"]))
        assert tris.dtype == np.float32 and tris.shape == (int(r["triangles"]), 3, 3), r["name"]
        assert tris.flags["C_CONTIGUOUS"]
        t = tris.astype(np.float64)
        zero = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1) == 0
        assert int(zero.sum()) == int(r["degenerate"]), r["name"]


def test_manifest_sha256_and_bbox():
    for r in _manifest():
        if r["name"] not in ("cornell_box_original", "teapot"):
            continue
        p = shared_scene(r["file"])
        assert file_sha256(p) == r["sha256"]
        lo, hi = (np.array([float(x) for x in s.split(",")]) for s in r["bbox"].split(".."))
        tris = load_triangles(p)
        np.testing.assert_allclose(tris.reshape(-1, 3).min(0), lo, rtol=1e-2, atol=1e-2)
        np.testing.assert_allclose(tris.reshape(-1, 3).max(0), hi, rtol=1e-2, atol=1e-2)


def test_order_multi_object_materials_and_fans(tmp_path):
    text = ("mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\n"
            "o first\nusemtl red\nf 1 2 3\nf 1 3 4\n"
            "o second\nusemtl blue\nf 5 6 7 4\n"
            "g third\nusemtl red\nf 1/1 2/1 3/1 4/1 5/1\nf 7 6 5\nvt 0 0\n")
    tris = load_triangles(_write(tmp_path, "m.obj", text))
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1]], np.float32)
    expect = [(0, 1, 2), (0, 2, 3), (4, 5, 6), (4, 6, 3), (0, 1, 2), (0, 2, 3), (0, 3, 4), (6, 5, 4)]
    np.testing.assert_array_equal(tris, v[np.array(expect)])


def test_no_merging_and_degenerates_kept(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nf 1 2 3\nf 1 2 3\nf 1 1 1\nf 4 2 3\nf 1 2 2\n"
    tris = load_triangles(_write(tmp_path, "d.obj", text))
    assert tris.shape == (5, 3, 3)
    np.testing.assert_array_equal(tris[0], tris[1])
    np.testing.assert_array_equal(tris[2], np.zeros((3, 3)))


@pytest.mark.parametrize("name,text,needle", [
    ("bad_number.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", "malformed"),
    ("bad_index.obj", TRI + "f 1 2 9\n", "out of range"),
    ("two_vertex_face.obj", TRI + "f 1 2\n", "fewer than 3"),
    ("zero_index.obj", TRI + "f 0 1 2\n", "index 0"),
    ("relative_index.obj", TRI + "f -3 -2 -1\n", "relative"),
    ("empty.obj", "", "no faces"),
    ("points_only.obj", TRI, "no faces"),
    ("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", "NaN or Inf"),
    ("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n", "NaN or Inf"),
    ("overflow.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", "float32 range"),
    ("mesh.stl", TRI, "unsupported extension"),
    ("noext", TRI, "unsupported extension"),
])
def test_errors(tmp_path, name, text, needle):
    p = _write(tmp_path, name, text)
    with pytest.raises(SceneError) as e:
        load_triangles(p)
    msg = str(e.value)
    assert needle in msg and "\n" not in msg and p in msg


def test_missing_file(tmp_path):
    with pytest.raises(SceneError, match="no such file"):
        load_triangles(str(tmp_path / "nope.obj"))


def test_ply_round_trip(tmp_path):
    import trimesh
    rng = np.random.default_rng(3)
    v = (np.round(rng.normal(size=(30, 3)) * 64) / 64).astype(np.float32)  # exact in ASCII too
    f = rng.integers(0, 30, size=(40, 3))
    for enc in ("binary", "ascii"):
        p = str(tmp_path / f"m_{enc}.ply")
        trimesh.Trimesh(v, f, process=False).export(p, encoding=enc)
        tris = load_triangles(p)
        np.testing.assert_array_equal(tris, v[f])


def test_ply_polygons_rejected(tmp_path):
    text = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    with pytest.raises(SceneError, match="non-triangle"):
        load_triangles(_write(tmp_path, "q.ply", text))


def test_export_cli(tmp_path):
    src = _write(tmp_path, "s.obj", TRI + "v 0 0 1\nf 1 2 3\nf 1 2 4\n")
    out = tmp_path / "s.npy"
    r = run_cli("scenes.export", src, str(out))
    assert r.returncode == 0, r.stderr
    arr = np.load(out)
    assert arr.dtype == np.float32 and arr.shape == (2, 3, 3) and arr.flags["C_CONTIGUOUS"]
    import json
    meta = json.loads((tmp_path / "s.json").read_text())
    assert meta == {"scene": os.path.abspath(src), "sha256": file_sha256(src), "triangles": 2,
                    "bbox": [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]}


def test_export_cli_error_writes_nothing(tmp_path):
    src = _write(tmp_path, "bad.obj", TRI + "f 1 2 9\n")
    out = tmp_path / "bad.npy"
    r = run_cli("scenes.export", src, str(out))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert sorted(os.listdir(tmp_path)) == ["bad.obj"]
