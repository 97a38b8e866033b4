"""Small space files for the dse tests, written from text so each test shows its whole space."""
import textwrap

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
