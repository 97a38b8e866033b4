"""make dse through the real JVM (rtaccel.cli.Serve on build/classpath.txt) and local Ray with 2 workers: the
server's protocol, the cache model's JSON and the store must agree with each other. Needs `make deps`."""
import json
import os
import shlex
import sqlite3
from pathlib import Path

import pytest

from dse.explore import explore, store
from dse.explore.knobs import ROOT

from . import spaces

CP_FILE = Path(os.environ.get("RTACCEL_CLASSPATH") or os.path.join(ROOT, "build", "classpath.txt"))
needs_jvm = pytest.mark.skipif(not CP_FILE.is_file(), reason="compiled model absent: run `make deps`")


@needs_jvm
def test_real_jvm_sweep_with_a_refused_point(tmp_path, capsys, local_ray):
    java = f"java -Xss64m -Xmx1g -cp {shlex.quote(CP_FILE.read_text().strip())}"
    # LRP needs a level field in the node refs: CONFIG=small has none, so the JVM refuses those points (status 2)
    sp = spaces.tiny(tmp_path, axes='TUS = [1, 4]\nNODE_CACHE = [0, 256]\nNODE_POLICY = ["dm", "lrp"]',
                     extra='[objectives]\nmaximize = ["rays_per_s", "rays_per_dram_byte"]\nminimize = ["bram36"]\n')
    out = tmp_path / "out"
    rc = explore.main(["--space", str(sp), "--out", str(out), "--workers", "2", "--java", java, "--version", "real-t"])
    j = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert rc == 0 and j["points"] == 8
    with sqlite3.connect(out / "store.sqlite") as db:
        rows = [(f, s, json.loads(c), e, json.loads(r) if r else None) for f, s, c, e, r in
                db.execute("SELECT fidelity, status, config, error, result FROM runs")]
    cs = [r for r in rows if r[0] == "cachesim"]
    refused = [r for r in cs if r[1] == store.REFUSED]
    # NODE_CACHE=0 with lrp has no cache to need levels; the two cached lrp points are refused
    assert {(c["TUS"], c["NODE_CACHE"]) for _, _, c, _, _ in refused} == {(1, 256), (4, 256)}
    assert all(c["NODE_POLICY"] == "lrp" and "level" in e for _, _, c, e, _ in refused)
    ok = [r for r in cs if r[1] == store.OK]
    assert len(ok) == 6 and all(r[4]["rays"] == 8 * 6 for r in ok)
    # the cost rung: refused by a build without FIDELITY=model (recorded, not failed), or answered by one with it
    area = [r for r in rows if r[0] == "area"]
    assert len(area) == 8 and all(s in (store.SKIPPED, store.OK, "infeasible", store.REFUSED) for _, s, _, _, _ in area)
    assert j["failed"] == len(refused) + sum(s == store.REFUSED for _, s, _, _, _ in area)
    # a bigger node cache never needs more DRAM bytes per ray on the same rays
    by = {(r[2]["TUS"], r[2]["NODE_CACHE"], r[2]["NODE_POLICY"]): r[4] for r in ok}
    assert by[(1, 256, "dm")]["dram_bytes_per_ray"] < by[(1, 0, "dm")]["dram_bytes_per_ray"]
    assert j["pareto"] and all(p["config"]["NODE_POLICY"] == "dm" or p["config"]["NODE_CACHE"] == 0 for p in j["pareto"])
