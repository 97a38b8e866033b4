"""./rtaccel: the make targets with the tool's own exit status, and no variable make would silently ignore."""
import importlib.machinery
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
CP_FILE = os.environ.get("RTACCEL_CLASSPATH", "")
FIX = Path(os.environ.get("RTACCEL_FIXTURES", ROOT / "build/fixtures"))


def load_entry():
    loader = importlib.machinery.SourceFileLoader("rtaccel_entry", str(ROOT / "rtaccel"))
    mod = importlib.util.module_from_spec(importlib.util.spec_from_loader(loader.name, loader))
    loader.exec_module(mod)
    return mod


def run(root, *args):
    return subprocess.run([sys.executable, str(root / "rtaccel"), *args], capture_output=True, text=True, cwd=root)


# A two-level Makefile like `make run`'s: the outer recipe runs the inner make, whose tool exits $(CODE).
FAKE = """SHELL := $(if $(RTACCEL_STATUS),$(abspath tools/recipe-shell),/bin/bash)
RESULT := result.txt
.PHONY: outer inner
outer:
\t@set -o pipefail; $(MAKE) --no-print-directory inner CODE=$(CODE) | cat
inner:
\t@echo "[inner] working" >&2; echo $(CODE) > $(RESULT); echo '{"ok": false}'; exit $(CODE)
"""


@pytest.fixture
def fake(tmp_path):
    shutil.copy(ROOT / "rtaccel", tmp_path / "rtaccel")
    (tmp_path / "tools").mkdir()
    shutil.copy(ROOT / "tools/recipe-shell", tmp_path / "tools/recipe-shell")
    (tmp_path / "Makefile").write_text(FAKE)
    (tmp_path / "config").mkdir()
    shutil.copy(ROOT / "config/knobs.json", tmp_path / "config/knobs.json")
    return tmp_path


def test_the_makefiles_verbs_and_user_variables_not_its_internals():
    entry = load_entry()
    verbs, variables = entry.makefile_names((ROOT / "Makefile").read_text())
    assert {"run", "test", "check", "simulate", "timing", "verilog", "dse", "paper"} <= verbs
    assert {"SCENE", "OUT", "GOLDEN", "WIDTH"} <= variables
    # the platform knobs come from the registry's export, which the Makefile includes; none is spelled there
    knobs = entry.knob_names()
    assert {"CONFIG", "TUS", "NODE_CACHE", "BOX_FORMAT", "PIPELINE", "CLOCK_MHZ"} <= knobs
    # set unconditionally by the Makefile (a command-line value would replace its own) or make's own
    assert not {"JAVA", "ROOT", "PLATFORM_KNOBS", "MODEL_ARGS", "VCONFIG", "MAKE", "SHELL", "PIPESTATUS"} & variables


@pytest.mark.parametrize("code", [0, 2, 3])
def test_the_inner_tools_status_comes_out_where_make_says_2(fake, code):
    res = run(fake, "outer", f"CODE={code}")
    assert res.returncode == code, res.stderr
    assert json.loads(res.stdout.strip().splitlines()[-1]) == {"ok": False}
    assert "[inner] working" in res.stderr and "***" not in res.stderr
    plain = subprocess.run(["make", "-C", str(fake), "outer", f"CODE={code}"], capture_output=True, text=True)
    assert plain.returncode == (0 if code == 0 else 2)


@pytest.mark.parametrize("args,message", [
    (["outer", "CDOE=3"], "unknown variable 'CDOE'; did you mean CODE?"),
    (["outer", "code=3"], "unknown variable 'code'; did you mean CODE?"),
    (["outr", "CODE=3"], "unknown command 'outr'; did you mean outer?"),
    (["outer", "RESULT=x.txt"], "unknown variable 'RESULT'"),  # the Makefile's own name
    (["outer", "--code", "3"], "'--code' is not VAR=value"),
    (["outer", "CODE=3", "CODE=0"], "variable CODE given twice"),
])
def test_bad_input_is_refused_before_make_runs(fake, args, message):
    res = run(fake, *args)
    assert res.returncode == 2 and res.stderr.startswith(f"error: {message}"), res.stderr
    assert res.stdout == "" and not (fake / "result.txt").exists()


def test_no_verb_prints_usage_and_exits_2_help_exits_0(fake):
    assert run(fake).returncode == 2
    res = run(fake, "help")
    line = next(l for l in res.stderr.splitlines() if l.startswith("variables: "))
    assert res.returncode == 0 and "commands: inner outer" in res.stderr and {"CODE", "NODE_CACHE"} <= set(line.split()[1:])


@pytest.mark.skipif(not (CP_FILE and Path(CP_FILE).is_file()),
                    reason="compiled model absent: run through `make test` (sets RTACCEL_CLASSPATH)")
def test_check_on_a_corrupted_golden_exits_3_with_the_json_last(tmp_path):
    src = FIX / "soup"
    if not (src / "golden/hits.npy").exists():
        pytest.skip("procedural fixtures absent: run `make fixtures`")
    golden = tmp_path / "golden"
    shutil.copytree(src / "golden", golden)
    hits = np.load(golden / "hits.npy")
    hit = np.flatnonzero(hits["prim"] >= 0)[:7]
    hits["prim"][hit], hits["t"][hit] = -1, np.inf  # Embree "missed" rays the model hits
    np.save(golden / "hits.npy", hits)
    res = run(ROOT, "check", f"SCENE={src / 'scene.obj'}", f"GOLDEN={golden}")
    assert res.returncode == 3, res.stderr[-2000:]
    last = json.loads(res.stdout.strip().splitlines()[-1])
    assert last["unexplained"] == len(hit) and last["rays"] == len(hits)
    assert "***" not in res.stderr
