"""python -m golden.check --tris TRIS.npy --golden DIR --hits MODEL_HITS.npy [--report-only]

Compares a model's hits with the golden (Embree) hits of the same rays and classifies every disagreement.
A short summary goes to stderr; the LAST stdout line is one JSON object:
  {"rays", "agree", "classified": {"tie", "edge", "grazing", "degenerate"}, "unexplained", "max_rel_t_err", ...,
   "faults": {"read_error", "overflow", "step_limit"}}
A model ray with prim -2 (memory read error), -3 (stack overflow) or -4 (step limit) never agrees: it is counted in "faults" and,
having no result, in "unexplained".
The rules, their order and every threshold are documented in docs/check.md; the constants below are those.
"""
import json
import os
import sys

import numpy as np

from scenes.cli import EXIT_CHECK_FAILED as CHECK_FAILED, ArgParser, run

from .io import (FAULT_CODES, PRIM_OVERFLOW, PRIM_READ_ERROR, PRIM_STEP_LIMIT, GoldenError, check_hits, check_rays, check_tris,
                 load_hits, load_rays, load_tris)
from .trace import build_scene, occluded

AGREE_REL = 1e-5        # both hit, |t_a - t_b| <= AGREE_REL * max(|t_a|, |t_b|): agree (coincident triangles)
DEGEN_ULPS = 2.0        # zero-area: height <= DEGEN_ULPS * 2^-23 * max |vertex coordinate| (a line in float32)
BARY_TOL = 1e-5         # barycentric tolerance of the edge/vertex test ...
POS_TOL = 4e-6          # ... widened to POS_TOL * S in distance (S: per-ray position scale, see _scale)
SCALE_FLOOR = 1e-3      # S >= SCALE_FLOOR * scene extent
GRAZE_COS = 1e-3        # grazing: |cos(ray, triangle normal)| < GRAZE_COS
TIE_REL = 1e-4          # tie: t tolerance = TIE_REL * max(|t_a|, |t_b|) + POS_TOL * S / |d|
CLASSES = ("tie", "edge", "grazing", "degenerate")
FAULT_LABELS = {PRIM_READ_ERROR: "read error", PRIM_OVERFLOW: "stack overflow", PRIM_STEP_LIMIT: "step limit"}


def _norm(x):
    return np.sqrt(np.einsum("ij,ij->i", x, x))


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def degenerate_mask(tris) -> np.ndarray:
    """True for triangles that are zero-area at float32 resolution (computed in float64): all vertices equal,
    or the height over the longest edge (2 * area / longest edge) is at most DEGEN_ULPS float32 ulps of the
    largest vertex coordinate magnitude (e.g. collinear points after rounding to float32)."""
    t = tris.astype(np.float64)
    e1, e2, e3 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0], t[:, 2] - t[:, 1]
    area2 = _norm(np.cross(e1, e2))
    lmax = np.sqrt(np.max(np.stack([_dot(e1, e1), _dot(e2, e2), _dot(e3, e3)]), axis=0))
    m = np.max(np.abs(t), axis=(1, 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        height = np.where(lmax > 0, area2 / np.where(lmax > 0, lmax, 1), 0.0)
    return (lmax == 0) | (height <= DEGEN_ULPS * 2.0 ** -23 * m)


def _intersect64(o, d, tri):
    """Float64 ray/plane intersection with the triangle: (t, barycentrics (k,3) for v0,v1,v2, heights (k,3)).
    Barycentric i is the signed distance to the edge opposite vertex i divided by the height h_i."""
    v0, v1, v2 = tri[:, 0], tri[:, 1], tri[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    p = np.cross(d, e2)
    det = _dot(e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - v0
        u = _dot(s, p) * inv
        q = np.cross(s, e1)
        v = _dot(d, q) * inv
        t = _dot(e2, q) * inv
        area2 = _norm(np.cross(e1, e2))
        lens = np.stack([_norm(v2 - v1), _norm(v0 - v2), _norm(v1 - v0)], axis=1)
        h = area2[:, None] / lens
        bary = np.stack([1 - u - v, u, v], axis=1)
    return t, bary, h


def _bary_tol(h, scale):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.maximum(BARY_TOL, POS_TOL * scale[:, None] / h)


_CUBE = np.array([[0, 1, 3], [0, 3, 2], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 3, 7], [1, 7, 5]])


def degenerate_boxes(tris, deg, extent) -> np.ndarray:
    """Each zero-area triangle as a closed oriented box (12 float32 triangles) around the segment of its longest
    edge (or its point), extended by w = POS_TOL * max(max |vertex coordinate|, SCALE_FLOOR * extent) on every
    side."""
    t = tris[deg].astype(np.float64)
    k = len(t)
    edges = np.stack([t[:, 1] - t[:, 0], t[:, 2] - t[:, 1], t[:, 0] - t[:, 2]], axis=1)
    j = np.argmax(np.sum(edges * edges, -1), axis=1)
    a = t[np.arange(k), j]
    seg = edges[np.arange(k), j]
    b = a + seg
    ln = _norm(seg)
    u = np.where(ln[:, None] > 0, seg / np.where(ln > 0, ln, 1)[:, None], [[1.0, 0.0, 0.0]])
    ax = np.where(np.abs(u[:, :1]) < 0.6, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    n1 = np.cross(u, ax)
    n1 /= _norm(n1)[:, None]
    n2 = np.cross(u, n1)
    w = POS_TOL * np.maximum(np.max(np.abs(t), axis=(1, 2)), SCALE_FLOOR * extent)[:, None]
    corners = np.empty((k, 8, 3))
    for c in range(8):
        base = (b + w * u) if c & 4 else (a - w * u)
        corners[:, c] = base + w * ((1 if c & 2 else -1) * n1 + (1 if c & 1 else -1) * n2)
    return np.ascontiguousarray(corners[:, _CUBE].reshape(-1, 3, 3).astype(np.float32))


def _degenerate_location(o, d, tcap, tris, deg, extent):
    """For each ray (o + t d, 0 <= t <= tcap): does it pass through the box of a zero-area triangle?
    Uses an Embree occlusion query against the boxes of degenerate_boxes()."""
    out = np.zeros(len(o), dtype=bool)
    if not deg.any() or len(o) == 0:
        return out
    boxes = degenerate_boxes(tris, deg, extent)
    scene, keep = build_scene(boxes)
    out[:] = occluded(scene, o.astype(np.float32), d.astype(np.float32), tcap.astype(np.float32))
    del keep
    return out


def _compare(tris, rays, golden_hits, model_hits):
    """The per-ray work shared by classify() and ray_classes(): validation, agreement, the class of every
    disagreeing ray (D: their indices; cls: their class, "" while unexplained; rem: still unexplained) and the
    float64 re-intersections the unexplained-ray details report."""
    check_tris(tris)
    check_rays(rays)
    n = len(rays)
    check_hits(golden_hits, n, where="golden hits")
    check_hits(model_hits, n, where="model hits")
    nt = len(tris)
    for name, h in (("golden", golden_hits), ("model", model_hits)):
        if h["prim"].max(initial=-1) >= nt:
            raise GoldenError(f"{name} hits reference prim {int(h['prim'].max())} but the triangle file has {nt} "
                              f"triangles; pass the triangles the hits were traced against")
    gfault = np.nonzero(golden_hits["prim"] <= PRIM_READ_ERROR)[0]
    if len(gfault):
        # Embree cannot fault, so these are not golden hits: comparing against them would hide the model's faults.
        raise GoldenError(f"golden hits: ray {int(gfault[0])} has fault code {int(golden_hits['prim'][gfault[0]])} "
                          f"({len(gfault)} such rays); golden hits come from Embree, pass the make golden directory")
    gp, mp = golden_hits["prim"], model_hits["prim"]
    gt, mt = golden_hits["t"].astype(np.float64), model_hits["t"].astype(np.float64)
    gh, mh = gp >= 0, mp >= 0
    both = gh & mh
    with np.errstate(invalid="ignore", over="ignore"):
        tmax = np.maximum(np.abs(gt), np.abs(mt))
        dt = np.abs(gt - mt)
        close = both & (dt <= AGREE_REL * tmax)
        # the same prim agrees only at nearly the same t: a wrong t on the right triangle is a difference to explain
        # (a tie within the classes' tolerance, or unexplained), not an agreement; two misses agree
        agree = ((gp == mp) & ~both) | close
        same = both & (gp == mp)
        rel = np.where(tmax[same] > 0, dt[same] / np.where(tmax[same] > 0, tmax[same], 1), 0.0)
    nonfinite = int(np.sum(~np.isfinite(rel)))
    finite_rel = rel[np.isfinite(rel)]
    max_rel = float(finite_rel.max()) if len(finite_rel) else 0.0

    deg_all = degenerate_mask(tris)
    lo, hi = tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0)
    extent = float(np.max(hi.astype(np.float64) - lo))

    D = np.nonzero(~agree)[0]
    r = rays[D].astype(np.float64)
    o, d = r[:, 0:3], r[:, 3:6]
    dn = _norm(d)
    g_hit, m_hit = gh[D], mh[D]
    gpd, mpd = np.maximum(gp[D], 0), np.maximum(mp[D], 0)
    gtd, mtd = gt[D], mt[D]
    with np.errstate(invalid="ignore", over="ignore"):
        pg = np.where(g_hit[:, None], o + np.where(g_hit, gtd, 0)[:, None] * d, 0)
        pm = np.where(m_hit[:, None], o + np.where(m_hit & np.isfinite(mtd), mtd, 0)[:, None] * d, 0)
    scale = np.maximum.reduce([np.max(np.abs(o), axis=1), np.max(np.abs(pg), axis=1),
                               np.max(np.abs(pm), axis=1), np.full(len(D), SCALE_FLOOR * extent)])

    cls = np.full(len(D), "", dtype=object)
    # A faulted ray has no result to explain a difference with: it takes no class and stays unexplained.
    fault_d = mp[D] <= PRIM_READ_ERROR
    rem = ~fault_d

    def assign(mask, name):
        nonlocal rem
        m = rem & mask
        cls[m] = name
        rem = rem & ~m

    # 1. degenerate: either side's prim is zero-area
    assign((g_hit & deg_all[gpd]) | (m_hit & deg_all[mpd]), "degenerate")

    tri_g, tri_m = tris[gpd].astype(np.float64), tris[mpd].astype(np.float64)
    tg64, bg, hg = _intersect64(o, d, tri_g)
    tm64, bm, hm = _intersect64(o, d, tri_m)
    tolg, tolm = _bary_tol(hg, scale), _bary_tol(hm, scale)
    with np.errstate(invalid="ignore"):
        inside_g = np.all(bg >= -tolg, axis=1)
        inside_m = np.all(bm >= -tolm, axis=1)
        edge_g = g_hit & inside_g & np.any(bg <= tolg, axis=1)
        edge_m = m_hit & inside_m & np.any(bm <= tolm, axis=1)
    # 2. edge: a side's hit point (float64, against its own prim) is within tolerance of an edge or vertex
    assign(edge_g | edge_m, "edge")

    with np.errstate(invalid="ignore", divide="ignore"):
        ng, nm = np.cross(tri_g[:, 1] - tri_g[:, 0], tri_g[:, 2] - tri_g[:, 0]), \
            np.cross(tri_m[:, 1] - tri_m[:, 0], tri_m[:, 2] - tri_m[:, 0])
        cos_g = np.abs(_dot(ng, d)) / (_norm(ng) * dn)
        cos_m = np.abs(_dot(nm, d)) / (_norm(nm) * dn)
    # 3. grazing: the ray is nearly parallel to a hit triangle's plane
    assign((g_hit & (cos_g < GRAZE_COS)) | (m_hit & (cos_m < GRAZE_COS)), "grazing")

    with np.errstate(invalid="ignore", over="ignore"):
        ttol = TIE_REL * np.maximum(np.abs(gtd), np.abs(mtd)) + POS_TOL * scale / dn
        both_d = g_hit & m_hit
        tie_t = both_d & (np.abs(gtd - mtd) <= ttol)
        # one prim also hit at the other's t: two prims; for the same prim it would excuse a wrong t by the right one
        other = both_d & (gpd != mpd)
        m_at_g = other & inside_m & (tm64 >= 0) & (np.abs(tm64 - gtd) <= ttol)
        g_at_m = other & inside_g & (tg64 >= 0) & (np.abs(tg64 - mtd) <= ttol)
    # 4. tie: both hit at nearly the same t, or one side's prim is also hit (float64) at the other's t
    assign(tie_t | m_at_g | g_at_m, "tie")

    # 5. degenerate (location): the ray passes through a zero-area triangle before the farther hit
    if rem.any():
        sel = np.nonzero(rem)[0]
        with np.errstate(invalid="ignore"):
            tcap = np.fmax(np.where(g_hit[sel], gtd[sel], np.nan), np.where(m_hit[sel], mtd[sel], np.nan))
        tcap = np.where(np.isfinite(tcap), tcap * (1 + TIE_REL), 0.0)
        hitloc = _degenerate_location(o[sel], d[sel], tcap, tris, deg_all, extent)
        mask = np.zeros(len(D), dtype=bool)
        mask[sel] = hitloc
        assign(mask, "degenerate")

    return dict(n=n, agree=agree, max_rel=max_rel, nonfinite=nonfinite, D=D, cls=cls, rem=rem, fault_d=fault_d,
                gp=gp, mp=mp, gt=gt, mt=mt, g_hit=g_hit, m_hit=m_hit, bg=bg, bm=bm, tm64=tm64)


def ray_classes(tris, rays, golden_hits, model_hits) -> np.ndarray:
    """The class classify() counts each ray in, one string per ray: "agree", one of CLASSES, "unexplained", or
    a FAULT_CODES name ("read_error", "overflow", "step_limit") for a model fault."""
    c = _compare(tris, rays, golden_hits, model_hits)
    out = np.full(c["n"], "agree", dtype=object)
    D, cls = c["D"], c["cls"].copy()
    cls[c["rem"]] = "unexplained"
    for name, code in FAULT_CODES.items():
        cls[c["fault_d"] & (c["mp"][D] == code)] = name
    out[D] = cls
    return out


def classify(tris, rays, golden_hits, model_hits, examples=10) -> dict:
    """Compare model hits with golden hits (same ray order). Returns the summary dict printed by the CLI,
    with extra keys: "disagree", "nonfinite_t_same_prim", "examples" (up to `examples` ray indices per class),
    "unexplained_rays" (details of up to `examples` unexplained rays, faulted ones included) and "faults"
    (model rays per fault code; they are counted in "unexplained" too)."""
    c = _compare(tris, rays, golden_hits, model_hits)
    D, cls, rem, fault_d = c["D"], c["cls"], c["rem"], c["fault_d"]
    gp, mp, gt, mt, g_hit, m_hit = c["gp"], c["mp"], c["gt"], c["mt"], c["g_hit"], c["m_hit"]
    bg, bm, tm64 = c["bg"], c["bm"], c["tm64"]
    counts = {k: int(np.sum(cls == k)) for k in CLASSES}
    unexplained = np.nonzero(rem | fault_d)[0]
    details = []
    for i in unexplained[:examples]:
        ray = int(D[i])
        details.append({
            "ray": ray, "origin": rays[ray, 0:3].tolist(), "dir": rays[ray, 3:6].tolist(),
            "golden": {"prim": int(gp[ray]), "t": _f(gt[ray])},
            "model": {"prim": int(mp[ray]), "t": _f(mt[ray])},
            "golden_prim_bary64": bg[i].tolist() if g_hit[i] else None,
            "model_prim_bary64": bm[i].tolist() if m_hit[i] else None,
            "model_prim_t64": _f(tm64[i]) if m_hit[i] else None,
        })
    return {
        "rays": int(c["n"]),
        "agree": int(np.sum(c["agree"])),
        "classified": counts,
        "unexplained": int(len(unexplained)),
        "max_rel_t_err": c["max_rel"],
        "disagree": int(len(D)),
        "nonfinite_t_same_prim": c["nonfinite"],
        "examples": {k: [int(D[i]) for i in np.nonzero(cls == k)[0][:examples]] for k in CLASSES},
        "unexplained_rays": details,
        "faults": {k: int(np.sum(mp == code)) for k, code in FAULT_CODES.items()},
    }


def _f(x):
    x = float(x)
    return x if np.isfinite(x) else (None if np.isnan(x) else ("inf" if x > 0 else "-inf"))


def summary_text(res: dict) -> str:
    c, f = res["classified"], res["faults"]
    lines = [f"rays {res['rays']}: agree {res['agree']}, disagree {res['disagree']} "
             f"(tie {c['tie']}, edge {c['edge']}, grazing {c['grazing']}, degenerate {c['degenerate']}), "
             f"unexplained {res['unexplained']} (of which model faults: read error {f['read_error']}, "
             f"stack overflow {f['overflow']}, step limit {f['step_limit']}); max rel t err (same prim) {res['max_rel_t_err']:.3g}"]
    for u in res["unexplained_rays"]:
        fault = FAULT_LABELS.get(u["model"]["prim"])
        lines.append(f"  unexplained ray {u['ray']}{f' (model fault: {fault})' if fault else ''}: "
                     f"o={u['origin']} d={u['dir']} golden={u['golden']} "
                     f"model={u['model']} golden_bary64={u['golden_prim_bary64']} "
                     f"model_bary64={u['model_prim_bary64']} model_t64={u['model_prim_t64']}")
    return "\n".join(lines)


def main(argv=None):
    ap = ArgParser(prog="python -m golden.check", description="Classify model hits against golden hits.")
    ap.add_argument("--tris", required=True, help="float32 (T,3,3) triangles (python -m scenes.export)")
    ap.add_argument("--golden", required=True, help="golden directory with rays.npy and hits.npy")
    ap.add_argument("--hits", required=True, help="model hits, same dtype as golden hits, same ray order")
    ap.add_argument("--summary", help="the model's summary.json (make trace): its config and numerics go into the JSON line")
    ap.add_argument("--report-only", action="store_true",
                    help="exit 0 even when rays are unexplained (default: exit 3, 'ran, but a check failed')")
    a = ap.parse_args(argv)
    if not os.path.isdir(a.golden):
        raise GoldenError(f"--golden {a.golden} is not a directory; run python -m golden.export first")
    tris = load_tris(a.tris)
    rays = load_rays(os.path.join(a.golden, "rays.npy"))
    golden = load_hits(os.path.join(a.golden, "hits.npy"), len(rays))
    model = load_hits(a.hits, len(rays))
    res = classify(tris, rays, golden, model)
    if a.summary:
        with open(a.summary) as fh:
            made = json.load(fh)
        res = {**{k: made[k] for k in ("scene", "config", "rtaccel", "numerics") if k in made}, **res}
    print(summary_text(res), file=sys.stderr)
    print(json.dumps(res))
    # A check is an exit status: the JSON line stays the last line either way.
    return CHECK_FAILED if (res["unexplained"] and not a.report_only) else 0


if __name__ == "__main__":
    run(main)
