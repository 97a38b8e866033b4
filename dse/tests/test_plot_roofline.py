"""dse.plots.roofline on a synthetic roofline.csv (the layout of rtaccel.cli.RooflineCmd)."""
import matplotlib.image
import numpy as np
import pytest

from dse.plots import roofline as plot_roofline

HEADER = ("tus,rays,cycles,rays_per_s,memory_bound,compute_bound,compute_bound_box,compute_bound_tri,roofline_fraction,"
          "binding,nearest_roof,dram_bytes_per_ray,box_jobs_per_ray,tri_jobs_per_ray,util_memory,util_iu,util_tu,"
          "stall_iu_arbitration,stall_memory_data,stall_memory_request,node_cache_miss_rate,prim_cache_miss_rate,ius,"
          "mem_channels,sim_build,wall_build_s,sim_cycles_per_wall_s,sim_cycles_per_cpu_s,sim_wall_s")


def row(tus, rate, binding, ius=1):
    return (f"{tus},70044,{int(70044 / rate * 150e6)},{rate},1272000,1573000,1840000,10830000,{rate / 1272000:.4f},{binding},"
            f"memory,471.6,20.37,6.92,{rate / 1272000:.4f},{rate / 1573000:.4f},0.95,0.4,0.36,0.0001,0.011,,{ius},1,o1,140,80000,160000,60")


def write(path, rows):
    path.write_text("# scene=/s/sponza_dabrovic.obj rays=70044 config=paper2017 clock_mhz=150.0 ius=1 mem_channels=1 rtaccel=test\n"
                    + HEADER + "\n" + "".join(r + "\n" for r in rows))


def test_sweep_png(tmp_path):
    csv = tmp_path / "roofline.csv"
    write(csv, [row(8, 3.1e5, "latency"), row(16, 6.0e5, "latency"), row(32, 9.96e5, "memory")])
    out = tmp_path / "roofline.png"
    plot_roofline.main(str(out), str(csv))
    img = matplotlib.image.imread(str(out))[..., :3].mean(axis=2)
    assert img.shape[0] > 300 and img.shape[1] > 800
    assert (img < 0.5).mean() > 0.01  # curves, labels and the footer were drawn, not a blank canvas


def test_one_configuration_png(tmp_path):
    csv = tmp_path / "roofline.csv"
    write(csv, [row(32, 9.96e5, "memory")])
    out = tmp_path / "one.png"
    plot_roofline.main(str(out), str(csv))
    assert matplotlib.image.imread(str(out)).shape[1] > 800


def test_no_rows_is_one_error(tmp_path):
    csv = tmp_path / "roofline.csv"
    write(csv, [])
    with pytest.raises(SystemExit, match="no data rows"):
        plot_roofline.main(str(tmp_path / "x.png"), str(csv))
    assert not (tmp_path / "x.png").exists()


def test_ius_grid_png(tmp_path):
    """ROOFLINE_IUS: one series per IU count, the same TU counts in each."""
    csv = tmp_path / "roofline.csv"
    write(csv, [row(t, r * k, "compute", ius=k) for k in (1, 2, 4) for t, r in ((8, 3e5), (16, 5e5), (32, 6e5))])
    out = tmp_path / "grid.png"
    plot_roofline.main(str(out), str(csv))
    img = matplotlib.image.imread(str(out))[..., :3].mean(axis=2)
    assert img.shape[1] > 800 and (img < 0.5).mean() > 0.01
