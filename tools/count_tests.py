"""Prints `N passed, N failed, N skipped` over every JUnit XML report (ScalaTest and pytest) under a folder.

CI cannot read sbt's own summary; this line is what it reads. A build that failed before any test could
report is counted by the caller (.ci/run), not here.

`--failures` first names each failed test with the start of its message, on stderr: a CI log keeps only its tail,
and sbt's own report of a failure is far above it.
"""
import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

MESSAGE_CHARS = 1200


def cases(folder: Path):
    for f in sorted(folder.rglob("*.xml")):
        for case in ET.parse(f).getroot().iter("testcase"):
            yield case


def count(folder: Path):
    passed = failed = skipped = 0
    for case in cases(folder):
        kinds = {child.tag for child in case}
        if kinds & {"failure", "error"}:
            failed += 1
        elif "skipped" in kinds:
            skipped += 1
        else:
            passed += 1
    return passed, failed, skipped


def failures(folder: Path):
    """(test, the start of its message) for each failed test."""
    for case in cases(folder):
        for child in case:
            if child.tag in ("failure", "error"):
                text = " ".join(((child.get("message") or "") + " " + (child.text or "")).split())
                yield f"{case.get('classname', '')}: {case.get('name', '')}", text[:MESSAGE_CHARS]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default="build/test-reports", type=Path)
    ap.add_argument("--failures", action="store_true", help="name each failed test and its message on stderr first")
    a = ap.parse_args()
    if a.failures:
        for name, text in failures(a.folder):
            print(f"FAILED {name}\n  {text}", file=sys.stderr)
    p, f, s = count(a.folder)
    print(f"{p} passed, {f} failed, {s} skipped")
