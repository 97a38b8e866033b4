"""python -m dse.plots.analysis DIR

Reads DIR/bandwidth_vs_mppl.csv and DIR/levels.csv and writes
  DIR/bandwidth_vs_mppl.png  node, primitive and total bytes per ray vs MPPL, log2 x axis (paper Fig. 4)
  DIR/levels.png             2x2 panels (paper Figs. 5-6): nodes per level, accesses per level, accesses per
                             node per level, cumulative share of nodes and of accesses by level
Lines starting with '#' are provenance comments (scene, config, version); they are shown as the plot footer,
and the first one is added to the title.
"""
import csv
import os

import numpy as np

from dse.plots.axes import log2_x
from dse.common import save_png
from scenes.cli import ArgParser, run
from scenes.errors import UserError

BANDWIDTH_COLUMNS = ("mppl", "rays", "nodes", "leaves", "depth", "node_accesses", "leaf_accesses",
                     "prim_accesses", "node_bytes_per_ray", "prim_bytes_per_ray", "total_bytes_per_ray")
LEVEL_COLUMNS = ("level", "nodes", "accesses", "accesses_per_node", "cum_node_share", "cum_access_share")


def read_csv(path, columns):
    """Return (comments, {column: float64 array}) sorted as in the file. Raises UserError on any problem."""
    if not os.path.isfile(path):
        raise UserError(f"{path} does not exist; write it with the Scala analysis first")
    comments, rows = [], []
    with open(path, newline="") as f:
        for line in f:
            s = line.strip()
            if not s:
                continue
            if s.startswith("#"):
                comments.append(s.lstrip("#").strip())
            else:
                rows.append(s)
    if not rows:
        raise UserError(f"{path} has no header line; expected columns {','.join(columns)}")
    reader = list(csv.reader(rows))
    header = [h.strip() for h in reader[0]]
    missing = [c for c in columns if c not in header]
    if missing:
        raise UserError(f"{path} lacks column(s) {','.join(missing)}; expected {','.join(columns)}")
    data = reader[1:]
    if not data:
        raise UserError(f"{path} has a header but no data rows")
    out = {}
    for c in columns:
        j = header.index(c)
        try:
            out[c] = np.array([float(r[j]) for r in data], dtype=np.float64)
        except (ValueError, IndexError):
            raise UserError(f"{path}: column {c} has a missing or non-numeric value; fix the CSV")
    return comments, out


def _footer(fig, comments):
    if comments:
        fig.text(0.01, 0.005, "\n".join(comments), fontsize=7, va="bottom", ha="left", color="0.3")


def _title(base, comments):
    return base + (f"\n{comments[0]}" if comments else "")


def plot_bandwidth(d, out):
    import matplotlib.pyplot as plt

    comments, c = read_csv(os.path.join(d, "bandwidth_vs_mppl.csv"), BANDWIDTH_COLUMNS)
    order = np.argsort(c["mppl"])
    x = c["mppl"][order]
    if np.any(x <= 0):
        raise UserError("bandwidth_vs_mppl.csv: mppl must be positive for a log2 axis")
    fig, ax = plt.subplots(figsize=(6.4, 4.8 + 0.15 * len(comments)))
    ax.plot(x, c["node_bytes_per_ray"][order], "o-", label="node")
    ax.plot(x, c["prim_bytes_per_ray"][order], "s-", label="primitive")
    ax.plot(x, c["total_bytes_per_ray"][order], "^-", label="total")
    log2_x(ax, x, "max primitives per leaf (MPPL)", "bytes per ray")
    ax.legend()
    ax.set_title(_title("Bandwidth per ray vs MPPL", comments), fontsize=10)
    fig.tight_layout(rect=(0, 0.03 + 0.025 * len(comments), 1, 1))
    _footer(fig, comments)
    save_png(fig, out)
    plt.close(fig)


def plot_levels(d, out):
    import matplotlib.pyplot as plt

    comments, c = read_csv(os.path.join(d, "levels.csv"), LEVEL_COLUMNS)
    order = np.argsort(c["level"])
    lv = c["level"][order]
    fig, axs = plt.subplots(2, 2, figsize=(10, 7.5 + 0.15 * len(comments)))
    (a, b), (e, f) = axs
    a.bar(lv, c["nodes"][order], color="C0")
    a.set_title("nodes per level", fontsize=10)
    b.bar(lv, c["accesses"][order], color="C1")
    b.set_title("node accesses per level", fontsize=10)
    e.bar(lv, c["accesses_per_node"][order], color="C2")
    e.set_title("accesses per node per level", fontsize=10)
    f.plot(lv, c["cum_node_share"][order], "o-", label="nodes")
    f.plot(lv, c["cum_access_share"][order], "s-", label="accesses")
    f.set_ylim(0, 1.02)
    f.set_title("cumulative share by level", fontsize=10)
    f.legend()
    for ax in axs.flat:
        ax.set_xlabel("level")
        ax.grid(True, alpha=0.3)
    fig.suptitle(_title("Node accesses by hierarchy level", comments), fontsize=11)
    fig.tight_layout(rect=(0, 0.03 + 0.02 * len(comments), 1, 1))
    _footer(fig, comments)
    save_png(fig, out)
    plt.close(fig)


def main(argv=None):
    ap = ArgParser(prog="python -m dse.plots.analysis", description="Plot the bandwidth and level analysis CSVs.")
    ap.add_argument("dir", help="directory with bandwidth_vs_mppl.csv and levels.csv")
    a = ap.parse_args(argv)
    if not os.path.isdir(a.dir):
        raise UserError(f"{a.dir} is not a directory; give the analysis output directory")
    import matplotlib
    matplotlib.use("Agg")
    # read and check both inputs before writing anything
    read_csv(os.path.join(a.dir, "bandwidth_vs_mppl.csv"), BANDWIDTH_COLUMNS)
    read_csv(os.path.join(a.dir, "levels.csv"), LEVEL_COLUMNS)
    plot_bandwidth(a.dir, os.path.join(a.dir, "bandwidth_vs_mppl.png"))
    plot_levels(a.dir, os.path.join(a.dir, "levels.png"))
    return 0


if __name__ == "__main__":
    run(main)
