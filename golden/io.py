"""File formats shared by the golden tools: rays, hits, triangles. Every loader checks shape and dtype and
raises GoldenError (one line: what is wrong, what to change)."""
import os

import numpy as np

from scenes.errors import UserError

RAY_COLUMNS = ("ox", "oy", "oz", "dx", "dy", "dz", "tmin", "tmax")
HIT_DTYPE = np.dtype([("t", "<f4"), ("prim", "<i4"), ("u", "<f4"), ("v", "<f4")])
# Negative prim codes of a hit record (t = +inf for all of them). The faults come from the model/RTL only: the ray
# has no result, so it must neither look like a miss nor be dropped.
PRIM_MISS = -1
PRIM_READ_ERROR = -2   # a memory read of the ray's traversal failed
PRIM_OVERFLOW = -3     # the ray's traversal stack overflowed
PRIM_STEP_LIMIT = -4   # the ray needed more fetches than MAX_STEPS (a loop through a corrupted image) and ended
FAULT_CODES = {"read_error": PRIM_READ_ERROR, "overflow": PRIM_OVERFLOW, "step_limit": PRIM_STEP_LIMIT}
PRIM_LOWEST = min(FAULT_CODES.values())


class GoldenError(UserError):
    """Bad rays/hits/triangles file or bad parameters of a golden tool."""


def _load_npy(path: str, what: str):
    if not os.path.isfile(path):
        raise GoldenError(f"{what} file {path} does not exist; check the path")
    try:
        return np.load(path, allow_pickle=False)
    except Exception as e:
        raise GoldenError(f"{what} file {path} is not a readable .npy array ({type(e).__name__}: {e}); "
                          f"regenerate it")


def check_rays(rays, where="rays"):
    """Validate an in-memory rays array: float32 (N,8), finite origins and directions, non-zero directions,
    0 <= tmin <= tmax (tmax may be +inf)."""
    if not isinstance(rays, np.ndarray) or rays.dtype != np.float32:
        raise GoldenError(f"{where}: dtype must be float32, got {getattr(rays, 'dtype', type(rays))}; "
                          f"save rays as float32 (N,8)")
    if rays.ndim != 2 or rays.shape[1] != 8:
        raise GoldenError(f"{where}: shape must be (N, 8) = ox,oy,oz,dx,dy,dz,tmin,tmax, got {rays.shape}")
    if len(rays) == 0:
        raise GoldenError(f"{where}: contains no rays; give at least one ray")
    if not np.all(np.isfinite(rays[:, :7])):
        raise GoldenError(f"{where}: NaN or Inf in origin, direction or tmin (ray "
                          f"{int(np.nonzero(~np.isfinite(rays[:, :7]).all(axis=1))[0][0])}); fix the rays")
    if np.isnan(rays[:, 7]).any():
        raise GoldenError(f"{where}: NaN tmax (ray {int(np.nonzero(np.isnan(rays[:, 7]))[0][0])}); use +inf for "
                          f"an unbounded ray")
    zero = np.all(rays[:, 3:6] == 0, axis=1)
    if zero.any():
        raise GoldenError(f"{where}: ray {int(np.nonzero(zero)[0][0])} has a zero direction; fix the rays")
    bad = (rays[:, 6] < 0) | (rays[:, 6] > rays[:, 7])
    if bad.any():
        raise GoldenError(f"{where}: ray {int(np.nonzero(bad)[0][0])} needs 0 <= tmin <= tmax; fix the rays")
    return rays


def load_rays(path: str) -> np.ndarray:
    return check_rays(_load_npy(path, "rays"), where=f"rays file {path}")


def check_hits(hits, n=None, where="hits"):
    """Validate a hits array: structured dtype HIT_DTYPE, 1-D, prim >= PRIM_LOWEST, optional ray count n."""
    if not isinstance(hits, np.ndarray) or hits.dtype != HIT_DTYPE:
        raise GoldenError(f"{where}: dtype must be {HIT_DTYPE.descr} (t,prim,u,v), got "
                          f"{getattr(hits, 'dtype', type(hits))}; save hits with that structured dtype")
    if hits.ndim != 1:
        raise GoldenError(f"{where}: must be 1-D (one record per ray), got shape {hits.shape}")
    if n is not None and len(hits) != n:
        raise GoldenError(f"{where}: has {len(hits)} records but there are {n} rays; hits must follow the ray "
                          f"order one to one")
    if len(hits) and hits["prim"].min() < PRIM_LOWEST:
        i = int(np.nonzero(hits["prim"] < PRIM_LOWEST)[0][0])
        raise GoldenError(f"{where}: prim {int(hits['prim'][i])} below {PRIM_LOWEST} (ray {i}); use -1 for a miss, "
                          f"-2 for a memory read error, -3 for a stack overflow, -4 for the step limit")
    return hits


def load_hits(path: str, n=None) -> np.ndarray:
    return check_hits(_load_npy(path, "hits"), n, where=f"hits file {path}")


def check_tris(tris, where="triangles"):
    if not isinstance(tris, np.ndarray) or tris.dtype != np.float32:
        raise GoldenError(f"{where}: dtype must be float32, got {getattr(tris, 'dtype', type(tris))}; "
                          f"export with python -m scenes.export")
    if tris.ndim != 3 or tris.shape[1:] != (3, 3) or len(tris) == 0:
        raise GoldenError(f"{where}: shape must be (T, 3, 3) with T > 0, got {tris.shape}; "
                          f"export with python -m scenes.export")
    if not np.all(np.isfinite(tris)):
        raise GoldenError(f"{where}: NaN or Inf coordinate; re-export the scene")
    return tris


def load_tris(path: str) -> np.ndarray:
    return check_tris(_load_npy(path, "triangles"), where=f"triangles file {path}")


def miss_hits(n: int) -> np.ndarray:
    h = np.zeros(n, dtype=HIT_DTYPE)
    h["t"] = np.inf
    h["prim"] = -1
    return h


def save_npy(path: str, arr: np.ndarray):
    """Save without pickling; the array is written C-contiguous."""
    np.save(path, np.ascontiguousarray(arr), allow_pickle=False)
