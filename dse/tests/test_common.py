"""dse.common: the JSON result line, provenance lines, atomic writes."""
import os

import pytest

from dse import common


def test_last_json_takes_the_last_object_line():
    text = '[progress] {"not": "this"}\n{"a": 1}\nlog\n  {"a": 2, "b": [1]}  \ntrailing text\n'
    assert common.last_json(text) == {"a": 2, "b": [1]}


@pytest.mark.parametrize("text, words", [
    ("", "no line starts with '{'"),
    ("only\nlogs\n", "no line starts with '{'"),
    ('{"a": 1}\n{"cut short', "not valid JSON"),  # an earlier line must not stand in for a broken last one
])
def test_last_json_refuses_missing_or_broken_lines(text, words):
    with pytest.raises(common.NoJsonResult, match=words):
        common.last_json(text)


def test_last_json_file(tmp_path):
    (tmp_path / "r.log").write_text('x\n{"ok": true}\n')
    assert common.last_json_file(tmp_path / "r.log") == {"ok": True}
    with pytest.raises(OSError):
        common.last_json_file(tmp_path / "missing.log")


def test_provenance_line_order_and_forms():
    line = common.provenance_line("/s/a b.obj", "fit", "v1", scene_fields="rays=9  golden=8x6",
                                  fields={"M": 4, "node_cache": "8192x1-dm"})
    assert line == "# scene=/s/a b.obj rays=9 golden=8x6 config=fit M=4 node_cache=8192x1-dm rtaccel=v1\n"
    line = common.provenance_line("s", "c", "v", fields=[("k", 1), ("j", 2)])
    assert line == "# scene=s config=c k=1 j=2 rtaccel=v\n"
    line = common.provenance_line("s", "c", "v", fields="tus=1 miss_rate")
    assert line == "# scene=s config=c tus=1 miss_rate rtaccel=v\n"
    assert common.parse_provenance(common.provenance_line("s.obj", "fit", "v2", fields="x=a=b flag")) == {
        "scene": "s.obj", "config": "fit", "x": "a=b", "rtaccel": "v2"}


def test_write_text_is_atomic(tmp_path):
    p = tmp_path / "t.csv"
    common.write_text(str(p), "a\n")
    assert p.read_text() == "a\n"
    with pytest.raises(TypeError):  # a write that fails keeps the old file and leaves no temporary
        common.write_text(str(p), None)
    assert p.read_text() == "a\n" and os.listdir(tmp_path) == ["t.csv"]


def test_failures_text_and_exit(capsys):
    assert common.failures_text({"failures": ["a=1", "b=2"]}) == "a=1, b=2"
    assert common.failures_text({"ok": False}) == "no failures listed"
    with pytest.raises(SystemExit) as e:
        common.exit_check_failed("it failed")
    assert e.value.code == 3 and capsys.readouterr().err == "error: it failed\n"
