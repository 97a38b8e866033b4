"""Load a triangle mesh (.obj or .ply) as a float32 (T, 3, 3) array with trimesh.

Contract (other code relies on it):
  * triangle order = face order in the file; a polygon face with vertices v0..vk-1 becomes the fan
    (v0, v1, v2), (v0, v2, v3), ... in that order, in place;
  * no vertex merging, no removal of degenerate, duplicate or unreferenced data (trimesh process=False);
  * multi-object / multi-material OBJ files are concatenated in file order;
  * every problem raises SceneError with one line saying what is wrong and what to change.

trimesh does the parsing. Two things are done before handing an OBJ to it, because trimesh would otherwise
change the order: `usemtl` lines are dropped (trimesh splits the file into one mesh per material run and
returns those runs in reverse order), and polygon face lines are rewritten as fan triangles (trimesh splits a
quad as (0,1,2),(2,3,0), a rotation of the fan). The face lines are also checked for things trimesh accepts
silently: fewer than 3 vertices (skipped), index 0 (read as vertex 1) and relative (negative) indices (resolved
against the end of the file instead of the current vertex).
"""
import hashlib
import io
import os
import re

import numpy as np

from .errors import SceneError

SUPPORTED_EXTENSIONS = (".obj", ".ply")

_FACE_LINE = re.compile(r"^f[ \t]+([^\n]*)$", re.MULTILINE)
_VERTEX_LINE = re.compile(r"^[ \t]*v[ \t]", re.MULTILINE)
_COMMENT_OR_MTL_LINE = re.compile(r"^[ \t]*(?:#|usemtl\b|mtllib\b)[^\n]*$", re.MULTILINE)
# A face-vertex token whose position index is 0 or negative ("0", "-3", "-3/1/2"), at the start of a token.
_BAD_INDEX = re.compile(r"(?:^|(?<=[ \t]))(0+|-\d+)(?=[/ \t]|$)", re.MULTILINE)


def file_sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def bbox(tris: np.ndarray):
    """[[minx,miny,minz],[maxx,maxy,maxz]] of a (T,3,3) array, as Python floats."""
    p = tris.reshape(-1, 3)
    return [p.min(axis=0).astype(float).tolist(), p.max(axis=0).astype(float).tolist()]


def _line_number(text: str, pos: int) -> int:
    return text.count("\n", 0, pos) + 1


def _prepare_obj_text(path: str, text: str):
    """Check face lines, fan-triangulate polygons in place, drop comments/material lines.

    Returns (text for trimesh, expected triangle count)."""
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    text = text.replace("\\\n", "")  # OBJ line continuation
    text = _COMMENT_OR_MTL_LINE.sub("", text)
    matches = list(_FACE_LINE.finditer(text))
    counts = np.fromiter((len(m.group(1).split()) for m in matches), dtype=np.int64, count=len(matches))
    short = np.nonzero(counts < 3)[0]
    if len(short):
        m = matches[short[0]]
        raise SceneError(
            f"{path}: face line {_line_number(text, m.start())} 'f {m.group(1).strip()}' has fewer than 3 "
            f"vertices ({len(short)} such lines); remove or fix those faces"
        )
    bad = _BAD_INDEX.search("\n".join(m.group(1) for m in matches)) if matches else None
    if bad:
        # find the offending line again for the message
        for m in matches:
            if _BAD_INDEX.search(m.group(1)):
                kind = "index 0 (OBJ indices start at 1)" if bad.group(1).strip("0") == "" else \
                    "a relative (negative) index, which is not supported"
                raise SceneError(
                    f"{path}: face line {_line_number(text, m.start())} 'f {m.group(1).strip()}' uses {kind}; "
                    f"re-export the mesh with absolute 1-based vertex indices"
                )
    expected = int(np.sum(counts - 2))
    if np.any(counts > 3):
        def fan(m):
            tok = m.group(1).split()
            if len(tok) == 3:
                return m.group(0)
            return "\n".join(f"f {tok[0]} {tok[i]} {tok[i + 1]}" for i in range(1, len(tok) - 1))
        text = _FACE_LINE.sub(fan, text)
    return text, expected


def _load_obj(path: str):
    import trimesh

    with open(path, "rb") as f:
        raw = f.read()
    text = raw.decode("utf-8", errors="replace")
    text, expected = _prepare_obj_text(path, text)
    if expected == 0:
        raise SceneError(f"{path}: OBJ has no faces ('f' lines); a scene needs at least one triangle")
    if not _VERTEX_LINE.search(text):  # trimesh would return an empty scene: "no triangles" would mislead
        raise SceneError(f"{path}: OBJ has face lines but no vertex ('v') lines, so every face index is out of "
                         f"range; fix or re-export the file")
    try:
        res = trimesh.load(io.BytesIO(text.encode("utf-8")), file_type="obj", process=False, validate=False,
                           maintain_order=True, group_material=False, skip_materials=True)
    except Exception as e:  # trimesh raises ValueError/IndexError/... on bad numbers or indices
        what = "a face index is out of range" if isinstance(e, IndexError) else "cannot parse it"
        raise SceneError(f"{path}: malformed OBJ, {what} ({type(e).__name__}: {e}); fix or re-export the file")
    verts, faces = _mesh_arrays(path, res)
    if len(faces) != expected:
        raise SceneError(f"{path}: malformed OBJ, {expected} triangles expected from its face lines but trimesh "
                         f"read {len(faces)}; check the face lines for non-numeric tokens")
    return verts, faces


def _ply_declared_faces(path: str):
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        raise SceneError(f"{path}: not a PLY file (no 'ply' magic or no 'end_header'); check the file")
    m = re.search(rb"^element[ \t]+face[ \t]+(\d+)", head[:end], re.MULTILINE)
    return int(m.group(1)) if m else 0


def _load_ply(path: str):
    import trimesh

    declared = _ply_declared_faces(path)
    if declared == 0:
        raise SceneError(f"{path}: PLY has no face element; a scene needs at least one triangle")
    try:
        res = trimesh.load(path, file_type="ply", process=False, validate=False, maintain_order=True)
    except Exception as e:
        raise SceneError(f"{path}: malformed PLY ({type(e).__name__}: {e}); fix or re-export the file")
    verts, faces = _mesh_arrays(path, res, allow_polygons=True)
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) != declared:
        raise SceneError(f"{path}: PLY has non-triangle faces, which cannot be loaded in file order; "
                         f"triangulate the mesh or export it as OBJ")
    return verts, faces


def _mesh_arrays(path, res, allow_polygons=False):
    import trimesh

    if isinstance(res, trimesh.Scene):
        geoms = list(res.geometry.values())
        if len(geoms) == 0:
            raise SceneError(f"{path}: no triangles found; a scene needs at least one face")
        if len(geoms) != 1:  # cannot happen with the preprocessing above; refuse rather than guess the order
            raise RuntimeError(f"{path}: trimesh returned {len(geoms)} meshes; loader assumption broken")
        res = geoms[0]
    if not isinstance(res, trimesh.Trimesh):
        raise SceneError(f"{path}: no triangles found (trimesh read a {type(res).__name__}); "
                         f"a scene needs at least one face")
    verts = np.asarray(res.vertices, dtype=np.float64)
    faces = np.asarray(res.faces, dtype=np.int64)
    return verts, faces


def load_triangles(path) -> np.ndarray:
    """Load `path` (.obj or .ply) as a C-contiguous float32 array of shape (T, 3, 3)."""
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in SUPPORTED_EXTENSIONS:
        raise SceneError(f"{path}: unsupported extension '{ext or '(none)'}'; give a .obj or .ply mesh")
    if not os.path.exists(path):
        raise SceneError(f"{path}: no such file; check the scene path")
    if not os.path.isfile(path):
        raise SceneError(f"{path}: not a regular file; give the path of a mesh file")
    verts, faces = _load_obj(path) if ext == ".obj" else _load_ply(path)
    if len(faces) == 0:
        raise SceneError(f"{path}: no triangles found; a scene needs at least one face")
    if faces.min() < 0 or faces.max() >= len(verts):
        raise SceneError(f"{path}: a face index is out of range (0..{len(verts) - 1}); fix the face list")
    tris64 = verts[faces]
    if not np.all(np.isfinite(tris64)):
        bad = int(np.nonzero(~np.isfinite(tris64).reshape(len(faces), -1).all(axis=1))[0][0])
        raise SceneError(f"{path}: triangle {bad} has a NaN or Inf coordinate; remove or fix that vertex")
    with np.errstate(over="ignore"):
        tris = np.ascontiguousarray(tris64.astype(np.float32))
    if not np.all(np.isfinite(tris)):
        bad = int(np.nonzero(~np.isfinite(tris).reshape(len(faces), -1).all(axis=1))[0][0])
        raise SceneError(f"{path}: triangle {bad} has a coordinate beyond the float32 range (|x| > 3.4e38); "
                         f"rescale the scene")
    return tris
