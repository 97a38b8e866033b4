"""make paper (dse.paper.paper, dse.paper.report) on synthetic sub-step outputs: fake_make.py stands in for the
sub-makes, so nothing here builds RTL or starts a JVM."""
import os
import sys

import pytest

from dse.paper import facts as P, paper
from dse.paper.report import g
from dse.tests import fake_make
from scenes.errors import UserError

FAKE = f"{sys.executable} {os.path.join(os.path.dirname(__file__), 'fake_make.py')}"
SECTIONS = ("## Table 1", "## Fig 4", "## Figs 5–6", "## Fig 8", "## Fig 9", "## Fig 11", "## Figs 12–13",
            "## Table 2", "## Fig 15", "## Not reproduced", "## How this report was made")


@pytest.fixture
def work(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("FAKE_MAKE_CALLS", str(tmp_path / "calls.txt"))
    monkeypatch.delenv("FAKE_MAKE_FAIL", raising=False)
    for n in ("sponza_dabrovic", "conference"):
        (tmp_path / f"{n}.obj").write_text("v 0 0 0\n")
    return tmp_path


def args(*extra, scenes="sponza_dabrovic.obj conference.obj"):
    return ["--scenes", scenes, "--out", "build/paper", "--version", "v-test", "--tus", "1 8", "--make", FAKE,
            "--machine-gbps", "10", *extra]


def calls(work):
    p = work / "calls.txt"
    return p.read_text().splitlines() if p.exists() else []


def test_report_has_every_section_and_ours_beside_the_papers(work):
    assert paper.main(args()) == 0
    text = (work / "build/paper/report.md").read_text()
    for s in SECTIONS:
        assert s in text, s
    # Table 2: our RTL rays/s in the row that names the paper's FPGA figure for the same scene
    row = next(l for l in text.splitlines() if l.startswith("| sponza_dabrovic | 2.88e5"))
    assert "Sponza 3.04e5" in row
    # ... and at the clock the circuit reaches, which names its source; the run at fmax came after make area
    assert "| 2.99e5 at 156 MHz (proxy) |" in row
    c = calls(work)
    first_area = next(i for i, l in enumerate(c) if l.startswith("area ") and "CONFIG=paper2017" in l)
    assert any(l.startswith("roofline ") and "CLOCK_MHZ=fmax" in l for l in c[first_area:])
    assert "0.95× the paper's FPGA at 32 TUs and 150 MHz (0.98× at the 156 MHz it reaches by proxy)" in text
    # the paper's CPU/GPU/FPGA rows, and conference set beside Kitchen and Classroom
    assert "| paper CPU | 8.70e5 | 1.10e6 | 3.31e5 | 7.64e5 |" in text
    assert any(l.startswith("| conference | 2.88e5 | 2.99e5 at 156 MHz (proxy) | Kitchen 2.60e5 / Classroom 2.52e5")
               for l in text.splitlines())
    # Fig 15: ours per GB/s at 1.2 GB/s, Embree per GB/s at the machine's 10 GB/s, and the paper's ratio
    ours, emb = fake_make.RTL_RAYS_PER_S / 1.2, fake_make.EMBREE_RAYS_PER_S / 10
    assert f"| sponza_dabrovic | {g(ours)} | {g(emb)} | " \
           f"{ours / emb:.1f}× | Sponza {P.fig15_ratio('Sponza'):.1f}× |" in text
    # Fig 8: our node-cache cut (1 / 0.04 = 25x) beside the paper's "up to 28x" for Sponza
    assert "node bytes cut 25.0–25.0× (paper Sponza up to 28×)" in text
    # every difference is explained, and the provenance of each CSV is listed with its version
    assert text.count("Difference") >= 9
    assert "rtaccel=fake-1" in text and "rtaccel **v-test**" in text
    # the PNGs the report links are inside its folder
    for line in text.splitlines():
        if line.startswith("!["):
            assert (work / "build/paper" / line.split("](")[1].rstrip(")")).is_file(), line


def test_rerun_reuses_every_step(work):
    assert paper.main(args()) == 0
    n = len(calls(work))
    assert n == 2 * 9  # per scene: 2 golden frames, nocache, caches, analyze, table2, table2-area, table2-fmax, bench
    assert paper.main(args()) == 0
    assert len(calls(work)) == n
    assert "| reused |" in (work / "build/paper/report.md").read_text()


def test_changed_output_is_rerun(work):
    assert paper.main(args()) == 0
    n = len(calls(work))
    os.utime(work / "build/paper-caches/conference/fig11_miss_rate.csv", ns=(1, 10 ** 19))
    assert paper.main(args()) == 0
    again = calls(work)[n:]
    assert len(again) == 1 and again[0].startswith("paper-caches") and "conference" in again[0]


@pytest.mark.parametrize("target", ["paper-caches", "roofline"])
def test_failed_substep_exits_nonzero_and_leaves_no_report(work, monkeypatch, capsys, target):
    assert paper.main(args()) == 0  # a report from an earlier run ...
    os.utime(work / "conference.obj")  # ... the mesh changes, so every step reruns
    monkeypatch.setenv("FAKE_MAKE_FAIL", target)
    assert paper.main(args()) == 3
    assert not (work / "build/paper/report.md").exists()  # ... is not left looking current
    err = capsys.readouterr().err
    assert "error: make paper:" in err and "no report written" in err


def test_absent_scene_skipped_and_fallback(work, capsys):
    assert paper.main(args(scenes="missing.obj sponza_dabrovic.obj")) == 0
    assert "skip missing.obj (absent)" in capsys.readouterr().err
    assert "skipped (absent): `missing.obj`" in (work / "build/paper/report.md").read_text()
    (work / "room.obj").write_text("v 0 0 0\n")
    assert paper.main(args("--fallback", "room.obj", scenes="nope.obj")) == 0
    assert "`room.obj`" in (work / "build/paper/report.md").read_text()
    with pytest.raises(UserError, match="none of the scenes exists"):
        paper.main(args(scenes="nope.obj"))


def test_empty_tus_and_no_table2_say_which_knob(work):
    a = args("--table2-tus", "0")
    a[a.index("--tus") + 1] = ""
    assert paper.main(a) == 0
    text = (work / "build/paper/report.md").read_text()
    assert "not run (PAPER_TUS is empty)" in text and "not run (PAPER_TABLE2_TUS=0)" in text
    assert not any(c.startswith(("paper-nocache", "roofline", "area")) for c in calls(work))


def test_table2_at_the_papers_clock_only(work):
    assert paper.main(args("--table2-fmax", "0")) == 0
    text = (work / "build/paper/report.md").read_text()
    assert "not run (PAPER_TABLE2_FMAX=0)" in text
    assert not any("CLOCK_MHZ=fmax" in c or c.startswith("area") for c in calls(work))
    assert any(l.startswith("| sponza_dabrovic | 2.88e5 | — |") for l in text.splitlines())
    for s in SECTIONS:
        assert s in text


def test_bad_tus_refused():
    with pytest.raises(UserError, match="PAPER_TUS"):
        paper.tus_list("1 x")
    assert paper.tus_list(" 1 8,16 ") == "1,8,16"


def test_paper_facts_match_the_text():
    # Section 9: "over six times ... Kitchen, five times ... Classroom, nearly eight ... Hairball, over eight ... Sponza"
    r = {n: P.fig15_ratio(n) for n in P.SCENES}
    assert 6 < r["Kitchen"] < 7 and 4.5 < r["Classroom"] < 5.5 and 7.5 < r["Hairball"] < 8 and r["Sponza"] > 8
    assert P.counterpart("sponza_dabrovic") == ("Sponza",) and P.counterpart("conference") == ("Kitchen", "Classroom")
