"""python -m scenes.export SCENE OUT.npy

Writes the scene's triangles as a float32 (T,3,3) C-order .npy and a sidecar OUT.json
{"scene": absolute path, "sha256": of the mesh file, "triangles": T, "bbox": [[min xyz], [max xyz]]}.
On error: `error: <message>` on stderr, exit 2, nothing written (files are renamed into place at the end).
"""
import json
import os

import numpy as np

from .cli import ArgParser, atomic_file, run
from .errors import UserError
from .load import bbox, file_sha256, load_triangles


def sidecar_path(out_npy: str) -> str:
    base = out_npy[:-4] if out_npy.endswith(".npy") else out_npy
    return base + ".json"


def main(argv=None):
    ap = ArgParser(prog="python -m scenes.export", description="Export a mesh as a float32 (T,3,3) .npy array.")
    ap.add_argument("scene", help="mesh file (.obj or .ply)")
    ap.add_argument("out", help="output .npy path (a sidecar .json is written beside it)")
    a = ap.parse_args(argv)
    if not a.out.endswith(".npy"):
        raise UserError(f"output '{a.out}' must end in .npy")
    tris = load_triangles(a.scene)
    meta = {"scene": os.path.abspath(a.scene), "sha256": file_sha256(a.scene), "triangles": int(len(tris)),
            "bbox": bbox(tris)}
    js = sidecar_path(a.out)
    with atomic_file(a.out, suffix=".npy") as tmp_npy, atomic_file(js, suffix=".json") as tmp_js:
        np.save(tmp_npy, np.ascontiguousarray(tris, dtype=np.float32))
        with open(tmp_js, "w") as f:
            json.dump(meta, f, indent=1)
            f.write("\n")
    return 0


if __name__ == "__main__":
    run(main)
