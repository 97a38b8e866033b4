"""Shared command-line plumbing: one `error: ...` line on stderr and exit code 2 for every user error."""
import argparse
import os
import shutil
import sys
import tempfile
from contextlib import contextmanager

from .errors import UserError

EXIT_USER_ERROR = 2
# "ran, but a check failed": the run's outputs and JSON line exist, but are not a result to use.
EXIT_CHECK_FAILED = 3


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


class ArgParser(argparse.ArgumentParser):
    """argparse that reports bad arguments as a single `error: ...` line (exit 2) instead of usage + message."""

    def error(self, message):  # noqa: D401 - argparse API
        raise UserError(f"{self.prog}: {message} (see --help)")


def run(main, argv=None):
    """Run `main(argv)`; turn UserError and OSError into `error: ...` on stderr and exit code 2."""
    try:
        rc = main(argv)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(EXIT_USER_ERROR)
    except OSError as e:
        print(f"error: {' '.join(str(e).split())}", file=sys.stderr)
        sys.exit(EXIT_USER_ERROR)
    sys.exit(rc or 0)


@contextmanager
def atomic_file(path, suffix=""):
    """Yield a temporary path next to `path`; rename it to `path` only if the block succeeds."""
    path = os.path.abspath(path)
    d = os.path.dirname(path)
    if not os.path.isdir(d):
        raise UserError(f"output directory {d} does not exist; create it first")
    fd, tmp = tempfile.mkstemp(prefix=".tmp-" + os.path.basename(path) + "-", suffix=suffix, dir=d)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


@contextmanager
def atomic_dir(path):
    """Yield a temporary directory next to `path`; on success replace `path` with it (nothing half-written)."""
    path = os.path.abspath(path.rstrip("/") or "/")
    parent = os.path.dirname(path)
    if not os.path.isdir(parent):
        raise UserError(f"parent directory {parent} of the output does not exist; create it first")
    if os.path.exists(path) and not os.path.isdir(path):
        raise UserError(f"output {path} exists and is not a directory; choose another --out")
    tmp = tempfile.mkdtemp(prefix=".tmp-" + os.path.basename(path) + "-", dir=parent)
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask())
        if os.path.isdir(path):
            old = tempfile.mkdtemp(prefix=".old-" + os.path.basename(path) + "-", dir=parent)
            os.rmdir(old)
            os.replace(path, old)
            os.replace(tmp, path)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, path)
    finally:
        if os.path.isdir(tmp):
            shutil.rmtree(tmp, ignore_errors=True)
