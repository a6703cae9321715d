"""What every test session shares: the fixtures of the presets and of a recorded bag, the browser
fixtures of the viewer tests, Hypothesis' profile without wall-clock limits, a ROS 2 domain of
this worker's own, and Ctrl-C given back to a suite started in the background. The helpers tests
import are in ``tests/support`` (``support.paths``, ``support.cli``, ``support.kinematics``, ...)."""

from __future__ import annotations

import os
import signal

import pytest
from hypothesis import HealthCheck, settings

from support.browser_fixtures import browser, page, page_log  # noqa: F401  (the viewer tests' fixtures)
from support.cli import run_entry_point
from support.ros_domain import default_domain

# the tests run in parallel (pytest-xdist): a ROS 2 graph of this worker's own, never the user's domain 0;
# tests that start nodes take a domain of their own with support.ros_domain.fresh_domain()
os.environ["ROS_DOMAIN_ID"] = str(default_domain())

# a shell starts a background job (`.ci/run &`, nohup) with Ctrl-C ignored, and an ignored signal stays
# ignored in every process started from it: the commands the signal tests stop with SIGINT would not
# stop. Python's handler, set here, is reset to the default in each child as it starts.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(scope="module")
def line_spin_bag(tmp_path_factory):
    """A bag (``omnikin simulate tomasi-omni3 --path "line 0.5; spin 90" --bag``), one per test
    module that asks for it."""
    path = tmp_path_factory.mktemp("bag") / "run.bag"
    done = run_entry_point("simulate", "tomasi-omni3", "--path", "line 0.5; spin 90", "--bag", path)
    assert done.returncode == 0, done.stderr
    return path


# no wall-clock limits: a loaded CI machine must not fail a test for being slow
settings.register_profile("ci", max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("ci")


@pytest.fixture(scope="session")
def tomasi():
    """tomasi-omni3 (a Robot is immutable: one for the session)."""
    from omnikin import load_robot

    return load_robot("tomasi-omni3")


@pytest.fixture(scope="session")
def synchro():
    """The synchro preset (immutable, one for the session)."""
    from omnikin import load_robot

    return load_robot("synchro")
