import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHARED_SCENES = os.environ.get("RTACCEL_SHARED_SCENES", os.path.join(os.path.dirname(ROOT), "shared", "scenes"))


def shared_scene(name):
    """Path of a real scene in shared/scenes, or skip the test with a message when it is absent."""
    p = os.path.join(SHARED_SCENES, name)
    if not os.path.isfile(p):
        pytest.skip(f"real scene {p} not available (set RTACCEL_SHARED_SCENES to the shared/scenes directory)")
    return p


def run_cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, capture_output=True, text=True, timeout=300)
