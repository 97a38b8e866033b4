import os

from scenes.tests.helpers import run_cli

BW = """# scene: synthetic.obj sha256 0000
# config: mppl sweep; rtaccel 0.1.0
mppl,rays,nodes,leaves,depth,node_accesses,leaf_accesses,prim_accesses,node_bytes_per_ray,prim_bytes_per_ray,total_bytes_per_ray
1,100,50,40,9,900,300,300,1152,192,1344
2,100,30,20,8,800,200,350,1024,224,1248
4,100,20,10,7,700,150,450,896,288,1184
"""
LV = """# scene: synthetic.obj
level,nodes,accesses,accesses_per_node,cum_node_share,cum_access_share
0,1,100,100,0.05,0.4
1,4,100,25,0.25,0.8
2,15,50,3.3,1.0,1.0
"""


def test_plots_written(tmp_path):
    (tmp_path / "bandwidth_vs_mppl.csv").write_text(BW)
    (tmp_path / "levels.csv").write_text(LV)
    r = run_cli("dse.plots.analysis", str(tmp_path))
    assert r.returncode == 0, r.stderr
    for name in ("bandwidth_vs_mppl.png", "levels.png"):
        data = (tmp_path / name).read_bytes()
        assert len(data) > 5000 and data[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_csv_writes_nothing(tmp_path):
    (tmp_path / "bandwidth_vs_mppl.csv").write_text(BW.replace("prim_bytes_per_ray,", ""))
    (tmp_path / "levels.csv").write_text(LV)
    for d in (tmp_path, tmp_path / "missing"):
        r = run_cli("dse.plots.analysis", str(d))
        assert r.returncode == 2
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: ")
    assert sorted(os.listdir(tmp_path)) == ["bandwidth_vs_mppl.csv", "levels.csv"]
