"""Prints `N passed, N failed, N skipped` over every JUnit XML report (ScalaTest and pytest) under a folder.

CI cannot read sbt's own summary; this line is what it reads. A build that failed before any test could
report is counted by the caller (.ci/run), not here.
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def count(folder: Path):
    passed = failed = skipped = 0
    for f in sorted(folder.rglob("*.xml")):
        root = ET.parse(f).getroot()
        for case in root.iter("testcase"):
            kinds = {child.tag for child in case}
            if kinds & {"failure", "error"}:
                failed += 1
            elif "skipped" in kinds:
                skipped += 1
            else:
                passed += 1
    return passed, failed, skipped


if __name__ == "__main__":
    p, f, s = count(Path(sys.argv[1] if len(sys.argv) > 1 else "build/test-reports"))
    print(f"{p} passed, {f} failed, {s} skipped")
