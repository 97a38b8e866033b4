"""The knobs a space file may name: each Makefile variable, the rtaccel.cli flag it becomes, and its legal values.

Read from the knob registry's export (config/knobs.json, `make knobs`, rtaccel.config.Knobs): a space file, the JVM
requests and the `make verilog ...` command of a result spell a knob as the registry does, and a value is judged
by the registry's rule (its domain, as data, interpreted here). Combinations the platform refuses (e.g. MPPL over a
preset's leaf count field) are refused by the JVM and recorded as failed points.
"""
import functools
import json
import os
import re
from dataclasses import dataclass

from scenes.procedural import NAMES as PROCEDURAL_SCENES  # noqa: F401  (re-exported for dse.explore.space)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # dse/explore/ -> the project
EXPORT = os.path.join(ROOT, "config", "knobs.json")


@functools.lru_cache(maxsize=None)
def boards(catalog=os.path.join(ROOT, "boards", "catalog.json")):
    """The board catalog, read once per process: knob checks and the Yosys rung's near-limit test ask it per point
    (read-only to every caller)."""
    with open(catalog) as f:
        return json.load(f)["boards"]


def accepts(domain, value):
    """Whether the registry's domain (config.Knobs.Domain as exported) takes `value` (as its string, names in any case)."""
    if isinstance(value, bool):
        return False
    v = str(value).lower()
    kind = domain["kind"]
    if kind == "ints":
        if not re.fullmatch(r"-?\d+", v):
            return False
        n = int(v)
        return (domain["zero"] and n == 0) or (domain["lo"] <= n <= domain["hi"] and (not domain["pow2"] or n & (n - 1) == 0))
    if kind == "names":
        return v in domain["names"]
    if kind == "positive":
        try:
            d = float(v)
        except ValueError:
            return False
        return 0 < d < float("inf")
    if kind == "template":
        m = re.fullmatch("".join(f"{p['letter']}(\\d+)" for p in domain["parts"]), v)
        return m is not None and all(len(n) <= 4 and p["lo"] <= int(n) <= p["hi"] for n, p in zip(m.groups(), domain["parts"]))
    if kind == "any_of":
        return any(accepts(d, value) for d in domain["of"])
    if kind == "board":
        return v in boards()
    if kind == "file":
        return bool(v)
    raise ValueError(f"config/knobs.json: unknown domain kind '{kind}'; run make knobs")


@dataclass(frozen=True)
class Knob:
    flag: str
    rule: str          # what the error message says is allowed
    domain: dict       # the registry's domain
    cost: bool = True  # changes the circuit (so the area rung and `make verilog` see it)

    def ok(self, value):
        return accepts(self.domain, value)


def _load():
    with open(EXPORT) as f:
        export = json.load(f)
    knobs = {k["make"]: Knob(k["flag"], k["rule"], k["domain"], k["shapes_circuit"]) for k in export["knobs"]}
    return knobs, tuple(export["level_aware_policies"])


KNOBS, LEVEL_AWARE = _load()
PRESETS = tuple(KNOBS["CONFIG"].domain["names"])
POLICIES = tuple(KNOBS["NODE_POLICY"].domain["names"])


def flags(config):
    """rtaccel.cli flags of a configuration {KNOB: value} (knobs in table order, so the args are canonical)."""
    out = []
    for k, knob in KNOBS.items():
        if k in config:
            out += [knob.flag, str(config[k])]
    return out


def verilog_command(config):
    """The exact `make verilog ...` that builds this configuration (only the knobs that change the circuit)."""
    return "make verilog " + " ".join(f"{k}={config[k]}" for k in KNOBS if k in config and KNOBS[k].cost)
