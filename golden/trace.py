"""Trace rays against triangles with Embree (embreex). Shared by golden.export and golden.bench.

embreex builds every scene with RTC_SCENE_FLAG_ROBUST and starts every ray at tnear = 0, so rays with a
non-zero tmin cannot be traced exactly: they are rejected. A finite tmax is passed to Embree as tfar.
"""
import numpy as np

from .io import GoldenError, HIT_DTYPE, check_rays, check_tris, miss_hits

SCENE_FLAGS = ["RTC_SCENE_FLAG_ROBUST"]  # set by embreex itself for every EmbreeScene
DEFAULT_BATCH = 1 << 18


def versions() -> dict:
    """embreex package version and the version of the Embree library it bundles (asked from the library
    itself through rtcGetDeviceProperty(RTC_DEVICE_PROPERTY_VERSION)); None where it cannot be found."""
    from importlib.metadata import PackageNotFoundError, version
    out = {"embreex": None, "embree": None}
    try:
        out["embreex"] = version("embreex")
    except PackageNotFoundError:
        pass
    try:
        import ctypes
        import glob
        import os
        import embreex
        libs = sorted(glob.glob(os.path.join(os.path.dirname(os.path.dirname(embreex.__file__)),
                                             "embreex.libs", "libembree*.so*")))
        if libs:
            lib = ctypes.CDLL(libs[0])
            lib.rtcNewDevice.restype = ctypes.c_void_p
            lib.rtcNewDevice.argtypes = [ctypes.c_char_p]
            lib.rtcGetDeviceProperty.restype = ctypes.c_ssize_t
            lib.rtcGetDeviceProperty.argtypes = [ctypes.c_void_p, ctypes.c_int]
            lib.rtcReleaseDevice.argtypes = [ctypes.c_void_p]
            dev = lib.rtcNewDevice(b"threads=1")
            if dev:
                v = int(lib.rtcGetDeviceProperty(dev, 0))  # RTC_DEVICE_PROPERTY_VERSION, e.g. 40400
                lib.rtcReleaseDevice(dev)
                out["embree"] = f"{v // 10000}.{v // 100 % 100}.{v % 100}"
    except Exception:
        pass
    return out


def build_scene(tris: np.ndarray):
    """Create and commit an Embree scene for float32 (T,3,3) triangles: one vertex triple per triangle,
    explicit int32 indices (no vertex sharing or merging), geometry id 0, primitive id = triangle index."""
    from embreex import mesh_construction, rtcore_scene

    check_tris(tris)
    t = len(tris)
    if 3 * t >= 2 ** 31:
        raise GoldenError(f"{t} triangles exceed Embree's 32-bit index range")
    verts = np.ascontiguousarray(tris.reshape(-1, 3), dtype=np.float32)
    idx = np.arange(3 * t, dtype=np.int32).reshape(t, 3)
    scene = rtcore_scene.EmbreeScene()
    mesh = mesh_construction.TriangleMesh(scene, verts, idx)
    # embreex commits the scene on the first run(); do it now so build time is measured here
    scene.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32), output=1)
    return scene, (verts, idx, mesh)


def trace_scene(scene, rays: np.ndarray, batch: int = DEFAULT_BATCH) -> np.ndarray:
    """Closest hits of float32 (N,8) rays in a committed scene, as a HIT_DTYPE array (miss: prim -1, t +inf,
    u = v = 0)."""
    check_rays(rays)
    if np.any(rays[:, 6] != 0):
        raise GoldenError("rays with tmin != 0 cannot be traced with embreex (it fixes tnear = 0); move the "
                          "origin along the ray instead")
    n = len(rays)
    hits = miss_hits(n)
    for s in range(0, n, batch):
        r = rays[s:s + batch]
        o = np.ascontiguousarray(r[:, 0:3])
        d = np.ascontiguousarray(r[:, 3:6])
        far = np.ascontiguousarray(r[:, 7])
        res = scene.run(o, d, dists=far, output=1)
        prim = res["primID"]
        hit = prim >= 0
        h = hits[s:s + batch]
        h["prim"][hit] = prim[hit]
        h["t"][hit] = res["tfar"][hit]
        h["u"][hit] = res["u"][hit]
        h["v"][hit] = res["v"][hit]
    return hits


def occluded(scene, origins, dirs, tfar) -> np.ndarray:
    """Boolean per ray: does anything lie on o + t d for 0 <= t <= tfar (Embree occlusion query)?"""
    res = np.empty(len(origins), dtype=bool)
    for s in range(0, len(origins), DEFAULT_BATCH):
        sl = slice(s, s + DEFAULT_BATCH)
        r = scene.run(np.ascontiguousarray(origins[sl], np.float32), np.ascontiguousarray(dirs[sl], np.float32),
                      dists=np.ascontiguousarray(tfar[sl], np.float32), query="OCCLUDED")
        res[sl] = np.asarray(r) != -1
    return res


def embree_trace(tris: np.ndarray, rays: np.ndarray, batch: int = DEFAULT_BATCH) -> np.ndarray:
    """Build an Embree scene for `tris` and return the closest hits of `rays` (HIT_DTYPE, ray order)."""
    scene, keep = build_scene(tris)
    hits = trace_scene(scene, rays, batch)
    del keep
    return hits
