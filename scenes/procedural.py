"""Procedural test scenes, written as OBJ (positions and triangle faces only).

    python -m scenes.procedural NAME OUT.obj [--seed S] [--scale F]
    python -m scenes.procedural --all OUTDIR [--seed S] [--scale F]

Names:
  cornell  closed Cornell-style room (walls/floor/ceiling as 5x5 grids with shared vertices) and two
           axis-aligned boxes inside, each face a 2x2 grid; 396 triangles. Not random: the seed is ignored.
  hairball 400 random curves inside the unit sphere, each a thin (radius 0.006) 3-sided tube of 8 segments of
           length 0.12; 19,200 triangles.
  soup     2,000 random triangles of random size (log-uniform 0.01..0.4) and orientation in [-1,1]^3.
  extreme  closed room [-50,50]^3 holding needles, zero-area triangles (collinear and repeated vertices),
           huge and tiny triangles, and vertex stars (fans sharing one vertex) near the origin.

The output is deterministic for a seed: the same name, seed and scale give byte-identical files. Coordinates are
computed in float64, multiplied by --scale, rounded to float32 and written with 9 significant digits, so that
loading the OBJ gives back exactly those float32 values.
"""
import os

import numpy as np

from .cli import ArgParser, atomic_file, run
from .errors import UserError

NAMES = ("cornell", "hairball", "soup", "extreme")
DEFAULT_SEED = 1


class _Builder:
    """Collects vertices (deduplicated only where the generator asks for sharing) and triangles."""

    def __init__(self):
        self.verts = []
        self.faces = []
        self._index = {}

    def vertex(self, p, key=None):
        """Add a vertex; vertices with the same non-None key are shared."""
        if key is not None and key in self._index:
            return self._index[key]
        self.verts.append(np.asarray(p, dtype=np.float64))
        i = len(self.verts) - 1
        if key is not None:
            self._index[key] = i
        return i

    def tri(self, a, b, c):
        self.faces.append((a, b, c))

    def arrays(self):
        return np.array(self.verts, dtype=np.float64).reshape(-1, 3), np.array(self.faces, dtype=np.int64).reshape(-1, 3)


def _grid_face(b, origin, du, dv, n, flip, keyfn):
    """A planar rectangle origin + s*du + t*dv (s,t in [0,1]) as an n x n grid of quads (2 triangles each).
    Vertices are keyed by keyfn(point) so that coincident grid points of neighbouring faces are shared."""
    origin, du, dv = (np.asarray(x, dtype=np.float64) for x in (origin, du, dv))
    idx = [[b.vertex(p, keyfn(p)) for p in (origin + (i / n) * du + (j / n) * dv for j in range(n + 1))]
           for i in range(n + 1)]
    for i in range(n):
        for j in range(n):
            a, c, d, e = idx[i][j], idx[i + 1][j], idx[i + 1][j + 1], idx[i][j + 1]
            if flip:
                b.tri(a, e, d)
                b.tri(a, d, c)
            else:
                b.tri(a, c, d)
                b.tri(a, d, e)


def _box(b, lo, hi, n, inward, tag):
    """Axis-aligned box [lo, hi] with every face an n x n grid; faces share their boundary vertices."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    size = hi - lo

    def key(p):
        return (tag,) + tuple(np.round((p - lo) / size * n * 2).astype(int))

    ex, ey, ez = np.diag(size)
    # (origin, du, dv) with du x dv pointing outward
    faces = [
        (lo, ey, ex),                   # z = lo (normal -z)
        (lo + ez, ex, ey),              # z = hi (normal +z)
        (lo, ez, ey),                   # x = lo (normal -x)
        (lo + ex, ey, ez),              # x = hi (normal +x)
        (lo, ex, ez),                   # y = lo (normal -y)
        (lo + ey, ez, ex),              # y = hi (normal +y)
    ]
    for o, du, dv in faces:
        _grid_face(b, o, du, dv, n, flip=inward, keyfn=key)


def cornell(rng):
    b = _Builder()
    _box(b, (-1.0, 0.0, -1.0), (1.0, 2.0, 1.0), 5, inward=True, tag="room")
    _box(b, (0.05, 0.0, -0.25), (0.65, 0.6, 0.35), 2, inward=False, tag="short")
    _box(b, (-0.7, 0.0, 0.05), (-0.1, 1.2, 0.65), 2, inward=False, tag="tall")
    return b.arrays()


def hairball(rng, strands=400, segments=8, sides=3, radius=0.006):
    pts = np.empty((strands, segments + 1, 3))
    p = rng.normal(size=(strands, 3))
    p *= (rng.random((strands, 1)) ** (1 / 3) * 0.9 / np.linalg.norm(p, axis=1, keepdims=True))
    d = rng.normal(size=(strands, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    step = 0.12
    for i in range(segments + 1):
        pts[:, i] = p
        d = d + 0.5 * rng.normal(size=(strands, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        nxt = p + step * d
        out = np.linalg.norm(nxt, axis=1) > 1.0
        d[out] -= 2 * np.sum(d[out] * nxt[out], axis=1, keepdims=True) * nxt[out] / \
            np.sum(nxt[out] ** 2, axis=1, keepdims=True)  # reflect at the sphere
        p = p + step * d
    # ring frames propagated along each strand (parallel transport, no sudden twists)
    tang = np.gradient(pts, axis=1)
    tang /= np.linalg.norm(tang, axis=2, keepdims=True)
    a = np.where(np.abs(tang[:, :1, 0:1]) < 0.9, [[[1.0, 0, 0]]], [[[0, 1.0, 0]]])
    nrm = np.empty_like(pts)
    n = np.cross(tang[:, 0], a[:, 0])
    for i in range(segments + 1):
        n = n - np.sum(n * tang[:, i], axis=1, keepdims=True) * tang[:, i]
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        nrm[:, i] = n
    bin_ = np.cross(tang, nrm)
    ang = 2 * np.pi * np.arange(sides) / sides
    ring = pts[:, :, None, :] + radius * (np.cos(ang)[None, None, :, None] * nrm[:, :, None, :] +
                                          np.sin(ang)[None, None, :, None] * bin_[:, :, None, :])
    verts = ring.reshape(-1, 3)
    vid = np.arange(len(verts)).reshape(strands, segments + 1, sides)
    faces = []
    for j in range(sides):
        k = (j + 1) % sides
        a0, a1 = vid[:, :-1, j], vid[:, :-1, k]
        b0, b1 = vid[:, 1:, j], vid[:, 1:, k]
        faces.append(np.stack([np.stack([a0, b0, b1], -1), np.stack([a0, b1, a1], -1)], axis=2))
    # order: strand, segment, side, (2 triangles)
    faces = np.stack(faces, axis=2).reshape(-1, 3)
    return verts, faces


def soup(rng, count=2000):
    centre = rng.uniform(-1, 1, size=(count, 1, 3))
    size = np.exp(rng.uniform(np.log(0.01), np.log(0.4), size=(count, 1, 1)))
    tris = centre + size * rng.normal(size=(count, 3, 3))
    return tris.reshape(-1, 3), np.arange(3 * count).reshape(count, 3)


def extreme(rng):
    b = _Builder()
    _box(b, (-50.0, -50.0, -50.0), (50.0, 50.0, 50.0), 1, inward=True, tag="room")

    def t(p, q, r):
        b.tri(b.vertex(p), b.vertex(q), b.vertex(r))

    # a huge triangle spanning most of the room behind the content
    t((-45, -45, 30), (45, -45, 30), (0, 45, 30))
    # needles: two long edges and one very short edge
    for _ in range(40):
        c = rng.uniform(-1.5, 1.5, 3)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        w = rng.normal(size=3)
        w -= w.dot(u) * u
        w /= np.linalg.norm(w)
        length = rng.uniform(0.5, 2.0)
        short = 10.0 ** rng.uniform(-7, -3)
        t(c, c + length * u, c + length * u + short * w)
    # zero-area: collinear vertices, repeated vertices, all three equal
    for _ in range(20):
        c = rng.uniform(-1.5, 1.5, 3)
        u = rng.normal(size=3) * 0.5
        t(c, c + u, c + 0.5 * u)          # collinear (midpoint)
        t(c, c, c + u)                    # repeated vertex
        t(c, c, c)                        # a point
    # tiny triangles
    for _ in range(200):
        c = rng.uniform(-1.5, 1.5, 3)
        s = 10.0 ** rng.uniform(-6, -3)
        t(c, c + s * rng.normal(size=3), c + s * rng.normal(size=3))
    # vertex stars: fans of triangles sharing a centre vertex (and their rim vertices), facing -z (the camera)
    for k in range(6):
        c = np.array([-1.5 + 0.6 * k, rng.uniform(-1, 1), rng.uniform(-0.5, 1.0)])
        ci = b.vertex(c)
        m = int(rng.integers(5, 12))
        r = rng.uniform(0.05, 0.3)
        rim = [b.vertex(c + r * np.array([np.cos(a), np.sin(a), rng.uniform(-0.1, 0.1)]))
               for a in 2 * np.pi * np.arange(m) / m]
        for i in range(m):
            b.tri(ci, rim[i], rim[(i + 1) % m])
    # a medium triangle sharing an edge with a huge one (T-junction-free shared edge)
    p, q = b.vertex((-3, -3, 5)), b.vertex((3, -3, 5))
    b.tri(p, q, b.vertex((0, 3, 5)))
    b.tri(q, p, b.vertex((0, -40, 5)))
    return b.arrays()


GENERATORS = {"cornell": cornell, "hairball": hairball, "soup": soup, "extreme": extreme}


def generate(name: str, seed: int = DEFAULT_SEED, scale: float = 1.0):
    """Return (vertices float32 (V,3), faces int64 (F,3)) of a procedural scene."""
    if name not in GENERATORS:
        raise UserError(f"unknown procedural scene '{name}'; choose one of {', '.join(NAMES)}")
    if not np.isfinite(scale) or scale == 0:
        raise UserError(f"--scale {scale} must be a finite non-zero number")
    verts, faces = GENERATORS[name](np.random.default_rng(seed))
    with np.errstate(over="ignore", under="ignore"):
        v32 = (verts * scale).astype(np.float32)
    if not np.all(np.isfinite(v32)):
        raise UserError(f"--scale {scale} pushes coordinates beyond the float32 range; use a smaller scale")
    return v32, faces


def triangles(name: str, seed: int = DEFAULT_SEED, scale: float = 1.0) -> np.ndarray:
    v, f = generate(name, seed, scale)
    return np.ascontiguousarray(v[f])


def obj_text(name: str, seed: int = DEFAULT_SEED, scale: float = 1.0) -> str:
    v, f = generate(name, seed, scale)
    lines = [f"# rtaccel procedural scene '{name}' seed {seed} scale {scale!r}: {len(v)} vertices, {len(f)} triangles"]
    lines += ["v %.9g %.9g %.9g" % tuple(float(x) for x in p) for p in v]
    lines += ["f %d %d %d" % (a + 1, b + 1, c + 1) for a, b, c in f]
    return "\n".join(lines) + "\n"


def write_obj(name: str, out: str, seed: int = DEFAULT_SEED, scale: float = 1.0):
    text = obj_text(name, seed, scale)
    with atomic_file(out, suffix=".obj") as tmp:
        with open(tmp, "w") as fh:
            fh.write(text)


def main(argv=None):
    ap = ArgParser(prog="python -m scenes.procedural", description="Write procedural test scenes as OBJ.")
    ap.add_argument("name", nargs="?", help=f"one of {', '.join(NAMES)}")
    ap.add_argument("out", nargs="?", help="output .obj path")
    ap.add_argument("--all", metavar="OUTDIR", help="write every procedural scene as OUTDIR/<name>.obj")
    ap.add_argument("--seed", type=int, default=DEFAULT_SEED)
    ap.add_argument("--scale", type=float, default=1.0)
    a = ap.parse_args(argv)
    if a.all is not None:
        if a.name is not None:
            raise UserError("give either --all OUTDIR or NAME OUT.obj, not both")
        if not os.path.isdir(a.all):
            raise UserError(f"--all {a.all}: not a directory; create it first")
        texts = {n: obj_text(n, a.seed, a.scale) for n in NAMES}  # generate everything before writing anything
        for n, text in texts.items():
            with atomic_file(os.path.join(a.all, n + ".obj"), suffix=".obj") as tmp:
                with open(tmp, "w") as fh:
                    fh.write(text)
        return 0
    if a.name is None or a.out is None:
        raise UserError("usage: python -m scenes.procedural NAME OUT.obj [--seed S] [--scale F] | --all OUTDIR")
    if not a.out.endswith(".obj"):
        raise UserError(f"output '{a.out}' must end in .obj")
    write_obj(a.name, a.out, a.seed, a.scale)
    return 0


if __name__ == "__main__":
    run(main)
