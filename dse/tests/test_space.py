"""Space files: the shipped ones load; a bad one is refused with one error naming the file and the line."""
import glob
import os

import pytest
from hypothesis import given, settings, strategies as hs

from dse.explore import space
from dse.explore.knobs import KNOBS, ROOT
from scenes.errors import UserError
from scenes.tests.helpers import run_cli

from .spaces import SCENE, line_no, refused, write

GOOD = f"""[space]
base = {{CONFIG = "small"}}
{SCENE}
[axes]
TUS = [1, 2]
NODE_CACHE = [0, 64]
NODE_POLICY = ["dm", "lru"]

[objectives]
maximize = ["rays_per_s"]
"""


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(ROOT, "dse", "spaces", "*.toml"))))
def test_shipped_spaces_load(path):
    try:
        sp = space.load(path)
    except UserError as e:
        if "shared/scenes" in str(e) and "not found" in str(e):
            pytest.skip(f"real scenes absent: {e}")
        raise
    assert sp.axes and sp.scenes and sp.objectives


@pytest.mark.parametrize("old,new,words", [
    ("NODE_POLICY = [", "NODE_POLICYY = [", "unknown knob 'NODE_POLICYY'"),
    ("NODE_CACHE = [0, 64]", "NODE_CACHE = [0, 100]", "NODE_CACHE = 100 is not allowed"),
    ("TUS = [1, 2]", "TUS = []", "axis TUS is empty"),
    ("maximize = [", "maximise = [", "unknown key 'maximise' in [objectives]"),
    ('maximize = ["rays_per_s"]', 'maximize = ["speed"]', "unknown objective 'speed'"),
    ('procedural = "cornell"', 'procedural = "kitchen"', "unknown procedural scene 'kitchen'"),
    ("[axes]", "[axis]", "unknown table [axis]"),
    ("width = 8", "width = 0", "width must be an integer >= 1"),
    ('base = {CONFIG = "small"}', 'base = {CONFIG = "big"}', "CONFIG = 'big' is not allowed"),
    ("TUS = [1, 2]", "TUS = [1, 1]", "lists a value twice"),
    ("NODE_CACHE = [0, 64]", "NODE_CACHE = [0, 64] x", "not valid TOML"),
])
def test_a_bad_space_names_the_line(tmp_path, old, new, words):
    text = GOOD.replace(old, new)
    p, msg = refused(tmp_path, text)
    assert words in msg, msg
    assert msg.startswith(f"{p}:{line_no(text, new.split('=')[0].strip() if '=' in new else new)}:"), msg


def test_make_dse_refuses_a_bad_space_with_one_error_and_writes_nothing(tmp_path):
    p = write(tmp_path, GOOD.replace("TUS = [1, 2]", "TUS = [0, 2]"))
    out = tmp_path / "out"
    r = run_cli("dse.explore.explore", "--space", str(p), "--out", str(out), "--java", "false")
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().count("\n") == 0 and r.stderr.startswith(f"error: {p}:{line_no(GOOD, 'TUS =')}: TUS = 0"), r.stderr
    assert r.stdout == "" and not out.exists()


@settings(max_examples=40, deadline=None)
@given(knob=hs.sampled_from(sorted(KNOBS)), bad=hs.sampled_from([-1, 3.5, "x", True, 10 ** 9]), pos=hs.integers(0, 2))
def test_any_illegal_value_on_any_axis_is_refused_at_its_line(tmp_path_factory, knob, bad, pos):
    if KNOBS[knob].ok(bad):
        return  # legal for this knob (e.g. MEM_GBPS = 3.5)
    axes = {"TUS": [1, 2], "NODE_CACHE": [0, 64], "M": [2, 4]}
    vals = {"TUS": 1, "M": 4, "MPPL": 4, "STACK": 32, "SHORT_STACK": 8, "NODE_CACHE": 64, "PRIM_CACHE": 64,
            "NODE_WAYS": 2, "PRIM_WAYS": 2, "MAX_LEVEL": 3, "NODE_POLICY": "dm", "PRIM_POLICY": "dm",
            "CONFIG": "small", "BOARD": "xc7a100t", "MEM_GBPS": 1.2, "CLOCK_MHZ": 150, "BOX_FORMAT": "bf16",
                "TRI_TEST": "watertight", "TRI_FORMAT": "fp64", "NODE_FORMAT": "q8", "PRIM_FORMAT": "packed",
            "IUS": 1, "MEM_CHANNELS": 2, "RESP_ORDER": "path", "RAY_STORE": 0, "TAG_FORWARD": 1, "NODE_BANKS": 0,
            "PIPELINE": "auto", "NODE_BYTES": 128, "PRIM_BYTES": 64, "CATALOG": "boards/catalog.json", "MEM_RETRIES": 1, "MAX_STEPS": 1000,
            "TRI_II": 1, "BOX_II": 1}
    axes.pop(knob, None)
    vs = [vals[knob]] * 3
    vs = list(dict.fromkeys(vs))  # one legal value, then the illegal one inserted at pos
    vs.insert(min(pos, len(vs)), bad)
    lines = [f"{k} = {_toml(v)}" for k, v in axes.items()] + [f"{knob} = {_toml(vs)}"]
    text = f"[space]\n{SCENE}\n[axes]\n" + "\n".join(lines) + "\n"
    p, msg = refused(tmp_path_factory.mktemp("h"), text)
    assert msg.startswith(f"{p}:{line_no(text, f'{knob} =')}: {knob} = {bad!r} is not allowed"), msg


def _toml(v):
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    return f'"{v}"' if isinstance(v, str) else repr(v)


def test_an_error_in_the_second_scene_names_its_line(tmp_path):
    text = GOOD.replace("[axes]", '[[scenes]]\nprocedural = "soup"\nwidth = -3\n\n[axes]')
    p, msg = refused(tmp_path, text)
    assert msg.startswith(f"{p}:{line_no(text, 'width = -3')}: width must be"), msg
