"""Space files (dse/spaces/<name>.toml): what `make dse` explores, read with tomllib and checked before any run.

    [space]        name (default: the file name), description, base = {KNOB = value, ...} held fixed
    [[scenes]]     procedural = "<cornell|hairball|soup|extreme>" or mesh = "<path>", and either
                   rays = "<rays.npy>" or a golden frame width/height/depth/seed (defaults 32, 24, 1, 1)
    [axes]         KNOB = [values, ...]          (dse.explore.knobs.KNOBS: the Makefile's variables)
    [constraints]  fits = "<board>" | "BOARD" (each point's own BOARD), max_bram36, max_lut, max_dsp, max_ff
    [objectives]   maximize = [...], minimize = [...]   (OBJECTIVES below)
    [strategy]     kind = "grid" | "random" | "optuna"; n (random), budget + sampler "nsga2"|"tpe" (optuna), seed
    [fidelity]     area = true|false (the cost model rung), rtl = true|false (confirm the predicted front),
                   margin = extra points beyond the front to confirm, max_rtl = cap on confirmed points,
                   yosys_margin = fraction (0 < f <= 1): synthesize with Yosys the points the sweep would confirm
                   and each board's best whose model cost is within f of a limit (default: off)

Any problem is one UserError naming the file and line and what to change (exit 2, nothing written).
"""
import os
import re
import tomllib
from dataclasses import dataclass, field

from scenes.errors import UserError

from .knobs import KNOBS, PROCEDURAL_SCENES, ROOT, boards

OBJECTIVES = {  # name -> direction it may be optimised in, and the rung that measures it
    "rays_per_s": ("max", "cachesim"), "rays_per_dram_byte": ("max", "cachesim"),
    "lut": ("min", "area"), "dsp": ("min", "area"), "bram36": ("min", "area"), "ff": ("min", "area"),
}
LIMITS = {"max_bram36": "bram36", "max_lut": "lut", "max_dsp": "dsp", "max_ff": "ff"}
KEYS = {
    "space": {"name", "description", "base"},
    "scenes": {"procedural", "mesh", "rays", "width", "height", "depth", "seed"},
    "axes": None, "constraints": {"fits", *LIMITS}, "objectives": {"maximize", "minimize"},
    "strategy": {"kind", "n", "budget", "sampler", "seed"},
    "fidelity": {"area", "rtl", "margin", "max_rtl", "yosys_margin"},
}


@dataclass(frozen=True)
class Scene:
    name: str
    mesh: str            # absolute path; procedural ones are made in build/scenes/ by dse.explore.explore
    procedural: str = ""
    rays: str = ""       # a rays file, or "" for the golden frame below
    width: int = 32
    height: int = 24
    depth: int = 1
    seed: int = 1


@dataclass
class Space:
    path: str
    name: str
    description: str
    base: dict
    scenes: list
    axes: dict
    constraints: dict
    maximize: list
    minimize: list
    strategy: dict
    fidelity: dict = field(default_factory=dict)

    @property
    def objectives(self):
        return [(o, "max") for o in self.maximize] + [(o, "min") for o in self.minimize]

    def needs_area(self):
        return bool(self.fidelity["area"])


class _Lines:
    """Line numbers of tables and keys in the TOML text (tomllib gives none for values it accepted)."""

    def __init__(self, text):
        self.lines = text.splitlines()

    def of(self, table, key=None, index=0):
        seen, start = -1, None
        for i, line in enumerate(self.lines):
            m = re.match(r"\s*\[\[?\s*([A-Za-z0-9_.-]+)\s*\]\]?", line)
            if m:
                if start is not None:
                    break
                if m.group(1) == table:
                    seen += 1
                    if seen == index:
                        start = i
                        if key is None:
                            return i + 1
            elif start is not None and key is not None and re.match(rf"\s*\"?{re.escape(key)}\"?\s*=", line):
                return i + 1
        return (start + 1) if start is not None else 1


def load(path):
    """The Space of a file, or one UserError `<file>:<line>: <what is wrong>; <what to change>`."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise UserError(f"space file {path}: {e.strerror}; give SPACE=<path to a .toml file>")
    text = raw.decode("utf-8", errors="replace")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"at line (\d+)", str(e))
        raise UserError(f"{path}:{m.group(1) if m else 1}: not valid TOML ({e})")
    lines = _Lines(text)

    def bad(table, key, msg, index=0):
        raise UserError(f"{path}:{lines.of(table, key, index)}: {msg}")

    for t in doc:
        if t not in KEYS:
            bad(t, None, f"unknown table [{t}]; the tables are {', '.join(f'[{k}]' for k in KEYS)}")
    for t, allowed in KEYS.items():
        entries = doc.get(t, [] if t == "scenes" else {})
        if t == "scenes" and not isinstance(entries, list):
            bad(t, None, "scenes are [[scenes]] tables (one per scene)")
        for i, e in enumerate(entries if t == "scenes" else [entries]):
            if not isinstance(e, dict):
                bad(t, None, f"[{t}] must be a table")
            for k in e:
                if allowed is not None and k not in allowed:
                    bad(t, k, f"unknown key '{k}' in [{t}]; allowed: {', '.join(sorted(allowed))}", i)

    def knob_value(table, k, v, index=0, where=None):
        if k not in KNOBS:
            bad(table, k, f"unknown knob '{k}'; knobs are {', '.join(KNOBS)}", index)
        if not KNOBS[k].ok(v):
            bad(table, where or k, f"{k} = {v!r} is not allowed; {k} must be {KNOBS[k].rule}", index)

    sp = doc.get("space", {})
    base = sp.get("base", {})
    if not isinstance(base, dict):
        bad("space", "base", "base must be an inline table {KNOB = value, ...}")
    for k, v in base.items():
        knob_value("space", k, v, where="base")

    axes = doc.get("axes", {})
    if not axes:
        bad("axes", None, "a space needs at least one axis under [axes], e.g. TUS = [1, 4]")
    for k, vs in axes.items():
        if k not in KNOBS:
            bad("axes", k, f"unknown knob '{k}'; knobs are {', '.join(KNOBS)}")
        if not isinstance(vs, list) or not vs:
            bad("axes", k, f"axis {k} is empty or not a list; give at least one value, e.g. {k} = [..]")
        if len(set(map(repr, vs))) != len(vs):
            bad("axes", k, f"axis {k} lists a value twice")
        if k in base:
            bad("axes", k, f"{k} is both an axis and in [space] base; keep one")
        for v in vs:
            knob_value("axes", k, v)

    scenes = []
    if not doc.get("scenes"):
        bad("scenes", None, "a space needs at least one [[scenes]] table (procedural = \"cornell\" or mesh = \"<path>\")")
    for i, s in enumerate(doc["scenes"]):
        if ("procedural" in s) == ("mesh" in s):
            bad("scenes", None, "give exactly one of procedural = \"<name>\" or mesh = \"<path>\"", i)
        for k in ("width", "height", "depth", "seed"):
            v = s.get(k, 1)
            if not isinstance(v, int) or isinstance(v, bool) or v < (0 if k in ("depth", "seed") else 1):
                bad("scenes", k, f"{k} must be an integer >= {0 if k in ('depth', 'seed') else 1} (got {v!r})", i)
        if "procedural" in s:
            name = s["procedural"]
            if name not in PROCEDURAL_SCENES:
                bad("scenes", "procedural", f"unknown procedural scene '{name}'; choose one of {', '.join(PROCEDURAL_SCENES)}", i)
            mesh = os.path.join(ROOT, "build", "scenes", f"{name}.obj")
        else:
            mesh = _resolve(path, s["mesh"])
            if not os.path.isfile(mesh):
                bad("scenes", "mesh", f"mesh {mesh} not found; give an existing .obj or .ply", i)
            name = os.path.splitext(os.path.basename(mesh))[0]
        rays = ""
        if "rays" in s:
            rays = _resolve(path, s["rays"])
            if not os.path.isfile(rays):
                bad("scenes", "rays", f"rays file {rays} not found; give a rays.npy or a golden frame (width/height)", i)
        scenes.append(Scene(name, mesh, s.get("procedural", ""), rays, s.get("width", 32), s.get("height", 24),
                            s.get("depth", 1), s.get("seed", 1)))
    if len({s.name for s in scenes}) != len(scenes):
        bad("scenes", None, "two [[scenes]] have the same name; each scene once")

    cons = doc.get("constraints", {})
    if "fits" in cons:
        f = cons["fits"]
        if f != "BOARD" and f not in boards():
            bad("constraints", "fits", f"fits = {f!r}: not a board of boards/catalog.json ({', '.join(boards())}) nor \"BOARD\"")
        if f == "BOARD" and "BOARD" not in axes and "BOARD" not in base:
            bad("constraints", "fits", "fits = \"BOARD\" needs BOARD as an axis or in [space] base")
    for k in LIMITS:
        if k in cons and (not isinstance(cons[k], (int, float)) or isinstance(cons[k], bool) or cons[k] <= 0):
            bad("constraints", k, f"{k} must be a number > 0 (got {cons[k]!r})")

    obj = doc.get("objectives", {"maximize": ["rays_per_s"]})
    maxi, mini = obj.get("maximize", []), obj.get("minimize", [])
    for key, names, d in (("maximize", maxi, "max"), ("minimize", mini, "min")):
        if not isinstance(names, list):
            bad("objectives", key, f"{key} must be a list of objective names")
        for o in names:
            if o not in OBJECTIVES:
                bad("objectives", key, f"unknown objective '{o}'; objectives are {', '.join(OBJECTIVES)}")
            if OBJECTIVES[o][0] != d:
                bad("objectives", key, f"{o} can only be {OBJECTIVES[o][0]}imized")
    if not maxi + mini:
        bad("objectives", None, "give at least one objective, e.g. maximize = [\"rays_per_s\"]")
    if len(set(maxi + mini)) != len(maxi + mini):
        bad("objectives", None, "an objective is listed twice")

    st = {"kind": "grid", "seed": 1, **doc.get("strategy", {})}
    if st["kind"] not in ("grid", "random", "optuna"):
        bad("strategy", "kind", f"kind = {st['kind']!r}; choose grid, random or optuna")
    for k in ("n", "budget", "seed"):
        if k in st and (not isinstance(st[k], int) or isinstance(st[k], bool) or st[k] < (0 if k == "seed" else 1)):
            bad("strategy", k, f"{k} must be a positive integer (got {st[k]!r})")
    if st["kind"] == "random" and "n" not in st:
        bad("strategy", "kind", "kind = \"random\" needs n = <points to draw>")
    if st["kind"] == "optuna":
        st.setdefault("sampler", "nsga2")
        if "budget" not in st:
            bad("strategy", "kind", "kind = \"optuna\" needs budget = <trials>")
        if st["sampler"] not in ("nsga2", "tpe"):
            bad("strategy", "sampler", f"sampler = {st['sampler']!r}; choose nsga2 or tpe")
    elif "sampler" in st or "budget" in st:
        bad("strategy", "sampler" if "sampler" in st else "budget", "sampler and budget belong to kind = \"optuna\"")

    fid = {"area": any(OBJECTIVES[o][1] == "area" for o in maxi + mini) or bool(cons), "rtl": False,
           "margin": 0, "max_rtl": 8, "yosys_margin": None, **doc.get("fidelity", {})}
    for k in ("area", "rtl"):
        if not isinstance(fid[k], bool):
            bad("fidelity", k, f"{k} must be true or false")
    for k in ("margin", "max_rtl"):
        if not isinstance(fid[k], int) or isinstance(fid[k], bool) or fid[k] < 0:
            bad("fidelity", k, f"{k} must be an integer >= 0")
    if not fid["area"] and (cons or any(OBJECTIVES[o][1] == "area" for o in maxi + mini)):
        bad("fidelity", "area", "the constraints or objectives need the cost rung; set area = true")
    ym = fid["yosys_margin"]
    if ym is not None:
        if not isinstance(ym, (int, float)) or isinstance(ym, bool) or not 0 < ym <= 1:
            bad("fidelity", "yosys_margin", f"yosys_margin = {ym!r}: give a fraction of the limit, 0 < yosys_margin <= 1 "
                "(e.g. 0.1: synthesize points whose model cost is within 10 % of a limit), or leave it out")
        if not fid["area"]:
            bad("fidelity", "yosys_margin", "yosys_margin compares the cost model with its limits; set area = true")

    name = sp.get("name", os.path.splitext(os.path.basename(path))[0])
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        bad("space", "name", "name must be letters, digits, '.', '_' or '-'")
    return Space(os.path.abspath(path), name, str(sp.get("description", "")), dict(base), scenes, dict(axes), dict(cons),
                 list(maxi), list(mini), st, fid)


def _resolve(space_path, p):
    """A path in a space file: absolute, or relative to the project root (where make runs)."""
    return p if os.path.isabs(p) else os.path.join(ROOT, p)
