"""golden.image on the procedural fixtures (build/fixtures, `make fixtures`)."""
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from golden import image
from golden.io import HIT_DTYPE
from scenes.tests.helpers import ROOT, run_cli

FIX = Path(os.environ.get("RTACCEL_FIXTURES", os.path.join(ROOT, "build", "fixtures")))
PNG = b"\x89PNG\r\n\x1a\n"


def fixture(name):
    d = FIX / name
    if not (d / "tris.npy").is_file() or not (d / "golden" / "meta.json").is_file():
        pytest.skip(f"fixture {d} absent: run make fixtures (or set RTACCEL_FIXTURES)")
    return d


@pytest.fixture
def cornell(tmp_path):
    """A private copy of the cornell golden directory, so tests may break it."""
    d = fixture("cornell")
    shutil.copytree(d / "golden", tmp_path / "golden")
    return d / "tris.npy", tmp_path / "golden"


def draw(tris, golden, hits, out):
    r = run_cli("golden.image", "--tris", str(tris), "--golden", str(golden), "--hits", str(hits), "--out", str(out))
    return r, (json.loads(r.stdout.strip().splitlines()[-1]) if r.returncode == 0 else None)


def picture(path):
    """The PNG as float RGB (checks it is a real PNG first)."""
    import matplotlib.image

    assert path.read_bytes()[:8] == PNG
    return matplotlib.image.imread(str(path))[..., :3]


def dots(rgb, c):
    """How many dots of the PNG have colour c (the legend's patches have some of every colour)."""
    return int(np.sum(np.all(np.abs(rgb - np.asarray(c)) < 0.02, axis=-1)))


def test_golden_hits_draw_no_differences(cornell, tmp_path):
    tris, golden = cornell
    r, j = draw(tris, golden, golden / "hits.npy", tmp_path / "pics")
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(tmp_path / "pics")) == ["diff.png", "image.png"]
    meta = json.loads((golden / "meta.json").read_text())
    w, h = meta["params"]["width"], meta["params"]["height"]
    assert list(j) == ["image", "diff", "width", "height", "differing_pixels", "classes"]
    assert (j["width"], j["height"], j["differing_pixels"]) == (w, h, 0)
    assert j["classes"]["agree"] == w * h and sum(j["classes"].values()) == w * h
    assert j["image"] == str(tmp_path / "pics" / "image.png") and j["diff"] == str(tmp_path / "pics" / "diff.png")
    img, diff = picture(tmp_path / "pics" / "image.png"), picture(tmp_path / "pics" / "diff.png")
    assert img.shape == diff.shape and img.shape[1] > 4 * w  # drawn large enough to see the pixels
    # fault colours only in the legend's small patches
    assert 0 < dots(img, image.FAULT_RGB[-2]) < dots(img, (0, 0, 0)) / 50
    assert 0 < dots(diff, image.DIFF_RGB["unexplained"]) < dots(diff, image.DIFF_RGB["agree"]) / 50


def test_perturbed_hits_mark_exactly_those_pixels(cornell, tmp_path):
    tris, golden = cornell
    g = np.load(golden / "hits.npy")
    meta = json.loads((golden / "meta.json").read_text())
    w, h = meta["params"]["width"], meta["params"]["height"]
    hits = g.copy()
    hit = np.nonzero(g["prim"][:w * h] >= 0)[0]
    read_err, overflow, missed, limited = hit[:5], hit[40:43], hit[100:104], hit[60:62]
    # a triangle far from every hit point and no camera ray's own prim: a plain wrong answer
    far = int(np.setdiff1d(np.arange(len(np.load(tris))), g["prim"][:w * h])[0])
    wrong = hit[150:152]
    for idx, prim in ((read_err, -2), (overflow, -3), (missed, -1), (limited, -4), (wrong, far)):
        hits["prim"][idx] = prim
        hits["t"][idx] = np.inf if prim < 0 else 1e3
    hits["prim"][w * h:] = -2  # bounce rays are not pixels: their faults must not appear
    hits["t"][w * h:] = np.inf
    np.save(tmp_path / "hits.npy", hits)
    r, j = draw(tris, golden, tmp_path / "hits.npy", tmp_path / "pics")
    assert r.returncode == 0, r.stderr
    changed = np.concatenate([read_err, overflow, missed, limited, wrong])
    assert j["differing_pixels"] == len(changed)
    assert j["classes"]["read_error"] == 5 and j["classes"]["overflow"] == 3 and j["classes"]["step_limit"] == 2
    assert j["classes"]["agree"] == w * h - len(changed)

    img, diff, cls = image.render(np.load(tris), np.load(golden / "rays.npy"), g, hits, w, h)
    assert sorted(np.nonzero(cls.ravel() != "agree")[0]) == sorted(changed)
    assert all(cls.ravel()[read_err] == "read_error") and all(cls.ravel()[overflow] == "overflow")
    flat_img, flat_diff = img.reshape(-1, 3), diff.reshape(-1, 3)
    assert np.all(flat_img[read_err] == image.FAULT_RGB[-2]) and np.all(flat_img[overflow] == image.FAULT_RGB[-3])
    assert np.all(flat_img[missed] == 0) and np.all(flat_img[limited] == image.FAULT_RGB[-4])
    keep = np.setdiff1d(np.arange(w * h), changed)
    assert np.all(flat_diff[keep] == image.DIFF_RGB["agree"])
    assert not np.any(np.all(flat_diff[changed] == image.DIFF_RGB["agree"], axis=1))
    # The PNGs against those of the unperturbed hits (same layout and legend): the extra dots of each colour
    # are the perturbed pixels, 5 read errors : 3 overflows : 6 unexplained (4 misses + 2 wrong prims).
    r, _ = draw(tris, golden, golden / "hits.npy", tmp_path / "base")
    assert r.returncode == 0, r.stderr
    extra = {}
    for name in ("image", "diff"):
        a, b = picture(tmp_path / "pics" / f"{name}.png"), picture(tmp_path / "base" / f"{name}.png")
        for c, rgb in (("read_error", image.FAULT_RGB[-2]), ("overflow", image.FAULT_RGB[-3]),
                       ("unexplained", image.DIFF_RGB["unexplained"])):
            extra[name, c] = dots(a, rgb) - dots(b, rgb)
    px = extra["image", "read_error"] / 5
    assert px > 16  # each pixel is drawn as a block of dots
    assert extra["image", "overflow"] == pytest.approx(3 * px, rel=0.2) and extra["image", "unexplained"] == 0
    for c, k in (("read_error", 5), ("overflow", 3), ("unexplained", 6)):
        assert extra["diff", c] == pytest.approx(k * px, rel=0.2), c


def test_shading_is_cosine_to_the_light():
    tris = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 0], [1, 0, 0], [2, 0, 0]]], np.float32)
    hits = np.zeros(4, HIT_DTYPE)
    hits["prim"] = [0, 1, -1, -3]
    rgb = image.shade(tris, hits)
    lit = image.AMBIENT + (1 - image.AMBIENT) * abs(image.LIGHT[2])
    np.testing.assert_allclose(rgb[0], [lit] * 3)
    np.testing.assert_allclose(rgb[1], [image.AMBIENT] * 3)  # zero-area: no normal, ambient only
    assert list(rgb[2]) == [0, 0, 0] and tuple(rgb[3]) == image.FAULT_RGB[-3]


def test_version_from_environment(monkeypatch):
    monkeypatch.setenv("RTACCEL_VERSION", "v9-test")
    assert image.rtaccel_version() == "v9-test"
    monkeypatch.delenv("RTACCEL_VERSION")
    assert image.rtaccel_version()


def _drop_size(g):
    m = json.loads((g / "meta.json").read_text())
    del m["params"]["width"]
    (g / "meta.json").write_text(json.dumps(m))


def _short_hits(g):
    np.save(g.parent / "hits.npy", np.load(g / "hits.npy")[:-1])


def _low_prim(g):
    h = np.load(g / "hits.npy")
    h["prim"][3] = -5
    np.save(g.parent / "hits.npy", h)


def _no_meta(g):
    (g / "meta.json").unlink()


def _bad_json(g):
    (g / "meta.json").write_text("{not json")


def _inconsistent(g):
    m = json.loads((g / "meta.json").read_text())
    m["params"]["width"] *= 100
    (g / "meta.json").write_text(json.dumps(m))


def _string_size(g):
    m = json.loads((g / "meta.json").read_text())
    m["params"]["height"] = "24"
    (g / "meta.json").write_text(json.dumps(m))


@pytest.mark.parametrize("breakit, words", [
    (_string_size, "params.width/height must be positive integers"),
    (_drop_size, "has no params.width/height: its rays are not from a camera"),
    (_short_hits, "records but there are"),
    (_low_prim, "prim -5 below -4"),
    (_no_meta, "meta.json does not exist"),
    (_bad_json, "meta.json is not JSON"),
    (_inconsistent, "camera rays, but rays.npy has"),
])
def test_bad_inputs_exit_2_and_write_nothing(cornell, tmp_path, breakit, words):
    tris, golden = cornell
    shutil.copy(golden / "hits.npy", tmp_path / "hits.npy")
    breakit(golden)
    r, _ = draw(tris, golden, tmp_path / "hits.npy", tmp_path / "pics")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and words in lines[0], r.stderr
    assert r.stdout == "" and not (tmp_path / "pics").exists()


def test_bad_out_exit_2(cornell, tmp_path):
    tris, golden = cornell
    r, _ = draw(tris, golden, golden / "hits.npy", tmp_path / "missing" / "pics")
    assert r.returncode == 2 and "of --out does not exist" in r.stderr and not (tmp_path / "missing").exists()
    (tmp_path / "file").write_text("x")
    r, _ = draw(tris, golden, golden / "hits.npy", tmp_path / "file")
    assert r.returncode == 2 and "is not a directory" in r.stderr and (tmp_path / "file").read_text() == "x"


def test_failed_second_picture_leaves_nothing(cornell, tmp_path, monkeypatch):
    tris, golden = cornell
    calls = []

    def png(path, *args):
        calls.append(path)
        if len(calls) == 2:
            raise OSError("disk full")
        open(path, "wb").write(PNG)
    monkeypatch.setattr(image, "_png", png)
    with pytest.raises(OSError, match="disk full"):
        image.main(["--tris", str(tris), "--golden", str(golden), "--hits", str(golden / "hits.npy"),
                    "--out", str(tmp_path / "pics")])
    assert len(calls) == 2 and not (tmp_path / "pics").exists()
