"""The Makefile's knobs are the registry's export (config/knobs.json): every knob reaches the commands that read it
with its flag, a knob given to a command that does not read it is refused, and dse/ judges values by the same rule."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXPORT = json.loads((ROOT / "config/knobs.json").read_text())["knobs"]


def legal(domain):
    """One value the domain takes, built from the domain alone."""
    kind = domain["kind"]
    if kind == "ints":
        return str(domain["lo"])
    if kind == "names":
        return domain["names"][-1]
    if kind == "positive":
        return "1.5"
    if kind == "template":
        return "".join(f"{p['letter']}{p['hi']}" for p in domain["parts"])
    if kind == "any_of":
        return legal(domain["of"][-1])
    return {"board": "ecp5-85", "file": "boards/catalog.json"}[kind]


# as a user's make, not a sub-make of `make test` (whose MAKELEVEL and MAKEFLAGS would reach it)
TOP = {k: v for k, v in os.environ.items() if k not in ("MAKELEVEL", "MAKEFLAGS", "MFLAGS")}


def make(*args):
    return subprocess.run(["make", "-n", "--no-print-directory", *args], capture_output=True, text=True, cwd=ROOT, env=TOP)


def test_every_knob_a_command_reads_reaches_it_with_its_flag():
    given = {k["make"]: legal(k["domain"]) for k in EXPORT if "verilog" in k["commands"]}
    given["CLOCK_MHZ"] = "125"
    r = make("verilog", *(f"{k}={v}" for k, v in given.items()))
    assert r.returncode == 0, r.stderr
    line = next(l for l in r.stdout.splitlines() if "rtaccel.cli.EmitVerilog" in l)
    args = line.split()
    for k in EXPORT:
        if k["make"] in given and k["make"] != "CONFIG":  # CONFIG becomes the preset the circuit commands build
            i = args.index(k["flag"])
            assert args[i + 1] == given[k["make"]], (k["make"], line)


@pytest.mark.parametrize("knob", [k for k in EXPORT if "trace" not in k["commands"]], ids=lambda k: k["make"])
def test_a_knob_given_to_a_command_that_does_not_read_it_is_refused(knob):
    r = make("trace", "SCENE=x", f"{knob['make']}={legal(knob['domain'])}")
    assert r.returncode == 2 and f"{knob['make']}={legal(knob['domain'])} has no effect on make trace" in r.stderr, r.stderr
    assert r.stdout == ""


def test_the_entry_point_gives_the_same_refusal_with_status_2():
    r = subprocess.run([sys.executable, str(ROOT / "rtaccel"), "trace", "SCENE=x", "NODE_CACHE=64"], capture_output=True,
                       text=True, cwd=ROOT, env=TOP)
    assert r.returncode == 2 and "NODE_CACHE=64 has no effect on make trace" in r.stderr, r.stderr


def test_dse_knobs_are_the_export_and_judge_by_its_domains():
    from dse.explore import knobs
    assert list(knobs.KNOBS) == [k["make"] for k in EXPORT]
    for k in EXPORT:
        dk = knobs.KNOBS[k["make"]]
        assert (dk.flag, dk.rule, dk.cost) == (k["flag"], k["rule"], k["shapes_circuit"])
        if k["domain"]["kind"] != "file":
            assert dk.ok(legal(k["domain"])) and not dk.ok("not-a-value")
    # the drifts a restated rule had: SHORT_STACK 0 is the full stack; NODE_CACHE is not capped at 65536
    assert knobs.KNOBS["SHORT_STACK"].ok(0) and knobs.KNOBS["NODE_CACHE"].ok(1 << 17)
    assert not knobs.KNOBS["NODE_CACHE"].ok(48) and not knobs.KNOBS["BOX_FORMAT"].ok("e9m4") and knobs.KNOBS["BOX_FORMAT"].ok("m10")
