"""Where in their roller pitch the wheels start (``PhysicsSim(..., roller_phase=...)``,
``simulate_physics(..., roller_phase=...)``).

Expected values from the geometry of docs/physics.md ("Rollers: the osculating ellipsoid"), not
from the engine: tomasi-omni3's omni wheels have 2 staggered rows of 6 rollers by default, a
hand-over every ``2 pi / 12`` rad of wheel angle; the axle of a wheel resting on the hand-over
(half a pitch from a roller's bottom) stands lower than on a roller's bottom by
``h(0) - h(pi / 12)``, ``h(phi) = c cos(phi) + sqrt(b^2 + (a^2 - b^2) sin^2(phi))`` for rollers
along the drive direction (``gamma = 0``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.errors import InputError  # noqa: E402
from omnikin.physics.engine import PhysicsSim  # noqa: E402
from omnikin.physics.run import simulate_physics  # noqa: E402
from omnikin.plans import parse_plan  # noqa: E402

PITCH = 2.0 * math.pi / (2 * 6)
"""Wheel angle [rad] between two hand-overs of tomasi-omni3's default rollers (2 rows of 6)."""


@pytest.fixture(scope="module")
def tomasi():
    return load_robot("tomasi-omni3")


def joint_angles(sim: PhysicsSim) -> np.ndarray:
    """The wheel joints' angles [rad] in MuJoCo (not zeroed at the start as ``wheel_angles``)."""
    ids = [sim.model.joint(name).qposadr[0] for name in sim.robot.rolling_names]
    return sim.data.qpos[ids].copy()


def test_wheels_start_turned_by_the_phase_times_the_roller_pitch_encoders_at_zero(tomasi):
    phase = [0.1, 0.5, 0.9]
    sim = PhysicsSim(tomasi, start=(1.0, 2.0, 0.3), roller_phase=phase)
    np.testing.assert_allclose(joint_angles(sim), np.array(phase) * PITCH, atol=1e-3)
    assert np.all(sim.encoder_counts() == 0) and np.all(sim.wheel_angles == 0.0)
    np.testing.assert_allclose(sim.pose, [1.0, 2.0, 0.3], atol=1e-12)


def test_a_wheel_on_the_hand_over_stands_lower_by_the_roller_ripple(tomasi):
    rollers = PhysicsSim(tomasi).description.wheels[0].rollers
    a, b, c = rollers.half_length, rollers.radius, rollers.centre_radius

    def h(phi):
        return c * math.cos(phi) + math.sqrt(b * b + (a * a - b * b) * math.sin(phi) ** 2)

    ripple = h(0.0) - h(PITCH / 2)
    heights = {p: PhysicsSim(tomasi, roller_phase=p).height for p in (0.0, 0.5, 0.999)}
    # the contacts sink differently with one roller or two carrying a wheel: within a quarter
    assert heights[0.0] - heights[0.5] == pytest.approx(ripple, rel=0.25)
    assert abs(heights[0.999] - heights[0.0]) < 0.02 * ripple  # one pitch on: where it started


def test_wheels_without_rollers_ignore_the_phase():
    diff = load_robot("diff-drive")
    sim = PhysicsSim(diff, roller_phase=0.7)
    assert np.all(sim.roller_offsets == 0.0)


@pytest.mark.parametrize(
    "phase, named",
    [
        (1.0, "wheel 'w1'"),
        (-0.1, "wheel 'w1'"),
        ([0.1, float("nan"), 0.2], "wheel 'w2'"),
        ([0.1, 0.2, float("inf")], "wheel 'w3'"),
        ([0.1, 0.2], "one number per rolling wheel"),
        ("0.5", "one number per rolling wheel"),
        (None, "one number per rolling wheel"),
        (True, "one number per rolling wheel"),
        ([[0.1, 0.2, 0.3]], "one number per rolling wheel"),
        (list(range(10**5)), "one number per rolling wheel"),
    ],
)
def test_bad_roller_phases_are_refused_in_one_line(tomasi, phase, named):
    with pytest.raises(InputError, match="roller_phase") as info:
        PhysicsSim(tomasi, roller_phase=phase)
    message = str(info.value)
    assert named in message and "\n" not in message and len(message) < 300


def test_simulate_physics_starts_its_wheels_at_the_phase(tomasi):
    plan = parse_plan("line 0.2")
    ends = [simulate_physics(plan, tomasi, tomasi, rate=50.0, roller_phase=p).truth[0, -1] for p in (0.0, 0.5)]
    # another start on the rollers: another end, a few micrometres away
    assert 0.0 < np.linalg.norm(ends[1][:2] - ends[0][:2]) < 1e-3
    with pytest.raises(InputError, match="roller_phase"):
        simulate_physics(plan, tomasi, tomasi, rate=50.0, roller_phase=2.0)


def test_a_four_wheel_base_on_uneven_roller_phases_comes_to_rest():
    # mecanum4's wheels at these phases stand on rollers of different heights: the base rocks
    # down into them for 2.4 s of simulated time (the slowest of 200 draws)
    sim = PhysicsSim(load_robot("mecanum4"), roller_phase=[0.895, 0.272, 0.987, 0.39])
    assert np.linalg.norm(sim.twist) < 1e-3 and sim.tilt < 1e-3
