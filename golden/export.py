"""python -m golden.export --scene MESH --out DIR [--width 64] [--height 48] [--depth 5] [--seed 1]

Writes a golden trace of a scene into DIR (see docs/golden.md):
  rays.npy  float32 (N,8) ox,oy,oz,dx,dy,dz,tmin,tmax   (tmin = 0, tmax = +inf)
  hits.npy  structured (t <f4, prim <i4, u <f4, v <f4)   (miss: prim -1, t +inf, u = v = 0)
  meta.json scene, sha256, triangles, versions, flags, parameters, camera, rays per depth, epsilon rule

Rays: one pinhole camera ray per pixel (row-major from the top-left pixel), then for every hit a diffuse
bounce ray (cosine-weighted on the hemisphere of the geometric normal facing the incoming ray), up to DEPTH
bounces; a path ends on a miss. Rays are stored depth by depth; within a depth in path (pixel) order.
"""
import json
import os
import re
import time

import numpy as np

from scenes.catalog import camera_for
from scenes.cli import ArgParser, atomic_dir, run
from scenes.load import bbox, file_sha256, load_triangles

from .io import GoldenError, save_npy
from .trace import SCENE_FLAGS, build_scene, trace_scene, versions

# Bounce origin offset: eps = OFFSET_REL * max(max|P|, OFFSET_SCENE_REL * scene_extent) along the normal.
OFFSET_REL = 1e-5
OFFSET_SCENE_REL = 1e-2


def rtaccel_version() -> str:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        with open(os.path.join(root, "build.sbt")) as f:
            m = re.search(r'version\s*:=\s*"([^"]+)"', f.read())
        if m:
            return m.group(1)
    except OSError:
        pass
    return "0.1.0"


def camera_rays(cam: dict, width: int, height: int) -> np.ndarray:
    """One ray per pixel through the pixel centre; fov_deg is the vertical field of view."""
    eye = np.asarray(cam["eye"], np.float64)
    fwd = np.asarray(cam["look_at"], np.float64) - eye
    if np.linalg.norm(fwd) == 0:
        raise GoldenError("camera eye and look_at coincide; give a look_at point different from the eye")
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.asarray(cam["up"], np.float64))
    if np.linalg.norm(right) == 0:
        raise GoldenError("camera up vector is parallel to the view direction; give another up vector")
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    th = np.tan(np.radians(float(cam["fov_deg"])) / 2)
    xs = (2 * (np.arange(width) + 0.5) / width - 1) * th * width / height
    ys = (1 - 2 * (np.arange(height) + 0.5) / height) * th
    d = fwd[None, None, :] + xs[None, :, None] * right[None, None, :] + ys[:, None, None] * up[None, None, :]
    d = d.reshape(-1, 3)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    rays = np.empty((len(d), 8), np.float32)
    rays[:, 0:3] = eye
    rays[:, 3:6] = d
    rays[:, 6] = 0.0
    rays[:, 7] = np.inf
    return rays


def _orthonormal_basis(n):
    """Two unit vectors perpendicular to each unit row of n (float64)."""
    a = np.where(np.abs(n[:, :1]) < 0.6, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t = np.cross(n, a)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(n, t)
    return t, b


def bounce_rays(tris, rays, hits, rng, extent):
    """Diffuse bounce rays for the hit rays. Returns (new rays float32 (M,8), index of the parent rays)."""
    idx = np.nonzero(hits["prim"] >= 0)[0]
    r = rays[idx].astype(np.float64)
    o, d = r[:, 0:3], r[:, 3:6]
    t = hits["t"][idx].astype(np.float64)
    p = o + t[:, None] * d
    tri = tris[hits["prim"][idx]].astype(np.float64)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nl = np.linalg.norm(n, axis=1)
    ok = nl > 0  # a zero-area triangle has no normal: the path ends there
    idx, p, d, n, nl = idx[ok], p[ok], d[ok], n[ok], nl[ok]
    n /= nl[:, None]
    n[np.sum(n * d, axis=1) > 0] *= -1  # face the side the ray came from
    u = rng.random((len(idx), 2))
    rad = np.sqrt(u[:, 0])
    phi = 2 * np.pi * u[:, 1]
    tb, bb = _orthonormal_basis(n)
    nd = (rad * np.cos(phi))[:, None] * tb + (rad * np.sin(phi))[:, None] * bb + \
        np.sqrt(np.maximum(0.0, 1 - u[:, 0]))[:, None] * n
    nd /= np.linalg.norm(nd, axis=1, keepdims=True)
    eps = OFFSET_REL * np.maximum(np.max(np.abs(p), axis=1), OFFSET_SCENE_REL * extent)
    out = np.empty((len(idx), 8), np.float32)
    out[:, 0:3] = p + eps[:, None] * n
    out[:, 3:6] = nd
    out[:, 6] = 0.0
    out[:, 7] = np.inf
    return out, idx


def generate(tris, cam, width, height, depth, seed):
    """Trace camera rays and `depth` bounces. Returns (rays (N,8), hits, rays per depth, build/trace seconds)."""
    rng = np.random.default_rng(seed)
    scene, keep = build_scene(tris)
    lo, hi = bbox(tris)
    extent = float(np.max(np.asarray(hi) - np.asarray(lo)))
    cur = camera_rays(cam, width, height)
    all_rays, all_hits, per_depth = [], [], []
    for k in range(depth + 1):
        h = trace_scene(scene, cur)
        all_rays.append(cur)
        all_hits.append(h)
        per_depth.append(int(len(cur)))
        if k == depth:
            break
        cur, _ = bounce_rays(tris, cur, h, rng, extent)
        if len(cur) == 0:
            break
    del keep
    return np.concatenate(all_rays), np.concatenate(all_hits), per_depth


def main(argv=None):
    ap = ArgParser(prog="python -m golden.export", description="Write a golden Embree trace of a scene.")
    ap.add_argument("--scene", required=True, help="mesh file (.obj or .ply)")
    ap.add_argument("--out", required=True, help="output directory (replaced as a whole on success)")
    ap.add_argument("--width", type=int, default=64)
    ap.add_argument("--height", type=int, default=48)
    ap.add_argument("--depth", type=int, default=5, help="bounces after the camera rays (0 = camera rays only)")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)
    if a.width <= 0 or a.height <= 0:
        raise GoldenError(f"--width {a.width} --height {a.height}: both must be positive")
    if a.width * a.height > 1 << 26:
        raise GoldenError(f"--width x --height = {a.width * a.height} rays is too many; stay below 2^26")
    if a.depth < 0:
        raise GoldenError(f"--depth {a.depth} must be >= 0")
    if a.seed < 0:
        raise GoldenError(f"--seed {a.seed} must be >= 0")
    t0 = time.perf_counter()
    tris = load_triangles(a.scene)
    cam = camera_for(a.scene, tris)
    rays, hits, per_depth = generate(tris, cam, a.width, a.height, a.depth, a.seed)
    v = versions()
    meta = {
        "format": "rtaccel-golden-1",
        "scene": os.path.abspath(a.scene),
        "sha256": file_sha256(a.scene),
        "triangles": int(len(tris)),
        "bbox": bbox(tris),
        "embreex_version": v["embreex"],
        "embree_version": v["embree"],
        "scene_flags": SCENE_FLAGS,
        "params": {"width": a.width, "height": a.height, "depth": a.depth, "seed": a.seed},
        "camera": cam,
        "rays": int(len(rays)),
        "hits": int((hits["prim"] >= 0).sum()),
        "rays_per_depth": per_depth,
        "bounce_offset": {"rule": "origin = P + eps * N, eps = rel * max(max|P_i|, scene_rel * scene_extent)",
                          "rel": OFFSET_REL, "scene_rel": OFFSET_SCENE_REL},
        "rtaccel_version": rtaccel_version(),
        "seconds": round(time.perf_counter() - t0, 3),
    }
    with atomic_dir(a.out) as tmp:
        save_npy(os.path.join(tmp, "rays.npy"), rays)
        save_npy(os.path.join(tmp, "hits.npy"), hits)
        with open(os.path.join(tmp, "meta.json"), "w") as f:
            json.dump(meta, f, indent=1)
            f.write("\n")
    return 0


if __name__ == "__main__":
    run(main)
