"""python -m dse.plots.caches fig11|bytes OUT.png CSV [CSV ...] — the cache figures of the paper.

  fig11  node-cache miss rate vs cache size (paper Fig 11), one panel per CSV (= per scene): direct-mapped,
         breadth-first and LRP0..6 as written by `dse.paper.caches` (fig11_miss_rate.csv)
  bytes  DRAM bytes per ray vs MPPL (paper Figs 4, 8, 9), one row per CSV: (a) no cache, (b) node cache only,
         (c) node + primitive caches, node and primitive bytes stacked (fig8_9_bytes_per_ray.csv)

`#` lines of a CSV are provenance (scene, config, rtaccel version); the first one of each CSV goes into the
footer of the PNG, so a picture always says what made it. Every input is read and checked before anything
is written; a bad one gives one `error:` line and exit status 2.
"""
import csv
import os

import numpy as np

from dse.plots.axes import log2_x
from dse.common import parse_provenance, save_png
from scenes.cli import ArgParser, run
from scenes.errors import UserError

# Fig 11 of the paper shows these nine curves; the sweep CSV has more rows (4-way, hybrid), kept in the CSV only.
FIG11_CONFIGS = ("dm", "bf") + tuple(f"lrp{k}" for k in range(7))
BYTES_COLUMNS = ("mppl", "variant", "node_bytes_per_ray", "prim_bytes_per_ray", "dram_bytes_per_ray",
                 "node_miss_rate", "prim_miss_rate")
# (variant name in the CSV, panel title); the order is the paper's (a) Fig 4, (b) Fig 8, (c) Fig 9.
VARIANTS = (("nocache", "(a) no cache"), ("node", "(b) node cache 8192 DM"),
            ("node_prim", "(c) node 4096 DM + prim 4096 DM"))


def split_csv(path, text=None):
    """(comment lines without '#', header cells, data rows) of a CSV; `text` instead of reading `path`."""
    if text is None:
        if not os.path.isfile(path):
            raise UserError(f"{path} does not exist; run make paper-caches first")
        with open(path, newline="") as f:
            text = f.read()
    comments, rows = [], []
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("#"):
            comments.append(s.lstrip("#").strip())
        elif s:
            rows.append(s)
    if not rows:
        raise UserError(f"{path} has no header line")
    table = list(csv.reader(rows))
    if len(table) < 2:
        raise UserError(f"{path} has a header but no data rows")
    return comments, [h.strip() for h in table[0]], table[1:]


def _num(path, what, v):
    try:
        x = float(v)
    except ValueError:
        raise UserError(f"{path}: {what} is '{v}', not a number; fix or regenerate the CSV")
    return x


def read_fig11(path, text=None):
    """(comments, sizes, {config: miss rates}) of a miss-rate sweep (`config,256,...,8192` rows)."""
    comments, header, rows = split_csv(path, text)
    if header[0] != "config" or len(header) < 2:
        raise UserError(f"{path}: header must be config,<size>,<size>,...; got {','.join(header)}")
    sizes = np.array([_num(path, "cache size in the header", h) for h in header[1:]])
    if np.any(sizes <= 0) or np.any(np.diff(sizes) <= 0):
        raise UserError(f"{path}: cache sizes in the header must be positive and increasing")
    rates = {}
    for r in rows:
        if len(r) != len(header):
            raise UserError(f"{path}: row {r[0]} has {len(r) - 1} values for {len(sizes)} sizes")
        v = np.array([_num(path, f"{r[0]} miss rate", x) for x in r[1:]])
        if np.any(~np.isfinite(v)) or np.any(v < 0) or np.any(v > 1):
            raise UserError(f"{path}: {r[0]} miss rates must be in 0..1")
        rates[r[0].strip()] = v
    missing = [c for c in FIG11_CONFIGS if c not in rates]
    if missing:
        raise UserError(f"{path} lacks row(s) {','.join(missing)}; expected {','.join(FIG11_CONFIGS)}")
    return comments, sizes, rates


def read_bytes(path, text=None):
    """(comments, MPPL values, {variant: {column: array over MPPL}}) of fig8_9_bytes_per_ray.csv."""
    comments, header, rows = split_csv(path, text)
    missing = [c for c in BYTES_COLUMNS if c not in header]
    if missing:
        raise UserError(f"{path} lacks column(s) {','.join(missing)}; expected {','.join(BYTES_COLUMNS)}")
    col = {c: header.index(c) for c in BYTES_COLUMNS}
    by = {}
    for r in rows:
        if len(r) != len(header):
            raise UserError(f"{path}: a row has {len(r)} cells for {len(header)} columns")
        v = r[col["variant"]].strip()
        if v not in dict(VARIANTS):
            raise UserError(f"{path}: unknown variant '{v}'; expected {','.join(dict(VARIANTS))}")
        m = _num(path, "mppl", r[col["mppl"]])
        # An absent cache has no miss rate: the cell is empty and is read as NaN.
        by.setdefault(v, {})[m] = {c: (np.nan if c.endswith("miss_rate") and not r[col[c]].strip()
                                       else _num(path, c, r[col[c]])) for c in BYTES_COLUMNS if c != "variant"}
    mppls = sorted(set().union(*(d.keys() for d in by.values())))
    if any(m <= 0 for m in mppls):
        raise UserError(f"{path}: mppl must be positive")
    for v, _ in VARIANTS:
        if v not in by or sorted(by[v]) != mppls:
            raise UserError(f"{path}: variant {v} needs one row for every MPPL ({','.join(f'{m:g}' for m in mppls)})")
    out = {v: {c: np.array([by[v][m][c] for m in mppls]) for c in BYTES_COLUMNS if c not in ("variant", "mppl")}
           for v, _ in VARIANTS}
    return comments, np.array(mppls), out


def provenance(comments):
    """key=value pairs of the first comment line (`scene=... config=... rtaccel=...`)."""
    return parse_provenance(comments[0]) if comments else {}


def scene_name(comments, path):
    return os.path.splitext(os.path.basename(provenance(comments).get("scene", path)))[0]


def _finish(fig, footer, out):
    """Provenance footer below the axes, then an atomic PNG write (a reader never sees half a file)."""
    import matplotlib.pyplot as plt

    fig.text(0.01, 0.005, "\n".join(footer), fontsize=6, va="bottom", ha="left", color="0.3")
    fig.tight_layout(rect=(0, 0.02 + 0.018 * len(footer), 1, 1))
    save_png(fig, out)
    plt.close(fig)


def plot_fig11(tables, out):
    """tables: [(path, comments, sizes, rates)] -> one miss-rate panel per scene."""
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, len(tables), figsize=(5.6 * len(tables), 4.6), squeeze=False)
    lrp_colors = plt.cm.viridis(np.linspace(0, 0.9, 7))
    for ax, (path, comments, sizes, rates) in zip(axs[0], tables):
        ax.plot(sizes, 100 * rates["dm"], "o-", color="C3", lw=2.2, label="direct mapped")
        ax.plot(sizes, 100 * rates["bf"], "s--", color="0.4", label="breadth first")
        for k in range(7):
            ax.plot(sizes, 100 * rates[f"lrp{k}"], ".-", color=lrp_colors[k], lw=1, label=f"LRP{k}")
        log2_x(ax, sizes, "node cache size (entries)", "miss rate (%)")
        ax.set_title(f"{scene_name(comments, path)}: miss rate vs cache size", fontsize=10)
        ax.legend(fontsize=7, ncol=2)
    _finish(fig, [c[1][0] for c in tables if c[1]], out)


def plot_bytes(tables, out):
    """tables: [(path, comments, mppls, data)] -> per scene three panels of stacked node/prim bytes per ray."""
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(len(tables), 3, figsize=(14, 3.9 * len(tables)), squeeze=False)
    for row, (path, comments, mppls, d) in zip(axs, tables):
        x = np.arange(len(mppls))
        for ax, (v, title) in zip(row, VARIANTS):
            node, prim = d[v]["node_bytes_per_ray"], d[v]["prim_bytes_per_ray"]
            ax.bar(x, node, color="C0", label="node")
            ax.bar(x, prim, bottom=node, color="C1", label="primitive")
            for xi, t in zip(x, node + prim):
                ax.text(xi, t, f"{t:.0f}", ha="center", va="bottom", fontsize=7)
            ax.set_xticks(x)
            ax.set_xticklabels([f"{m:g}" for m in mppls])
            ax.set_xlabel("max primitives per leaf (MPPL)")
            ax.set_ylabel("DRAM bytes per ray")
            ax.grid(True, axis="y", alpha=0.3)
            ax.set_title(f"{scene_name(comments, path)} {title}", fontsize=10)
            ax.legend(fontsize=7)
        # (b) and (c) on one scale so the node-vs-primitive trade of Fig 9 is visible; (a) is ~10x taller.
        top = 1.12 * max(float(np.max(d[v]["dram_bytes_per_ray"])) for v in ("node", "node_prim"))
        for ax in row[1:]:
            ax.set_ylim(0, top)
    _finish(fig, [c[1][0] for c in tables if c[1]], out)


KINDS = {"fig11": (read_fig11, plot_fig11), "bytes": (read_bytes, plot_bytes)}


def main(argv=None):
    ap = ArgParser(prog="python -m dse.plots.caches", description="Plot the paper's cache figures from CSVs.")
    ap.add_argument("kind", choices=sorted(KINDS), help="fig11 (miss rate vs size) or bytes (bytes per ray vs MPPL)")
    ap.add_argument("out", help="PNG to write")
    ap.add_argument("csvs", nargs="+", help="one CSV per scene")
    a = ap.parse_args(argv)
    read, plot = KINDS[a.kind]
    tables = [(p, *read(p)) for p in a.csvs]  # all inputs checked before anything is written
    import matplotlib
    matplotlib.use("Agg")
    plot(tables, a.out)
    print(f"[plot] {a.out}")
    return 0


if __name__ == "__main__":
    run(main)
