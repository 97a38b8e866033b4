"""Small space files for the dse tests, written from text so each test shows its whole space."""
import textwrap

import pytest

from dse.explore import space
from scenes.errors import UserError

SCENE = """
[[scenes]]
procedural = "cornell"
width = 8
height = 6
depth = 0
"""


def write(tmp_path, body, name="t"):
    p = tmp_path / f"{name}.toml"
    p.write_text(textwrap.dedent(body))
    return p


def tiny(tmp_path, axes="TUS = [1, 2, 4]\nNODE_CACHE = [0, 64, 256]", extra="", name="tiny"):
    return write(tmp_path, f"[space]\nbase = {{CONFIG = \"small\"}}\n{SCENE}\n[axes]\n{axes}\n{extra}", name)


def line_no(text, needle):
    return next(i + 1 for i, l in enumerate(text.splitlines()) if needle in l)


def refused(tmp_path, text):
    """(path, message) of the one error that loading `text` as a space file raises."""
    p = write(tmp_path, text)
    with pytest.raises(UserError) as e:
        space.load(p)
    return p, str(e.value)
