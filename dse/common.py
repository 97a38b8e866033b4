"""What every dse driver needs from the runs it reads and the files it writes.

Entry points (rtaccel.cli.*, make simulate/cachesim/check) end their stdout with one JSON object line; the
drivers read that line, write CSVs whose first line is `# scene=... config=... rtaccel=...`, and never leave a
half-written file behind.
"""
import json
import sys
from collections.abc import Mapping

from scenes.cli import EXIT_CHECK_FAILED, atomic_file


class NoJsonResult(ValueError):
    """A run's output has no usable JSON result line: the step that prints it failed or was cut short."""


def last_json(text):
    """The last line of `text` that starts with '{', parsed (earlier ones are superseded progress lines)."""
    for line in reversed(text.splitlines()):
        s = line.strip()
        if s.startswith("{"):
            try:
                return json.loads(s)
            except json.JSONDecodeError as e:
                raise NoJsonResult(f"its last JSON line is not valid JSON ({e})")
    raise NoJsonResult("no line starts with '{'")


def last_json_file(path):
    """last_json of a file's text; OSError when the file cannot be read."""
    with open(path) as f:
        return last_json(f.read())


def write_text(path, text):
    with atomic_file(path) as tmp:
        with open(tmp, "w") as f:
            f.write(text)


def save_png(fig, path, dpi=120):
    with atomic_file(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")


def tus_axes(axes, tus=None):
    """The traversal-unit x axis the TU sweeps share: log2 scale, labelled ticks at the swept counts."""
    for ax in axes:
        if tus is None or len(tus) > 1:
            ax.set_xscale("log", base=2)
        if tus is not None:
            ax.set_xticks(tus)
            ax.set_xticklabels([str(int(t)) for t in tus])
        ax.set_xlabel("traversal units")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)


def save_with_footer(fig, path, footer, fontsize=6):
    """Saves `fig` with its provenance lines (which scene, config and version made it) along the bottom."""
    fig.text(0.01, 0.005, "\n".join(footer), fontsize=fontsize, va="bottom")
    fig.tight_layout(rect=(0, 0.02 + 0.02 * len(footer), 1, 1))
    save_png(fig, path)


def _tokens(fields):
    if isinstance(fields, str):
        return fields.split()
    if isinstance(fields, Mapping):
        fields = fields.items()
    return [f"{k}={v}" for k, v in fields]


def provenance_line(scene, config, rtaccel, scene_fields=(), fields=()):
    """`# scene=S <scene_fields> config=C <fields> rtaccel=V` and a newline: scene first and version last, so a
    reader (and parse_provenance) finds them whatever lies between. Fields: "k=v ..." text, a mapping, or
    (k, v) pairs."""
    parts = [f"scene={scene}", *_tokens(scene_fields), f"config={config}", *_tokens(fields), f"rtaccel={rtaccel}"]
    return "# " + " ".join(parts) + "\n"


def parse_provenance(line):
    """{key: value} of the key=value tokens of a provenance line (with or without its '#')."""
    return dict(kv.split("=", 1) for kv in line.lstrip("#").split() if "=" in kv)


def failures_text(result):
    """The "failures" of a run's JSON result as one line."""
    f = result.get("failures")
    return ", ".join(map(str, f)) if isinstance(f, list) and f else "no failures listed"


def exit_check_failed(message):
    """One `error:` line and exit status 3: the run produced its result, but one of its checks failed."""
    print(f"error: {message}", file=sys.stderr)
    raise SystemExit(EXIT_CHECK_FAILED)
