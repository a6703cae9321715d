"""Tracking in the kinematic engine on an exact model: the error is that of the control rate
alone, the chord bound of a held command (closed form), checked at every tick and between ticks."""

from __future__ import annotations

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.control import PoseFeedback, WheelLimits, circle, figure8, plan_trajectory
from omnikin.evaluation.tracking import track, tracking_errors
from support.paths import ROOT

LIMITS = WheelLimits(speed=12.0, accel=40.0)


@pytest.fixture(scope="module")
def dc_tomasi(tmp_path_factory):
    """tomasi-omni3 with DC motors: its encoders read the wheels the engine turned, so the
    odometry is exact and the only error left is the controller's."""
    text = (ROOT / "src/omnikin/presets/tomasi-omni3.yaml").read_text()
    assert text.count("motor: stepper") == 3
    path = tmp_path_factory.mktemp("robot") / "dc.yaml"
    path.write_text(text.replace("motor: stepper", "motor: dc"))
    return load_robot(path)


class HeldEvery:
    """A controller asked only every ``every``-th tick, its twist held in between: the truth is
    then sampled ``every`` times per control period."""

    def __init__(self, inner, every: int):
        self.inner, self.every, self.calls, self.last = inner, every, 0, np.zeros(3)
        self.name = inner.name

    def command(self, t, pose):
        if self.calls % self.every == 0:
            self.last = self.inner.command(t, pose)
        self.calls += 1
        return self.last


def control_rate_bound(trajectory, rate: float) -> float:
    """``(a + v omega) dt^2 / 8`` [m]: how far a curve with acceleration ``a`` can be from the
    constant-twist arc (acceleration ``v omega``) that joins its positions ``dt = 1 / rate``
    apart (both vanish at the ends, their difference's second derivative is at most the sum);
    ``a``, ``v``, ``omega`` by finite differences of the reference's poses."""
    dt = 1e-3
    pose = trajectory.at(np.arange(0.0, trajectory.duration, dt))[0]
    accel = np.max(np.hypot(*(np.diff(pose[:, :2], 2, axis=0) / dt**2).T))
    speed = np.hypot(*(np.diff(pose[:, :2], axis=0) / dt).T)
    turn = np.abs(np.diff(np.unwrap(pose[:, 2])) / dt)
    return (accel + np.max(speed * turn)) / rate**2 / 8.0


@pytest.mark.parametrize("gain", [1.0, 0.5])
def test_at_the_ticks_the_robot_is_within_the_control_rate_bound_of_the_reference(dc_tomasi, gain):
    trajectory = plan_trajectory(dc_tomasi, figure8(1.0, heading="tangent"), LIMITS)
    run = track(dc_tomasi, trajectory, PoseFeedback(dc_tomasi, trajectory, rate=50, gain=gain), rate=50)
    gap = np.hypot(*(run.truth[:, :2] - run.reference[:, :2]).T)
    assert gap.max() <= control_rate_bound(trajectory, 50.0)
    assert tracking_errors(run, trajectory)["rms_heading_error_rad"] < 1e-3


@pytest.mark.parametrize(("path", "chord"), [(circle(0.5), True), (figure8(1.0, heading="tangent"), False)])
def test_between_ticks_the_error_is_within_the_control_rate_bound(dc_tomasi, path, chord):
    rate, every = 20.0, 10
    trajectory = plan_trajectory(dc_tomasi, path, LIMITS)
    inner = PoseFeedback(dc_tomasi, trajectory, rate=rate, gain=1.0)
    run = track(dc_tomasi, trajectory, HeldEvery(inner, every), rate=rate * every)
    bound = control_rate_bound(trajectory, rate)  # at a fixed heading (chord) omega = 0: a dt^2 / 8
    gap = np.hypot(*(run.truth[:, :2] - run.reference[:, :2]).T)
    assert gap.max() <= bound * 1.05
    if chord:
        assert gap.max() >= bound * 0.3  # the bound is the error's size, not a loose ceiling
    assert tracking_errors(run, trajectory)["max_error_m"] <= bound * 1.05
