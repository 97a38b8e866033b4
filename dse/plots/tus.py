"""python -m dse.plots.tus OUT CSV [CSV ...] — paper Figs 12-13: rays/s and memory utilisation vs TUs.

Each CSV is a `tus_sweep.csv` of one scene (rtaccel.cli.SweepTus); its `#` provenance line labels the curve
with the scene and its node cache (`node_cache=`), so cached (make paper-caches) and uncached (make
paper-nocache) sweeps of one scene can share a plot: one colour per scene, solid with a cache, dashed without.
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dse.common import parse_provenance, save_with_footer, tus_axes  # noqa: E402


def read(path):
    lines = Path(path).read_text().splitlines()
    prov = [l[1:].strip() for l in lines if l.startswith("#")]
    rows = [l for l in lines if l and not l.startswith("#")]
    data = np.genfromtxt(rows, delimiter=",", names=True)
    kv = parse_provenance(prov[0]) if prov else {}
    return Path(kv.get("scene", path)).stem, data, prov, kv.get("node_cache", "none")


def main(out, *csvs):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    footer, colours = [], {}
    for c in csvs:
        name, d, prov, cache = read(c)
        colour = colours.setdefault(name, f"C{len(colours)}")
        style = "o--" if cache == "none" else "o-"
        label = f"{name} ({'no cache' if cache == 'none' else cache + ' node cache'})"
        a1.plot(d["tus"], d["rays_per_s"], style, color=colour, label=label)
        a2.plot(d["tus"], 100 * d["mem_utilisation"], style, color=colour, label=label)
        footer += prov
    for ax, title, yl in ((a1, "rays/s at 150 MHz", "rays/s"), (a2, "memory utilisation (of peak)", "%")):
        ax.set_ylabel(yl)
        ax.set_title(title)
    tus_axes((a1, a2))
    save_with_footer(fig, out, footer)
    plt.close(fig)
    print(f"[plot] {out}")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        raise SystemExit("error: usage: python -m dse.plots.tus OUT.png CSV [CSV ...]")
    main(*sys.argv[1:])
