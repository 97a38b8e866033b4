"""python -m golden.image --tris TRIS.npy --golden DIR --hits HITS.npy --out OUTDIR

Pictures of one set of hits on the camera rays of a `make golden` directory DIR (rays.npy, hits.npy, meta.json;
the first width x height rays, row-major from the top-left pixel, width and height from meta.json "params"):
  OUTDIR/image.png  HITS shaded: grey = |cos(triangle normal, fixed light)| (plus ambient), black = miss,
                    magenta = memory read error (prim -2), orange = stack overflow (prim -3)
  OUTDIR/diff.png   every pixel whose HITS record does not agree with Embree's (DIR/hits.npy) under the rules of
                    golden.check, coloured by the class golden.check gives it; agreeing pixels dark grey
Both carry a legend and a footer naming the scene, the hits file and the rtaccel version (RTACCEL_VERSION, else
`git describe --always --dirty`). Last stdout line: {"image", "diff", "width", "height", "differing_pixels",
"classes": {class: pixels}}. Differing pixels are not a failure (exit 0). Bad input: one `error:` line, exit 2,
no file written.
"""
import json
import os
import subprocess

import numpy as np

from scenes.cli import ArgParser, atomic_file, run

from .check import ray_classes
from .io import FAULT_CODES, PRIM_OVERFLOW, PRIM_READ_ERROR, PRIM_STEP_LIMIT, GoldenError, load_hits, load_rays, load_tris

LIGHT = np.array([0.4, 0.8, 0.45]) / np.linalg.norm([0.4, 0.8, 0.45])
AMBIENT = 0.12  # keeps surfaces edge-on to the light distinguishable from misses
FAULT_RGB = {PRIM_READ_ERROR: (1.0, 0.0, 1.0), PRIM_OVERFLOW: (1.0, 0.55, 0.0), PRIM_STEP_LIMIT: (0.55, 0.35, 0.1)}
# Classes in legend order; faults keep their image.png colours so both pictures read alike.
DIFF_RGB = {"agree": (0.2, 0.2, 0.2), "tie": (0.3, 0.55, 1.0), "edge": (0.2, 0.85, 0.85),
            "grazing": (0.3, 0.8, 0.3), "degenerate": (0.95, 0.9, 0.2), "unexplained": (0.9, 0.1, 0.1),
            **{name: FAULT_RGB[code] for name, code in FAULT_CODES.items()}}

LABELS = {"read_error": "read error (prim -2)", "overflow": "stack overflow (prim -3)", "step_limit": "step limit (prim -4)"}


def camera_frame(meta, n_rays, where):
    """(width, height) of the camera rays, which are the first width*height of the n_rays."""
    p = meta.get("params") if isinstance(meta, dict) else None
    w, h = (p.get("width"), p.get("height")) if isinstance(p, dict) else (None, None)
    if w is None or h is None:
        raise GoldenError(f"{where} has no params.width/height: its rays are not from a camera; give a directory "
                          f"made by make golden")
    if not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (w, h)):
        raise GoldenError(f"{where}: params.width/height must be positive integers, got {w!r} x {h!r}")
    per_depth = meta.get("rays_per_depth")
    first = per_depth[0] if isinstance(per_depth, list) and per_depth else w * h
    if first != w * h or n_rays < w * h:
        raise GoldenError(f"{where}: {w} x {h} camera rays, but rays.npy has {n_rays} rays and rays_per_depth "
                          f"starts with {first}; the directory is inconsistent, remake it with make golden")
    return w, h


def shade(tris, hits):
    """(k, 3) RGB in 0..1 for hit records (prim checked against tris by the caller)."""
    rgb = np.zeros((len(hits), 3))
    hit = hits["prim"] >= 0
    t = tris[hits["prim"][hit]].astype(np.float64)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    ln = np.linalg.norm(n, axis=1)
    cos = np.abs(n @ LIGHT) / np.where(ln > 0, ln, 1)  # a zero-area triangle has no normal: ambient only
    rgb[hit] = (AMBIENT + (1 - AMBIENT) * cos)[:, None]
    for code, c in FAULT_RGB.items():
        rgb[hits["prim"] == code] = c
    return rgb


def render(tris, rays, golden, hits, w, h):
    """image (h,w,3), diff (h,w,3) and the per-pixel class (h,w) of the first w*h rays."""
    k = w * h
    cls = ray_classes(tris, rays[:k], golden[:k], hits[:k])
    diff = np.array([DIFF_RGB[c] for c in cls])
    return shade(tris, hits[:k]).reshape(h, w, 3), diff.reshape(h, w, 3), cls.reshape(h, w)


def rtaccel_version():
    v = os.environ.get("RTACCEL_VERSION", "").strip()
    if v:
        return v
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        r = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=root, capture_output=True, text=True,
                           timeout=10)
        return r.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _png(path, rgb, title, legend, footer):
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    h, w = rgb.shape[:2]
    # 5 inches for the longer side of the picture; title above, legend right, footer below it
    iw, ih = (5.0, 5.0 * h / w) if w >= h else (5.0 * w / h, 5.0)
    fw, fh = max(iw, 5.0) + 2.6, ih + 0.95
    fig = plt.figure(figsize=(fw, fh))
    ax = fig.add_axes((0.1 / fw, 0.55 / fh, iw / fw, ih / fh))
    ax.imshow(rgb, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)
    fig.legend(handles=[Patch(facecolor=c, edgecolor="0.5", label=l) for l, c in legend], loc="center left",
               bbox_to_anchor=((iw + 0.2) / fw, (0.55 + ih / 2) / fh), fontsize=8, frameon=False)
    fig.text(0.1 / fw, 0.08 / fh, footer, fontsize=6, va="bottom", ha="left", color="0.3", wrap=True)
    fig.savefig(path, dpi=max(120, int(np.ceil(max(w / iw, h / ih)))), format="png")  # >= 1 dot per pixel
    plt.close(fig)


def main(argv=None):
    ap = ArgParser(prog="python -m golden.image", description="Picture of hits on the camera rays, and a diff "
                                                                "against the golden hits.")
    ap.add_argument("--tris", required=True, help="float32 (T,3,3) triangles the hits refer to")
    ap.add_argument("--golden", required=True, help="make golden directory: rays.npy, hits.npy, meta.json")
    ap.add_argument("--hits", required=True, help="hits to draw (golden dtype, one record per ray of --golden)")
    ap.add_argument("--out", required=True, help="directory for image.png and diff.png (its parent must exist)")
    a = ap.parse_args(argv)
    if not os.path.isdir(a.golden):
        raise GoldenError(f"--golden {a.golden} is not a directory; run make golden first")
    meta_path = os.path.join(a.golden, "meta.json")
    if not os.path.isfile(meta_path):
        raise GoldenError(f"{meta_path} does not exist; give a directory made by make golden")
    try:
        with open(meta_path) as f:
            meta = json.load(f)
    except ValueError as e:
        raise GoldenError(f"{meta_path} is not JSON ({e}); remake the directory with make golden")
    tris = load_tris(a.tris)
    rays = load_rays(os.path.join(a.golden, "rays.npy"))
    golden = load_hits(os.path.join(a.golden, "hits.npy"), len(rays))
    hits = load_hits(a.hits, len(rays))
    w, h = camera_frame(meta, len(rays), meta_path)
    image, diff, cls = render(tris, rays, golden, hits, w, h)
    out = os.path.abspath(a.out)
    if not os.path.isdir(os.path.dirname(out)):
        raise GoldenError(f"parent directory {os.path.dirname(out)} of --out does not exist; create it first")
    if os.path.exists(out) and not os.path.isdir(out):
        raise GoldenError(f"--out {a.out} exists and is not a directory; choose another --out")
    import matplotlib
    matplotlib.use("Agg")
    made = not os.path.isdir(out)
    os.makedirs(out, exist_ok=True)
    counts = {c: int(np.sum(cls == c)) for c in DIFF_RGB}
    differing = w * h - counts["agree"]
    scene = meta.get("scene", a.golden)
    footer = f"scene={scene} hits={os.path.abspath(a.hits)} golden={os.path.abspath(a.golden)} " \
             f"camera={w}x{h} rtaccel={rtaccel_version()}"
    name = os.path.join(*os.path.normpath(str(scene)).split(os.sep)[-2:])  # fixtures are all <name>/scene.obj
    paths = os.path.join(out, "image.png"), os.path.join(out, "diff.png")
    legend = [("miss", (0, 0, 0))] + [(LABELS[n], FAULT_RGB[code]) for n, code in FAULT_CODES.items()]
    # Both pictures or neither: the renames happen only once both figures are written.
    try:
        with atomic_file(paths[0], suffix=".png") as tmp_img, atomic_file(paths[1], suffix=".png") as tmp_diff:
            _png(tmp_img, image, f"{name}: {os.path.basename(a.hits)}, |cos(normal, light)|", legend, footer)
            _png(tmp_diff, diff, f"{name}: {differing} of {w * h} pixels differ from Embree",
                 [(f"{LABELS.get(c, c)} ({counts[c]})", DIFF_RGB[c]) for c in DIFF_RGB], footer)
    except BaseException:
        if made:
            os.rmdir(out)
        raise
    print(json.dumps({"image": paths[0], "diff": paths[1], "width": w, "height": h, "differing_pixels": differing,
                      "classes": counts}))
    return 0


if __name__ == "__main__":
    run(main)
