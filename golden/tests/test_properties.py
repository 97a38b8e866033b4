"""Property tests of the rays/hits/triangles loaders (golden.io) and of the CLIs that read them: every bad file is
one UserError line in process, and exit 2 with one `error:` line and no output file through the CLI."""
import contextlib
import io
import json
import os
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from golden import image
from golden.io import HIT_DTYPE, load_hits, load_rays, load_tris
from scenes.cli import run
from scenes.errors import UserError
from scenes.tests.helpers import run_cli

FAST = settings(max_examples=40, derandomize=True, database=None, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])
CLI = settings(FAST, max_examples=3)

finite = st.floats(-1e3, 1e3, allow_nan=False, width=32)
bad_float = st.sampled_from([np.nan, np.inf, -np.inf])
other_dtypes = st.sampled_from([np.float64, np.float16, np.int32, np.int64, np.uint8, np.bool_, ">f4", "U3"])


@st.composite
def good_rays(draw, n=None):
    n = draw(st.integers(1, 6)) if n is None else n
    r = draw(hnp.arrays(np.float32, (n, 8), elements=finite))
    r[:, 3:6] += np.where(np.all(r[:, 3:6] == 0, axis=1, keepdims=True), 1, 0).astype(np.float32)
    r[:, 6] = np.abs(r[:, 6])
    r[:, 7] = np.maximum(r[:, 6], np.abs(r[:, 7])) if draw(st.booleans()) else np.inf
    return r


@st.composite
def bad_rays(draw):
    """Rays that must be refused: each is a good array with one thing broken."""
    r = draw(good_rays())
    i = draw(st.integers(0, len(r) - 1))
    kind = draw(st.sampled_from(["dtype", "columns", "ndim", "empty", "nonfinite", "nan_tmax", "zero_dir",
                                 "neg_tmin", "tmin_gt_tmax"]))
    if kind == "dtype":
        return r.astype(draw(other_dtypes))
    if kind == "columns":
        return np.zeros((len(r), draw(st.sampled_from([0, 1, 7, 9, 16]))), np.float32)
    if kind == "ndim":
        return draw(st.sampled_from([r.ravel(), r[None], r.reshape(len(r), 2, 4), np.float32(1)]))
    if kind == "empty":
        return r[:0]
    if kind == "nonfinite":
        r[i, draw(st.integers(0, 6))] = draw(bad_float)
    elif kind == "nan_tmax":
        r[i, 7] = np.nan
    elif kind == "zero_dir":
        r[i, 3:6] = 0
    elif kind == "neg_tmin":
        r[i, 6] = -draw(st.floats(0.5, 1e3, width=32))
    else:
        r[i, 7] = np.inf
        r[i, 6], r[i, 7] = 2, draw(st.floats(0, 1.5, width=32))
    return r


def good_hits(n):
    return hnp.arrays(HIT_DTYPE, n, elements=st.tuples(finite, st.integers(-3, 100), finite, finite)).map(
        lambda a: np.array(a, HIT_DTYPE))


@st.composite
def bad_hits(draw):
    """(hits, ray count) that must be refused."""
    n = draw(st.integers(1, 6))
    h = draw(good_hits(n))
    kind = draw(st.sampled_from(["dtype", "plain", "ndim", "count", "low_prim"]))
    if kind == "dtype":
        other = draw(st.sampled_from([[("t", "<f8"), ("prim", "<i4"), ("u", "<f4"), ("v", "<f4")],
                                      [("t", "<f4"), ("prim", "<i8"), ("u", "<f4"), ("v", "<f4")],
                                      [("t", "<f4"), ("prim", "<i4"), ("u", "<f4")],
                                      [("prim", "<i4"), ("t", "<f4"), ("u", "<f4"), ("v", "<f4")]]))
        return np.zeros(n, other), n
    if kind == "plain":
        return np.zeros((n, 4), draw(st.sampled_from([np.float32, np.int32]))), n
    if kind == "ndim":
        return np.stack([h, h]), n
    if kind == "count":
        return h, n + draw(st.sampled_from([-n, 1, 5])) if n > 1 else n + 1
    h["prim"][draw(st.integers(0, n - 1))] = draw(st.integers(-2 ** 31, -4))
    return h, n


@st.composite
def bad_tris(draw):
    t = draw(hnp.arrays(np.float32, (draw(st.integers(1, 5)), 3, 3), elements=finite))
    kind = draw(st.sampled_from(["dtype", "shape", "empty", "nonfinite"]))
    if kind == "dtype":
        return t.astype(draw(other_dtypes))
    if kind == "shape":
        return draw(st.sampled_from([t.reshape(len(t), 9), t.reshape(len(t), 9, 1), t[:, :2], t[:, :, :2], t[0]]))
    if kind == "empty":
        return t[:0]
    t[draw(st.integers(0, len(t) - 1)), draw(st.integers(0, 2)), draw(st.integers(0, 2))] = draw(bad_float)
    return t


not_npy = st.one_of(st.binary(max_size=200), st.just(b"\x93NUMPY\x01\x00garbage"),
                    st.just(b"\x93NUMPY\x01\x00\x76\x00{'descr': '<f4', 'fortran_order': False, 'shape': (9, 8), }"))


def save(d, name, data):
    p = os.path.join(d, name)
    if isinstance(data, bytes):
        with open(p, "wb") as f:
            f.write(data)
    else:
        np.save(p, data, allow_pickle=False)
    return p


def one_line(load, *args):
    with pytest.raises(UserError) as e:
        load(*args)
    msg = str(e.value)
    assert msg and "\n" not in msg and "Traceback" not in msg
    return msg


@FAST
@given(bad_rays())
def test_bad_rays_refused(r):
    with tempfile.TemporaryDirectory() as d:
        one_line(load_rays, save(d, "rays.npy", r))


@FAST
@given(bad_hits())
def test_bad_hits_refused(case):
    h, n = case
    with tempfile.TemporaryDirectory() as d:
        one_line(load_hits, save(d, "hits.npy", h), n)


@FAST
@given(bad_tris())
def test_bad_tris_refused(t):
    with tempfile.TemporaryDirectory() as d:
        one_line(load_tris, save(d, "tris.npy", t))


@FAST
@given(not_npy, st.sampled_from(["rays", "hits", "tris"]))
def test_not_an_npy_file_refused(data, which):
    load = {"rays": load_rays, "hits": load_hits, "tris": load_tris}[which]
    with tempfile.TemporaryDirectory() as d:
        assert "not a readable .npy" in one_line(load, save(d, "x.npy", data))


@FAST
@given(good_rays(), st.integers(1, 6).flatmap(good_hits))
def test_good_arrays_load_unchanged(r, h):
    """The bad cases above are one change away from these, which load as they are (fault codes included)."""
    with tempfile.TemporaryDirectory() as d:
        np.testing.assert_array_equal(load_rays(save(d, "r.npy", r)), r)
        assert np.array_equal(load_hits(save(d, "h.npy", h), len(h)), h)


# A valid `make golden` directory of 2x2 camera rays aimed at one big triangle, for the CLI tests to break.
TRIS = np.array([[[-10, -10, 5], [10, -10, 5], [0, 10, 5]]], np.float32)


def golden_dir(d):
    g = os.path.join(d, "golden")
    os.mkdir(g)
    rays = np.zeros((4, 8), np.float32)
    rays[:, 3:6] = [[0, 0, 1], [0.1, 0, 1], [0, 0.1, 1], [0.1, 0.1, 1]]
    rays[:, 7] = np.inf
    hits = np.zeros(4, HIT_DTYPE)
    hits["t"] = 5
    save(g, "rays.npy", rays)
    save(g, "hits.npy", hits)
    with open(os.path.join(g, "meta.json"), "w") as f:
        json.dump({"scene": "/s/tri.obj", "params": {"width": 2, "height": 2}, "rays_per_depth": [4]}, f)
    save(d, "tris.npy", TRIS)
    save(d, "model.npy", hits)
    return g


def bad_input():
    """(which file of the golden.image inputs, its bad content)."""
    return st.one_of(
        st.tuples(st.just("tris.npy"), st.one_of(bad_tris(), not_npy)),
        st.tuples(st.just("golden/rays.npy"), st.one_of(bad_rays(), not_npy)),
        st.tuples(st.sampled_from(["golden/hits.npy", "model.npy"]),
                  st.one_of(bad_hits().filter(lambda c: c[1] == 4 or c[0].shape != (4,)).map(lambda c: c[0]),
                            not_npy)))


def image_argv(d):
    return ["--tris", os.path.join(d, "tris.npy"), "--golden", os.path.join(d, "golden"),
            "--hits", os.path.join(d, "model.npy"), "--out", os.path.join(d, "pics")]


def files(d):
    return sorted(os.path.relpath(os.path.join(r, f), d) for r, _, fs in os.walk(d) for f in fs)


@FAST
@given(bad_input())
def test_image_cli_refuses_bad_files(case):
    name, data = case
    with tempfile.TemporaryDirectory() as d:
        golden_dir(d)
        save(d, name, data)
        before = files(d)
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()) as out, \
                pytest.raises(SystemExit) as e:
            run(image.main, image_argv(d))
        assert e.value.code == 2 and out.getvalue() == ""
        assert len(err.getvalue().splitlines()) == 1 and err.getvalue().startswith("error: ")
        assert files(d) == before and not os.path.exists(os.path.join(d, "pics"))


def test_image_cli_accepts_the_unbroken_inputs():
    """The base the property above breaks is itself good."""
    with tempfile.TemporaryDirectory() as d:
        golden_dir(d)
        with contextlib.redirect_stdout(io.StringIO()) as out, pytest.raises(SystemExit) as e:
            run(image.main, image_argv(d))
        assert e.value.code == 0 and json.loads(out.getvalue().splitlines()[-1])["differing_pixels"] == 0


@CLI
@given(bad_input())
def test_image_cli_process(case):
    """The same through a real `python -m golden.image`."""
    name, data = case
    with tempfile.TemporaryDirectory() as d:
        golden_dir(d)
        save(d, name, data)
        before = files(d)
        r = run_cli("golden.image", *image_argv(d))
        assert r.returncode == 2 and r.stdout == ""
        assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: ")
        assert files(d) == before


@CLI
@given(st.sampled_from(["f 1 2 3\n", "v 0 0 0\nv 1 0 0\nf 1 2\n", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", ""]),
       st.integers(1, 8), st.integers(1, 8))
def test_export_cli_refuses_bad_scene(text, w, h):
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "m.obj")
        with open(p, "w") as f:
            f.write(text)
        r = run_cli("golden.export", "--scene", p, "--out", os.path.join(d, "g"), "--width", str(w),
                    "--height", str(h))
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: ")
        assert os.listdir(d) == ["m.obj"]
