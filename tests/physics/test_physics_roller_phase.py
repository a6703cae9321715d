"""Where in their roller period the wheels start (``PhysicsSim(..., roller_phase=...)``,
``simulate_physics(..., roller_phase=...)``).

Expected values from the geometry of docs/physics.md ("Rollers: the osculating ellipsoid") and
from mirror symmetry, not from the engine: tomasi-omni3's omni wheels have 2 staggered rows of
6 rollers by default, a hand-over every ``2 pi / 12`` rad of wheel angle; with both rows in the
mid-plane the rollers stand as before after one such pitch, with the rows side by side only
after ``2 pi / 6`` (the rows differ by their place on the axle). The axle of a wheel resting on
the hand-over (half a pitch from a roller's bottom) stands lower than on a roller's bottom by
``h(0) - h(pi / 12)``, ``h(phi) = c cos(phi) + sqrt(b^2 + (a^2 - b^2) sin^2(phi))`` for rollers
along the drive direction (``gamma = 0``).

Mirror symmetry: tomasi-omni3 (wheels at 0, 120 and 240 deg) mirrored across its x axis is
itself with wheels 2 and 3 exchanged, each wheel's rollers reflected along its drive direction:
roller angles ``psi -> -psi``, a set each row maps onto itself. A spin of +90 deg with phases
``(p1, p2, p3)`` is thus the mirror image of a spin of -90 deg with phases
``(1 - p1, 1 - p3, 1 - p2)`` (modulo 1): their end headings are opposite, as long as the phase
spans the whole period of the rollers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.errors import InputError  # noqa: E402
from omnikin.io.robot_file import robot_from_dict, robot_to_dict  # noqa: E402
from omnikin.motion.plans import parse_plan  # noqa: E402
from omnikin.physics.run import simulate_physics  # noqa: E402
from omnikin.physics.simulator import PhysicsSim  # noqa: E402

PITCH = 2.0 * math.pi / (2 * 6)
"""Wheel angle [rad] between two hand-overs of tomasi-omni3's default rollers (2 rows of 6)."""


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


def side_by_side(robot, width: float = 0.028):
    """``robot`` with its wheels ``width`` [m] wide: the rows of rollers side by side."""
    doc = robot_to_dict(robot)
    for wheel in doc["wheels"]:
        wheel.setdefault("physical", {})["width"] = width
    return robot_from_dict(doc)


def test_rows_side_by_side_repeat_after_a_whole_roller_spacing_of_a_row(tomasi):
    robot = side_by_side(tomasi)
    sim = PhysicsSim(robot, roller_phase=0.5)
    np.testing.assert_allclose(joint_angles(sim), 2 * PITCH * 0.5, atol=1e-3)
    rollers = sim.description.wheels[0].rollers
    a, b, c = rollers.half_length, rollers.radius, rollers.centre_radius
    ripple = c + b - c * math.cos(PITCH / 2) - math.sqrt(b * b + (a * a - b * b) * math.sin(PITCH / 2) ** 2)
    heights = {p: PhysicsSim(robot, roller_phase=p).height for p in (0.0, 0.25, 0.5)}
    # half the period on: the other row's roller straight below the axle, as high as the first
    assert abs(heights[0.5] - heights[0.0]) < 0.05 * ripple
    # a quarter: the hand-over between the rows, lower by the ripple
    assert heights[0.0] - heights[0.25] == pytest.approx(ripple, rel=0.25)


@pytest.mark.parametrize("layout", ["mid-plane", "side by side"])
def test_a_spin_and_its_mirror_image_end_mirrored(tomasi, layout):
    robot = tomasi if layout == "mid-plane" else side_by_side(tomasi)
    for p1, p2, p3 in np.random.default_rng(3).random((3, 3)):
        left = simulate_physics(parse_plan("spin 90"), robot, robot, rate=50.0, roller_phase=[p1, p2, p3])
        mirrored = [(1.0 - p) % 1.0 for p in (p1, p3, p2)]
        right = simulate_physics(parse_plan("spin -90"), robot, robot, rate=50.0, roller_phase=mirrored)
        (x, y, heading), (xm, ym, heading_m) = left.epsilon[0], right.epsilon[0]
        assert abs(heading + heading_m) < 1e-4  # rad; the headings themselves reach 2e-3
        assert abs(x - xm) < 2e-5 and abs(y + ym) < 2e-5  # m


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
