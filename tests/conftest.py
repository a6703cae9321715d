"""Shared test helpers: the repository's paths, the environment for omnikin subprocesses, and
wheel layouts built from first principles."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from omnikin import Encoder, Robot, Wheel
from support.browser_fixtures import browser, page, page_log  # noqa: F401  (the viewer tests' fixtures)
from support.cli import run_cli, run_entry_point  # noqa: F401  (re-exported: tests import them from here)
from support.paths import ROOT, SRC, omnikin_env  # noqa: F401  (re-exported: tests import them from here)
from support.ros_domain import default_domain

# the tests run in parallel (pytest-xdist): a ROS 2 graph of this worker's own, never the user's domain 0;
# tests that start nodes take a domain of their own with support.ros_domain.fresh_domain()
os.environ["ROS_DOMAIN_ID"] = str(default_domain())


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


def omni_robot(angles_deg, distance=0.113, radius=0.04125, drive_offsets_deg=None, name="test"):
    """Omni wheels on a circle; drive = CCW tangent (+ optional offsets)."""
    wheels = []
    for i, a in enumerate(angles_deg):
        b = math.radians(a)
        off = math.radians(drive_offsets_deg[i]) if drive_offsets_deg else 0.0
        wheels.append(
            Wheel(f"w{i + 1}", "omni", distance * math.cos(b), distance * math.sin(b), b + math.pi / 2 + off, radius)
        )
    return Robot(name, tuple(wheels))


def circle_wheels(n, distance=0.2, radius=0.05, ticks_per_rev=100):
    """``n`` encoded omni wheels ``w0 .. w{n-1}`` evenly on a circle, driving along the CCW
    tangent (for tests of how checks scale with the wheel count)."""
    step = 2 * math.pi / n
    return tuple(
        Wheel(
            f"w{i}",
            "omni",
            distance * math.cos(i * step),
            distance * math.sin(i * step),
            i * step + math.pi / 2,
            radius,
            encoder=Encoder(ticks_per_rev),
        )
        for i in range(n)
    )


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


def constant_twist_pose(twist, t):
    """Closed-form pose after moving with a constant body twist for time t (from the origin)."""
    vx, vy, w = twist
    if abs(w) < 1e-15:
        return np.array([vx * t, vy * t, 0.0])
    th = w * t
    x = (vx * math.sin(th) - vy * (1 - math.cos(th))) / w
    y = (vx * (1 - math.cos(th)) + vy * math.sin(th)) / w
    return np.array([x, y, (th + math.pi) % (2 * math.pi) - math.pi])


class CountedName(str):
    """A name (column, key, wheel) that counts the comparisons made with it, for tests of linear
    time that count instead of timing (a busy machine changes the time, not the count): a search
    of the whole list per name compares about n^2 / 2 names, a dict, set or Counter about n. Set
    ``counts, budget = [], limit`` before the work: beyond ``limit`` the test fails at once."""

    counts: list = []
    budget = 0  # fail at once beyond it: a quadratic search would take minutes to finish

    def __eq__(self, other):
        CountedName.counts.append(1)
        if len(CountedName.counts) > CountedName.budget:
            pytest.fail(f"more than {CountedName.budget} name comparisons: a search of the whole list per name")
        return str.__eq__(self, other)

    __hash__ = str.__hash__
