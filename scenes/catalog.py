"""Default cameras per scene (scenes/catalog.json), looked up by the mesh file's stem.

camera_for(path, tris) returns {"eye", "look_at", "up", "fov_deg", "source"}:
  * the catalog entry for the file stem when the mesh's bounding box equals the catalog's recorded bbox
    (relative tolerance 1e-3 of the largest extent): source "catalog";
  * the same entry with eye and look_at multiplied by s when the bbox equals s times the recorded one
    (scenes written with `python -m scenes.procedural --scale s`): source "catalog-scaled";
  * otherwise (unknown stem, or a different mesh with a known stem) the fallback camera: outside the bbox,
    at the centre + 2.6 * (half diagonal) along the direction (1, 0.6, 1.4) normalised, looking at the bbox
    centre, up +y, fov 45 degrees, so the bounding sphere fits in the view: source "fallback".
fov_deg is the vertical field of view; the image aspect ratio widens the horizontal one.
"""
import json
import os

import numpy as np

CATALOG_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "catalog.json")
FALLBACK_FOV = 45.0
FALLBACK_DIR = (1.0, 0.6, 1.4)


def load_catalog() -> dict:
    with open(CATALOG_PATH) as f:
        data = json.load(f)
    return {k: v for k, v in data.items() if not k.startswith("_")}


def _bbox(tris):
    p = np.asarray(tris, dtype=np.float64).reshape(-1, 3)
    return p.min(axis=0), p.max(axis=0)


def fallback_camera(tris) -> dict:
    lo, hi = _bbox(tris)
    c = (lo + hi) / 2
    r = max(np.linalg.norm(hi - lo) / 2, np.finfo(np.float32).tiny)
    d = np.asarray(FALLBACK_DIR) / np.linalg.norm(FALLBACK_DIR)
    dist = r / np.sin(np.radians(FALLBACK_FOV) / 2)
    return {"eye": (c + dist * d).tolist(), "look_at": c.tolist(), "up": [0.0, 1.0, 0.0],
            "fov_deg": FALLBACK_FOV, "source": "fallback"}


def _scale_match(entry_bbox, lo, hi, tol=1e-3):
    """Return s if [lo,hi] == s * entry_bbox (s > 0) within tol of the extent, else None."""
    elo, ehi = np.asarray(entry_bbox[0], float), np.asarray(entry_bbox[1], float)
    eext = float(np.max(ehi - elo))
    ext = float(np.max(hi - lo))
    if eext <= 0 or ext <= 0:
        return None
    s = ext / eext
    err = max(np.max(np.abs(lo - s * elo)), np.max(np.abs(hi - s * ehi)))
    return s if err <= tol * ext else None


def camera_for(path, tris) -> dict:
    stem = os.path.splitext(os.path.basename(os.fspath(path)))[0]
    entry = load_catalog().get(stem)
    if entry is None:
        return fallback_camera(tris)
    lo, hi = _bbox(tris)
    s = _scale_match(entry["bbox"], lo, hi)
    if s is None:
        return fallback_camera(tris)
    cam = {k: [float(x) for x in entry[k]] for k in ("eye", "look_at", "up")}
    cam["fov_deg"] = float(entry["fov_deg"])
    if abs(s - 1.0) <= 1e-6:
        cam["source"] = "catalog"
    else:
        cam["eye"] = [s * x for x in cam["eye"]]
        cam["look_at"] = [s * x for x in cam["look_at"]]
        cam["source"] = "catalog-scaled"
    return cam
