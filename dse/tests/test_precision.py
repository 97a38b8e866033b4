"""make precision through the real JVM (rtaccel.cli.Serve): every option on the same rays of a procedural scene,
the CSV's columns and provenance, conservative box formats losing no hit, and bad options refused. Needs `make deps`
and the fixtures (`make fixtures`)."""
import csv
import json
import os
import shlex
from pathlib import Path

import pytest

from dse.studies import precision
from dse.common import parse_provenance
from dse.explore.knobs import ROOT
from scenes.errors import UserError

CP_FILE = Path(os.environ.get("RTACCEL_CLASSPATH") or os.path.join(ROOT, "build", "classpath.txt"))
FIX = Path(os.environ.get("RTACCEL_FIXTURES", os.path.join(ROOT, "build", "fixtures")))
needs_jvm = pytest.mark.skipif(not CP_FILE.is_file(), reason="compiled model absent: run `make deps`")


def _java():
    return f"java -Xss64m -Xmx1g -cp {shlex.quote(CP_FILE.read_text().strip())}"


@needs_jvm
def test_precision_table_on_the_hairball(tmp_path, capsys):
    d = FIX / "hairball"
    if not (d / "golden" / "rays.npy").exists():
        pytest.skip("procedural fixtures absent: run `make fixtures`")
    out = tmp_path / "out"
    rc = precision.main(["--scene", "hairball", "--tris", str(d / "tris.npy"), "--golden", str(d / "golden"),
                         "--out", str(out), "--java", _java(), "--knobs", "--config fit --tus 4 --node-cache 256",
                         "--options", "bf16:mt e8m3:watertight fp32:mt:q4 fp32:mt:full:packed", "--exhaustive", "200", "--rtl", "0"])
    j = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert rc == 0 and j["failed"] == []
    # the fp32 Möller–Trumbore baseline is always measured, first
    assert j["options"] == ["fp32:mt", "bf16:mt", "e8m3:watertight", "fp32:mt:q4", "fp32:mt:full:packed"]
    lines = (out / "precision.csv").read_text().splitlines()
    prov = parse_provenance(lines[0])
    assert prov["scene"] == "hairball" and prov["tus"] == "4" and prov["node-cache"] == "256" and "rtaccel" in prov
    rows = {r["option"]: r for r in csv.DictReader(lines[1:])}
    assert list(rows) == j["options"] and set(precision.COLUMNS) == set(rows["fp32:mt"])
    base, bf, e3, q4, pk = (rows[o] for o in j["options"])
    assert int(base["differ_from_baseline"]) == 0 and base["differ_classes"] == "" and float(base["max_rel_t_vs_baseline"]) == 0
    assert int(e3["prim_differs_from_baseline"]) <= int(e3["differ_from_baseline"])
    # conservative boxes (and the watertight slack) lose nothing; looser boxes cost more work
    assert int(bf["lost_hits"]) == 0 and int(e3["lost_hits"]) == 0 and int(bf["exhaustive_rays"]) == 200
    # 4-bit quantized nodes: looser boxes (more work), half the bytes per node fetch, nothing lost; built in the RTL
    assert int(q4["lost_hits"]) == 0 and q4["node_format"] == "q4" and q4["note"] == "" and pk["note"] == ""
    assert float(q4["node_fetches_per_ray"]) >= float(base["node_fetches_per_ray"])
    # (the CSV keeps 6 significant digits)
    assert float(q4["node_bytes_per_ray_nocache"]) / float(q4["node_fetches_per_ray"]) == pytest.approx(64, rel=1e-4)
    assert float(base["node_bytes_per_ray_nocache"]) / float(base["node_fetches_per_ray"]) == pytest.approx(128, rel=1e-4)
    # packed leaves: the same work and hits, fewer primitive bytes (40 B records, beat-aligned per leaf)
    assert pk["prim_format"] == "packed" and int(pk["differ_from_baseline"]) == 0
    assert pk["prim_tests_per_ray"] == base["prim_tests_per_ray"]
    assert 40 / 64 <= float(pk["prim_bytes_per_ray_nocache"]) / float(base["prim_bytes_per_ray_nocache"]) < 1
    assert float(e3["node_fetches_per_ray"]) > float(bf["node_fetches_per_ray"]) >= float(base["node_fetches_per_ray"])
    assert float(e3["prim_bytes_per_ray"]) > float(base["prim_bytes_per_ray"])
    # with a node cache its bytes are below the uncached ones; no RTL run, no synthesis: empty, not invented
    assert float(base["node_bytes_per_ray"]) < float(base["node_bytes_per_ray_nocache"]) and float(base["node_miss_rate"]) < 1
    assert all(rows[o][k] == "" for o in rows for k in ("rtl_rays_per_s", "iu_lut", "iu_dsp"))
    assert int(base["rays"]) * 0.9 <= int(base["agree"]) <= int(base["rays"])
    assert int(base["unexplained"]) == 0 and int(bf["unexplained"]) == 0
    assert (out / "precision.png").stat().st_size > 0


def test_a_triangle_format_rides_on_the_triangle_test():
    assert precision.parse_options("fp32:mt@fp64 bf16:mt:q8") == [("fp32", "mt@fp64", "full", "slot64"), ("bf16", "mt", "q8", "slot64")]
    assert precision.name_of("fp32", "mt@e8m31", "full", "slot64") == "fp32:mt@e8m31"


@pytest.mark.parametrize("bad", ["fp32", "fp32:xx", ":mt", "", "fp32:mt:", "a:mt:q8:slot64:x", "fp32:mt@", "fp32:xx@fp64"])
def test_bad_options_are_refused_with_the_format(bad):
    with pytest.raises(UserError, match="BOX_FORMAT:TRI_TEST|empty"):
        precision.parse_options(bad)


@needs_jvm
def test_a_box_format_the_model_refuses_is_one_clear_error(tmp_path):
    d = FIX / "cornell"
    if not (d / "golden" / "rays.npy").exists():
        pytest.skip("procedural fixtures absent: run `make fixtures`")
    with pytest.raises(UserError, match="e9m4"):
        precision.main(["--scene", "cornell", "--tris", str(d / "tris.npy"), "--golden", str(d / "golden"),
                        "--out", str(tmp_path / "o"), "--java", _java(), "--options", "e9m4:mt", "--rtl", "0"])
    assert not (tmp_path / "o" / "precision.csv").exists()


def test_synthesis_knobs_take_the_board_once_and_a_preset_for_fit():
    knobs = ["--config", "fit", "--tus", "32", "--board", "xc5vlx330t", "--node-cache", "8192"]
    assert precision.synthesis_knobs(knobs) == ["--config", "paper2017", "--tus", "32", "--node-cache", "8192"]
    assert precision.synthesis_knobs(["--config", "small"]) == ["--config", "small"]
