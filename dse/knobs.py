"""The knobs a space file may name: each Makefile variable, the rtaccel.cli flag it becomes, and its legal values.

One table, so that a space file, the JVM requests and the `make verilog ...` command of a result all spell a knob
the same way. The checks here are the ones a space file can be refused for up front; combinations the platform
refuses (e.g. MPPL over a preset's leaf count field) are refused by the JVM and recorded as failed points.
"""
import functools
import json
import os
import re
from dataclasses import dataclass

from scenes.procedural import NAMES as PROCEDURAL_SCENES  # noqa: F401  (re-exported for dse.space)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ("fit", "paper2017", "paper2017-lrp", "small")  # rtaccel.config.Presets.all plus CONFIG=fit
POLICIES = ("dm", "lru", "plru", "lrp", "bf", "hybrid")   # rtaccel.config.CachePolicy.parse
LEVEL_AWARE = ("lrp", "hybrid")  # CachePolicy.levelAware: the node refs carry the tree level (paper Section 7.2)


@functools.lru_cache(maxsize=None)
def boards(catalog=os.path.join(ROOT, "boards", "catalog.json")):
    """The board catalog, read once per process: knob checks and the Yosys rung's near-limit test ask it per point
    (read-only to every caller)."""
    with open(catalog) as f:
        return json.load(f)["boards"]


def _pow2(v):
    return isinstance(v, int) and v > 0 and v & (v - 1) == 0


@dataclass(frozen=True)
class Knob:
    flag: str
    rule: str          # what the error message says is allowed
    ok: object         # value -> bool
    cost: bool = True  # changes the circuit (so the area rung and `make verilog` see it)


def _int(lo, hi):
    return lambda v: isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi


def _one_of(names):
    return lambda v: v in names


def _box_format(v):
    # rtaccel.fp.FpFormat.parse and PlatformParams' rule: at most fp32's 8 exponent and 23 fraction bits;
    # m<M> = M fraction bits with the exponent fitted to the scene (config.BoxRange)
    m = re.fullmatch(r"e(\d+)m(\d+)", v) if isinstance(v, str) else None
    f = re.fullmatch(r"m(\d+)", v) if isinstance(v, str) else None
    return (v in ("fp32", "fp24", "bf16", "fp16") or (m is not None and 3 <= int(m[1]) <= 8 and 2 <= int(m[2]) <= 23)
            or (f is not None and 2 <= int(f[1]) <= 23))


def _tri_format(v):
    # config.Numerics.parseTriFormat: fp32 or wider, at most fp64's 11 exponent and 52 fraction bits
    m = re.fullmatch(r"e(\d+)m(\d+)", v) if isinstance(v, str) else None
    return v in ("fp32", "fp64") or (m is not None and 8 <= int(m[1]) <= 11 and 23 <= int(m[2]) <= 52)


def _cache(v):
    return v == 0 or (_pow2(v) and v <= 1 << 16)


KNOBS = {
    "CONFIG": Knob("--config", f"one of {', '.join(PRESETS)}", _one_of(PRESETS)),
    "TUS": Knob("--tus", "an integer 1..1024", _int(1, 1024)),
    # TUS must be a multiple of IUS: the JVM refuses a point that is not (recorded as failed)
    "IUS": Knob("--ius", "an integer 1..64 (intersection units; TUS must be a multiple)", _int(1, 64)),
    "MEM_CHANNELS": Knob("--mem-channels", "1, 2, 4, 8 or 16 (address-interleaved DRAM channels, MEM_GBPS each)",
                         lambda v: _int(1, 16)(v) and _pow2(v)),
    "RESP_ORDER": Knob("--resp-order", "request (one in-order stream, the paper's), path (node and primitive streams) "
                       "or tagged (the two streams, hits under misses)", _one_of(("request", "path", "tagged"))),
    "RAY_STORE": Knob("--ray-store", "0 (every request carries its ray, the paper's) or 1 (rays in each IU's ray store)", _one_of((0, 1))),
    "TAG_FORWARD": Knob("--tag-forward", "0 (cache tags take one lookup per two cycles) or 1 (one per cycle, forwarding the set just written)", _one_of((0, 1))),
    "NODE_BANKS": Knob("--node-banks", "0 (a node cache per IU) or a power of two 1..64 (one node cache shared by every IU, "
                       "in that many banks)", _one_of((0, 1, 2, 4, 8, 16, 32, 64))),
    "M": Knob("--m", "2, 4 or 8", _one_of((2, 4, 8))),
    "MPPL": Knob("--mppl", "an integer 1..16", _int(1, 16)),
    "STACK": Knob("--stack-depth", "an integer 1..4096", _int(1, 4096)),
    "SHORT_STACK": Knob("--short-stack", "an integer 1..64", _int(1, 64)),
    "BOX_FORMAT": Knob("--box-format", "fp32, fp24, bf16, fp16, e<E>m<M> with E <= 8, M <= 23, or m<M> (exponent fitted to the scene)", _box_format),
    "TRI_TEST": Knob("--tri-test", "mt or watertight", _one_of(("mt", "watertight"))),
    "TRI_FORMAT": Knob("--tri-format", "fp32, fp64 or e<E>m<M> with 8 <= E <= 11, 23 <= M <= 52 (Möller–Trumbore only)", _tri_format),
    "NODE_FORMAT": Knob("--node-format", "full, q2..q16 (quantized planes) or fit",
                        lambda v: isinstance(v, str) and re.fullmatch(r"full|fit|q([2-9]|1[0-6])", v) is not None),
    "PRIM_FORMAT": Knob("--prim-format", "slot64 or packed (40 B records, a beat-aligned row per leaf)", _one_of(("slot64", "packed"))),
    "NODE_CACHE": Knob("--node-cache", "0 or a power of two up to 65536", _cache),
    "NODE_WAYS": Knob("--node-ways", "a power of two 1..64", lambda v: _pow2(v) and v <= 64),
    "NODE_POLICY": Knob("--node-policy", f"one of {', '.join(POLICIES)}", _one_of(POLICIES)),
    "MAX_LEVEL": Knob("--max-level", "an integer 0..15", _int(0, 15)),
    "PRIM_CACHE": Knob("--prim-cache", "0 or a power of two up to 65536", _cache),
    "PRIM_WAYS": Knob("--prim-ways", "a power of two 1..64", lambda v: _pow2(v) and v <= 64),
    "PRIM_POLICY": Knob("--prim-policy", f"one of {', '.join(POLICIES)}", _one_of(POLICIES)),
    "BOARD": Knob("--board", "a board of boards/catalog.json", lambda v: isinstance(v, str) and v in boards()),
    "MEM_GBPS": Knob("--mem-gbps", "a number > 0", lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0, cost=False),
    # "fmax": each point at the clock measured for its own circuit (a cached make timing or make area; a point
    # without one is refused by the JVM with the command that makes one, and recorded as failed)
    "CLOCK_MHZ": Knob("--clock-mhz", 'a number > 0, or "fmax" (the clock measured for the point\'s circuit)',
                      lambda v: v == "fmax" or (isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0), cost=False),
}


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
