"""python -m dse.plots.roofline OUT.png CSV — make roofline: achieved rays/s against the memory and compute bounds.

CSV is the `roofline.csv` of rtaccel.cli.RooflineCmd (one row per TU count and IU count; a series per IUS). Left: rays/s of the RTL and the
bounds (memory; compute with boxes and triangles alone) over the TUs; right: utilisation of memory, IU and TUs
and the stall shares that say which bound binds (docs/roofline.md). The CSV's provenance line is the footer.
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dse.common import parse_provenance, save_with_footer, tus_axes  # noqa: E402

BOUNDS = (("memory_bound", "memory bound", "C3", "-"), ("compute_bound", "compute bound (IU)", "C2", "-"),
          ("compute_bound_box", "IU, boxes alone", "C2", ":"), ("compute_bound_tri", "IU, triangles alone", "C2", "--"))
SHARES = (("util_memory", "memory (of sustained)", "C3", "o-"), ("util_iu", "IU beat port", "C2", "o-"),
          ("util_tu", "TUs busy", "C0", "o-"), ("stall_iu_arbitration", "TU-cycles waiting for the IU", "C0", "x--"),
          ("stall_memory_data", "IU cycles waiting for data", "C3", "x--"),
          ("stall_memory_request", "cycles DRAM refused a read", "C1", "x:"))


def read(path):
    lines = Path(path).read_text().splitlines()
    prov = [ln[1:].strip() for ln in lines if ln.startswith("#")]
    rows = [ln for ln in lines if ln and not ln.startswith("#")]
    if len(rows) < 2:
        raise SystemExit(f"error: {path} has no data rows; rerun make roofline")
    data = np.genfromtxt(rows, delimiter=",", names=True, dtype=None, encoding="utf-8")
    return np.atleast_1d(data), prov


def main(out, csv):
    d, prov = read(csv)
    kv = parse_provenance(prov[0]) if prov else {}
    tus = d["tus"].astype(float)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11.5, 4.4))
    # one series per IU count (ROOFLINE_IUS): the bounds and the achieved rays/s of each
    ius = d["ius"].astype(int)
    groups = sorted(set(ius.tolist()))
    markers = "osD^v<>"
    for gi, k in enumerate(groups):
        sel = ius == k
        t = tus[sel]
        tag = f", IUS={k}" if len(groups) > 1 else ""
        for key, label, colour, style in BOUNDS:
            if len(groups) > 1 and key in ("compute_bound_box", "compute_bound_tri"):
                continue  # the per-kind IU bounds only on a single-IUS plot, which stays readable
            v = np.array([np.nan if str(x) == "" else float(x) for x in d[key][sel]])
            a1.plot(t, v, style, color=colour, alpha=1.0 - 0.6 * gi / max(1, len(groups) - 1) if len(groups) > 1 else 1.0,
                    label=label + tag, marker="." if len(t) == 1 else None)
        a1.plot(t, d["rays_per_s"][sel], "k" + markers[gi % len(markers)] + "-", label="achieved (RTL)" + tag)
        for x, r, b in zip(t, d["rays_per_s"][sel], d["binding"][sel]):
            a1.annotate(str(b), (x, r), textcoords="offset points", xytext=(0, -12), ha="center", fontsize=7)
    a1.set_yscale("log")
    a1.set_ylabel(f"rays/s at {kv.get('clock_mhz', '?')} MHz")
    a1.set_title(f"roofline: {Path(kv.get('scene', csv)).stem}, {d['rays'][0]} rays")
    for gi, k in enumerate(groups):
        sel = ius == k
        for key, label, colour, style in SHARES:
            a2.plot(tus[sel], 100 * d[key][sel].astype(float), style.replace("o", markers[gi % len(markers)]), color=colour,
                    label=label + (f", IUS={k}" if len(groups) > 1 else ""))
    a2.set_ylabel("%")
    a2.set_ylim(0, 105)
    a2.set_title("utilisation and stalls")
    tus_axes((a1, a2), tus)
    save_with_footer(fig, out, prov, fontsize=5.5)
    plt.close(fig)
    print(f"[plot] {out}", file=sys.stderr)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("error: usage: python -m dse.plots.roofline OUT.png CSV")
    main(*sys.argv[1:])
