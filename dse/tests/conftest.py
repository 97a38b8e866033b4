"""One local Ray instance (2 cpus) shared by the dse.explore.explore tests: starting Ray costs seconds, a test
should not pay it each time. dse.explore.pool uses a running instance as it is and leaves it running."""
import os

import pytest

from dse.explore.knobs import ROOT


@pytest.fixture(scope="session")
def local_ray():
    ray = pytest.importorskip("ray")
    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level="ERROR", log_to_driver=False,
             runtime_env={"env_vars": {"PYTHONPATH": ROOT}})
    yield ray
    ray.shutdown()
