"""Property tests of the mesh parser: every malformed OBJ/PLY is refused with one UserError line, in process and
through `python -m scenes.export` (exit 2, one `error:` line, no output file)."""
import contextlib
import io
import os
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scenes.cli import run
from scenes.errors import UserError
from scenes.export import main as export_main
from scenes.load import load_triangles
from scenes.tests.helpers import run_cli

# Deterministic (same examples every run, no example database in the tree) and small enough to stay fast.
FAST = settings(max_examples=40, derandomize=True, database=None, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])
CLI = settings(FAST, max_examples=4)

coord = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False, width=32)
vertex = st.tuples(coord, coord, coord)
nonfinite = st.sampled_from(["nan", "NaN", "inf", "-inf", "1e39"])  # 1e39: beyond float32


def obj_text(verts, faces):
    return "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in verts) + "".join(
        "f " + " ".join(map(str, f)) + "\n" for f in faces)


@st.composite
def valid_obj(draw):
    """(vertices, faces) of a well-formed OBJ: 1-based indices, faces of 3..5 vertices."""
    verts = draw(st.lists(vertex, min_size=3, max_size=8))
    n = len(verts)
    faces = draw(st.lists(st.lists(st.integers(1, n), min_size=3, max_size=5), min_size=1, max_size=5))
    return verts, faces


@st.composite
def bad_obj(draw):
    """OBJ text that must be refused, and a word its error must contain."""
    verts, faces = draw(valid_obj())
    n = len(verts)
    kind = draw(st.sampled_from(["index_high", "index_zero", "index_negative", "short_face", "nonfinite",
                                 "no_faces", "too_few_vertices", "empty"]))
    i = draw(st.integers(0, len(faces) - 1))
    j = draw(st.integers(0, len(faces[i]) - 1))
    if kind == "index_high":
        faces[i][j] = draw(st.integers(n + 1, n + 1000))
    elif kind == "index_zero":
        faces[i][j] = 0
    elif kind == "index_negative":
        faces[i][j] = draw(st.integers(-n - 5, -1))
    elif kind == "short_face":
        faces[i] = faces[i][:draw(st.integers(1, 2))]
    elif kind == "nonfinite":
        text = obj_text(verts, faces).splitlines()
        k = faces[i][j] - 1  # a vertex a face uses, so the bad number reaches a triangle
        parts = text[k].split()
        parts[draw(st.integers(1, 3))] = draw(nonfinite)
        text[k] = " ".join(parts)
        return "\n".join(text) + "\n", ("NaN or Inf", "float32 range", "malformed")
    elif kind == "no_faces":
        faces = []
    elif kind == "too_few_vertices":
        verts = verts[:draw(st.integers(0, 2))]
        faces = [[1, 2, 3]]
    else:
        return draw(st.sampled_from(["", "\n\n", "# only a comment\n", "   \t\n"])), ("no faces",)
    words = {"index_high": ("out of range",), "index_zero": ("index 0",), "index_negative": ("negative",),
             "short_face": ("fewer than 3",), "no_faces": ("no faces",), "too_few_vertices": ("out of range",)}
    return obj_text(verts, faces), words[kind]


def ply_text(verts, faces, declared_verts=None, declared_faces=None):
    head = ("ply\nformat ascii 1.0\n"
            f"element vertex {len(verts) if declared_verts is None else declared_verts}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(faces) if declared_faces is None else declared_faces}\n"
            "property list uchar int vertex_indices\nend_header\n")
    return head + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in verts) + "".join(
        f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)


@st.composite
def bad_ply(draw):
    verts = draw(st.lists(vertex, min_size=3, max_size=6))
    n = len(verts)
    faces = draw(st.lists(st.lists(st.integers(0, n - 1), min_size=3, max_size=3), min_size=1, max_size=4))
    kind = draw(st.sampled_from(["index_high", "index_negative", "quad", "nonfinite", "no_faces", "truncated",
                                 "no_magic", "no_end_header"]))
    i = draw(st.integers(0, len(faces) - 1))
    if kind == "index_high":
        faces[i][0] = draw(st.integers(n, n + 1000))
    elif kind == "index_negative":
        faces[i][0] = draw(st.integers(-1000, -1))
    elif kind == "quad":
        faces[i] = faces[i] + [0]
    elif kind == "nonfinite":
        v = list(verts[faces[i][0]])
        v[draw(st.integers(0, 2))] = draw(nonfinite)
        verts[faces[i][0]] = tuple(v)
        return ply_text(verts, faces).replace("'", "")
    elif kind == "no_faces":
        return ply_text(verts, [])
    elif kind == "truncated":
        text = ply_text(verts, faces)
        return text[:text.index("end_header\n") + 11 + draw(st.integers(0, 6))]
    elif kind == "no_magic":
        return ply_text(verts, faces)[3:]
    else:
        return ply_text(verts, faces).replace("end_header", "end_heder")
    return ply_text(verts, faces)


def one_line_user_error(path):
    with pytest.raises(UserError) as e:
        load_triangles(path)
    msg = str(e.value)
    assert msg and "\n" not in msg and "Traceback" not in msg
    return msg


def write(d, name, data):
    p = os.path.join(d, name)
    with open(p, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)
    return p


@FAST
@given(bad_obj())
def test_malformed_obj_is_one_user_error(case):
    text, words = case
    with tempfile.TemporaryDirectory() as d:
        msg = one_line_user_error(write(d, "m.obj", text))
    assert any(w in msg for w in words), (msg, text)


@FAST
@given(bad_ply())
def test_malformed_ply_is_one_user_error(text):
    with tempfile.TemporaryDirectory() as d:
        one_line_user_error(write(d, "m.ply", text))


@FAST
@given(st.binary(max_size=300), st.sampled_from([".obj", ".ply"]), st.booleans())
def test_junk_is_refused_or_a_valid_mesh(junk, ext, ply_header):
    """Random bytes (after a PLY header, or alone) never crash the loader: either a finite float32 mesh or one
    UserError line."""
    if ply_header and ext == ".ply":
        junk = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n" \
               b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + junk
    with tempfile.TemporaryDirectory() as d:
        p = write(d, "junk" + ext, junk)
        try:
            tris = load_triangles(p)
        except UserError as e:
            assert str(e) and "\n" not in str(e)
        else:
            assert tris.dtype == np.float32 and tris.ndim == 3 and tris.shape[1:] == (3, 3)
            assert len(tris) > 0 and np.isfinite(tris).all()


@FAST
@given(valid_obj())
def test_valid_obj_loads_as_fans(case):
    """The generator's good half is really good: the bad cases above differ from it in one place only."""
    verts, faces = case
    with tempfile.TemporaryDirectory() as d:
        tris = load_triangles(write(d, "m.obj", obj_text(verts, faces)))
    v = np.array(verts, np.float32)
    want = [v[[f[0] - 1, f[k] - 1, f[k + 1] - 1]] for f in faces for k in range(1, len(f) - 1)]
    np.testing.assert_array_equal(tris, np.array(want))


def export_in_process(argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as e:
        run(export_main, argv)
    return e.value.code, err.getvalue()


@FAST
@given(st.one_of(bad_obj().map(lambda c: ("m.obj", c[0])), bad_ply().map(lambda t: ("m.ply", t))))
def test_export_refuses_with_exit_2_and_writes_nothing(case):
    name, text = case
    with tempfile.TemporaryDirectory() as d:
        code, err = export_in_process([write(d, name, text), os.path.join(d, "out.npy")])
        assert code == 2
        assert len(err.splitlines()) == 1 and err.startswith("error: ")
        assert sorted(os.listdir(d)) == [name]


@CLI
@given(st.one_of(bad_obj().map(lambda c: ("m.obj", c[0].encode())), bad_ply().map(lambda t: ("m.ply", t.encode())),
                 st.binary(min_size=1, max_size=200).map(lambda b: ("m.obj", b"\x00\xff" + b))))
def test_export_cli_process(case):
    """The same through a real `python -m scenes.export` (nothing else, e.g. a library warning, on stderr)."""
    name, data = case
    with tempfile.TemporaryDirectory() as d:
        r = run_cli("scenes.export", write(d, name, data), os.path.join(d, "out.npy"))
        assert r.returncode == 2, r.stderr
        assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: ") and r.stdout == ""
        assert sorted(os.listdir(d)) == [name]
