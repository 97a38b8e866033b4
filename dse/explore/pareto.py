"""Pareto fronts of design points under mixed objectives (maximize rays/s, minimize LUTs, ...)."""
import numpy as np


def _as_max(values, directions):
    """Objective matrix with every column turned into one to maximize."""
    v = np.asarray(values, dtype=float).reshape(len(values), len(directions))
    return v * np.array([1.0 if d == "max" else -1.0 for d in directions])


def front(values, directions):
    """Indices of the non-dominated rows of `values` (one row per point, one column per objective).
    A point is dominated when another is at least as good in every objective and better in one; equal
    points do not dominate each other, so both stay on the front."""
    if len(values) == 0:
        return []
    v = _as_max(values, directions)
    ge = (v[:, None, :] >= v[None, :, :]).all(axis=2)  # ge[j, i]: j at least as good as i everywhere
    gt = (v[:, None, :] > v[None, :, :]).any(axis=2)
    dominated = (ge & gt).any(axis=0)
    return [i for i in range(len(v)) if not dominated[i]]


def ranks(values, directions):
    """Non-dominated sorting: rank 0 = the front, rank 1 = the front of the rest, ..."""
    left, rank, r = list(range(len(values))), [0] * len(values), 0
    while left:
        f = [left[i] for i in front([values[i] for i in left], directions)]
        for i in f:
            rank[i] = r
        left = [i for i in left if i not in set(f)]
        r += 1
    return rank
