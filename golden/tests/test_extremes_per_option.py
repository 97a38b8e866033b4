"""The extreme-value suite of docs/numerics.md run for every numerics option (BOX_FORMAT x TRI_TEST, and the node,
primitive and triangle formats beside fp32 Möller–Trumbore and the watertight test with bf16 boxes), not only fp32:
per option no lost rays, no hit a box test lost (against every triangle without boxes), no leak out of the closed
room along axis-parallel and subnormal directions, ±0 alike, every ray of the room scaled by 1e±30 hitting, and -
for the watertight test - no leak through shared edges and vertices. RTL == model for these options is PlatformSpec's
and IuPipesSpec's. Needs the compiled model (make test sets RTACCEL_CLASSPATH) and the fixtures."""
import subprocess
from pathlib import Path

import numpy as np
import pytest

from golden.io import load_hits, load_rays
from scenes import procedural

from .test_reference_model import (CP_FILE, FIX, _edge_and_vertex_rays, _room_eyes, _write, axis_parallel_rays, model_trace,
                                   needs_model, run_check)
from golden.trace import embree_trace

# (BOX_FORMAT, TRI_TEST, the other formats as trace flags)
OPTIONS = [(b, t, ()) for t in ("mt", "watertight") for b in ("fp32", "fp24", "fp16", "bf16")] + [
    ("fp32", "mt", ("--node-format", "q8")), ("fp32", "mt", ("--prim-format", "packed")),
    ("bf16", "watertight", ("--node-format", "q4", "--prim-format", "packed")), ("fp32", "mt", ("--tri-format", "fp64"))]
FLAG_KEYS = {"--node-format": "node_format", "--prim-format": "prim_format", "--tri-format": "tri_format"}
SUBNORMAL = np.float32(1e-40)


def _trace(tmp_path, tris, rays, box, tri, more, name, exhaustive=0):
    d = tmp_path / name
    d.mkdir()
    tp, rp = _write(d, tris, rays)
    extra = ("--box-format", box, "--tri-test", tri) + tuple(more) + (("--exhaustive", str(exhaustive)) if exhaustive else ())
    hits, summary = model_trace(tp, rp, d / "m", extra=extra)
    n = summary["numerics"]
    fitted = n["box_format"]
    assert (fitted == box or (box.startswith("m") and fitted.endswith(box))) and n["tri_test"] == tri
    assert all(n[FLAG_KEYS[f]] == v for f, v in zip(more[::2], more[1::2])), n
    return hits, summary


def _refused(tmp_path, tris, rays, box, tri, more, name):
    """The stderr of a trace that must exit with the input-error status and write nothing."""
    d = tmp_path / name
    d.mkdir()
    tp, rp = _write(d, tris, rays)
    cp = Path(CP_FILE).read_text().strip()
    res = subprocess.run(["java", "-cp", cp, "rtaccel.cli.Trace", "--tris", str(tp), "--rays", str(rp), "--out", str(d / "m"),
                          "--box-format", box, "--tri-test", tri, *more], capture_output=True, text=True)
    assert res.returncode == 2 and not (d / "m" / "hits.npy").exists(), (res.returncode, res.stderr)
    return res.stderr


@needs_model
@pytest.mark.parametrize("box,tri,more", OPTIONS, ids=lambda v: (" ".join(v) or "-") if isinstance(v, tuple) else v)
def test_extreme_values_for_every_option(box, tri, more, tmp_path):
    room = procedural.triangles("cornell")
    # axis-parallel rays whose other components are +0, -0 or subnormal, from points inside the room, some of them
    # exactly on the planes of the boxes inside it (the grid hits the room's own coordinates)
    pts, rays = axis_parallel_rays(room, 5, (0.0, -0.0, SUBNORMAL, -SUBNORMAL))
    hits, s = _trace(tmp_path, room, rays, box, tri, more, "axis", exhaustive=len(rays))
    assert (hits["prim"] >= 0).all(), f"{int((hits['prim'] < 0).sum())} axis-parallel rays left the closed room"
    assert s["lost_hits"] == 0, f"a box test lost hits on rays {s['lost_hit_rays']}"
    n = len(pts)
    for k in range(0, len(rays), 4 * n):  # +0 and -0 give bit-identical records
        a, b = hits[k:k + n], hits[k + n:k + 2 * n]
        assert (a["prim"] == b["prim"]).all() and (a["t"].view(np.int32) == b["t"].view(np.int32)).all()

    # the extreme fixture (needles, zero-area and tiny triangles, vertex stars) with its golden rays
    d = FIX / "extreme"
    if (d / "golden" / "rays.npy").exists():
        tris = np.load(d / "tris.npy")
        er = load_rays(str(d / "golden/rays.npy"))
        eh, es = _trace(tmp_path, tris, er, box, tri, more, "extreme", exhaustive=len(er))
        assert es["lost_hits"] == 0 and (eh["prim"] >= -1).all()
        assert run_check(tris, er, load_hits(str(d / "golden/hits.npy")), eh)["unexplained"] == 0

    # the room at 1e+30 and 1e-30: the power-of-two normalisation keeps coordinates in range, but distances stay
    # in the user's units (t near 1e+-30), which fp16's 5-bit exponent cannot hold: it is refused with a message
    # naming the format and both numbers, and BOX_FORMAT=m10 (fp16's fraction, exponent fitted) runs instead
    dirs = np.random.default_rng(4).normal(size=(300, 3)).astype(np.float32)
    for scale in (1e30, 1e-30):
        t = (room.astype(np.float64) * scale).astype(np.float32)
        l2, h2 = t.reshape(-1, 3).min(0), t.reshape(-1, 3).max(0)
        r = np.zeros((len(dirs), 8), np.float32)
        r[:, 0:3], r[:, 3:6], r[:, 7] = ((l2 + h2) / 2).astype(np.float32), dirs, np.inf
        name, run_box = f"scaled{scale:g}", box
        if box == "fp16":
            err = _refused(tmp_path, t, r, box, tri, more, name + "-refused")
            assert "BOX_FORMAT=fp16 cannot represent scene" in err and "exponent bits" in err, err
            run_box = "m10"
        sh, ss = _trace(tmp_path, t, r, run_box, tri, more, name)
        assert ss["normalize_exponent"] != 0 and (sh["prim"] >= 0).all(), f"scale {scale}: a ray left the room"

    # shared edges and vertices: the watertight test leaks nothing whatever the box format
    if tri == "watertight":
        er = _edge_and_vertex_rays(room, _room_eyes(room, 2))
        wh, _ = _trace(tmp_path, room, er, box, tri, more, "edges")
        assert (wh["prim"] >= 0).all(), f"{int((wh['prim'] < 0).sum())} of {len(er)} rays leaked"
