"""dse.paper.caches through the real JVM (rtaccel.cli.CacheSim), not the fake one: the driver, the entry point's
flags and JSON, and the plots must agree with each other. Needs RTACCEL_CLASSPATH and the fixtures (make test)."""
import csv
import os
import shlex
from pathlib import Path

import pytest

from scenes.tests.helpers import run_cli

CP_FILE = os.environ.get("RTACCEL_CLASSPATH", "")
FIX = Path(os.environ.get("RTACCEL_FIXTURES", "build/fixtures"))
needs_jvm = pytest.mark.skipif(not (CP_FILE and Path(CP_FILE).is_file()),
                               reason="compiled model absent: run through `make test` (sets RTACCEL_CLASSPATH)")


def rows(path):
    with open(path) as f:
        return [r for r in csv.DictReader(l for l in f if not l.startswith("#"))]


@needs_jvm
def test_paper_caches_with_the_real_cache_model(tmp_path):
    d = FIX / "cornell"
    if not (d / "golden" / "rays.npy").exists():
        pytest.skip("procedural fixtures absent: run `make fixtures`")
    java = f"java -Xss64m -Xmx4g -cp {shlex.quote(Path(CP_FILE).read_text().strip())}"
    out = tmp_path / "out"
    r = run_cli("dse.paper.caches", "--scene", str(d / "scene.obj"), "--tris", str(d / "tris.npy"),
                "--rays", str(d / "golden" / "rays.npy"), "--out", str(out), "--java", java, "--mppl-list", "1,4")
    assert r.returncode == 0, r.stderr
    fig11 = rows(out / "fig11_miss_rate.csv")
    dm = next(x for x in fig11 if x["config"] == "dm")
    rates = [float(dm[k]) for k in ("256", "512", "1024", "2048", "4096", "8192")]
    # a bigger direct-mapped cache never misses more on the same stream, and all rates are rates
    assert all(0 <= a <= 1 for a in rates) and all(b <= a + 1e-12 for a, b in zip(rates, rates[1:])), rates
    by = {(x["mppl"], x["variant"]): x for x in rows(out / "fig8_9_bytes_per_ray.csv")}
    for mppl in ("1", "4"):
        nocache, node = float(by[mppl, "nocache"]["node_bytes_per_ray"]), float(by[mppl, "node"]["node_bytes_per_ray"])
        assert 0 < node < nocache, (mppl, node, nocache)  # the embedded room fits the 8192-entry node cache
    for png in ("fig11_miss_rate.png", "fig8_9_bytes_per_ray.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
