"""tools/count_tests.py: the line CI reads, and the failures named on stderr."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

REPORT = """<?xml version="1.0"?>
<testsuites><testsuite name="s">
<testcase classname="rtaccel.top.PlatformSpec" name="bit-exact at 4 TUs"/>
<testcase classname="rtaccel.top.PlatformSpec" name="caches count like the model">
  <failure message="cache counts differ">at PlatformSpec.scala:117</failure></testcase>
<testcase classname="golden.tests.test_x" name="test_scene"><skipped message="no scene"/></testcase>
<testcase classname="golden.tests.test_x" name="test_error"><error message="boom"/></testcase>
</testsuite></testsuites>
"""


def run(folder, *flags):
    return subprocess.run([sys.executable, str(ROOT / "tools" / "count_tests.py"), *flags, str(folder)],
                          capture_output=True, text=True, check=True)


def test_counts_and_names_failures(tmp_path):
    (tmp_path / "scala").mkdir()
    (tmp_path / "scala" / "r.xml").write_text(REPORT)
    quiet = run(tmp_path)
    assert quiet.stdout == "1 passed, 2 failed, 1 skipped\n" and quiet.stderr == ""
    loud = run(tmp_path, "--failures")
    assert loud.stdout == quiet.stdout  # the one line CI parses stays alone on stdout
    assert "FAILED rtaccel.top.PlatformSpec: caches count like the model\n  cache counts differ at PlatformSpec.scala:117" in loud.stderr
    assert "FAILED golden.tests.test_x: test_error\n  boom" in loud.stderr
    assert "bit-exact at 4 TUs" not in loud.stderr and "test_scene" not in loud.stderr
