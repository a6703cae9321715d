"""Headings and steering angles given to the robot model are bounded like robot-file angles:
real, finite, a heading at most MAX_ANGLE = 1e6 rad in size, a steering angle within its
wheel's limits (a wheel that turns all the way round: any angle up to 1e6 rad). Refused with one
line naming the argument, the wheel and the limits (docs/conventions.md, "Angles")."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from omnikin import InputError, load_robot
from omnikin.kinematics.se2 import MAX_ANGLE
from support.cli import run_entry_point

LIMIT = math.radians(35.0)  # ackermann: both front wheels steer within -35 .. 35 deg


@pytest.fixture(scope="module")
def ackermann():
    return load_robot("ackermann")


@pytest.mark.parametrize("heading", [1e308, -1e308, MAX_ANGLE * (1 + 1e-12), 1e20])
def test_absurd_headings_are_refused(tomasi, heading):
    for call in (
        lambda: tomasi.ik([1.0, 0.0, 0.0], heading=heading),
        lambda: tomasi.body_twist([1.0, 0.0, 0.0], heading),
        lambda: tomasi.ik([[1.0, 0.0, 0.0]] * 2, heading=[0.0, heading]),
    ):
        with pytest.raises(InputError, match=r"^heading.*: .* rad is beyond \+-1e\+06 rad") as info:
            call()
        assert "\n" not in str(info.value)


@pytest.mark.parametrize("heading", [math.nan, math.inf])
def test_non_finite_headings_are_refused(tomasi, heading):
    with pytest.raises(InputError, match=r"^heading: non-finite value"):
        tomasi.ik([1.0, 0.0, 0.0], heading=heading)


def test_large_unwrapped_headings_within_the_bound_work(tomasi):
    """An unwrapped heading of many turns is the same heading: world (1, 0) at heading
    theta is body (cos theta, -sin theta) (rotation by -theta)."""
    theta = 1000 * 2 * math.pi + 0.3
    body = tomasi.body_twist([1.0, 0.0, 0.5], theta)
    np.testing.assert_allclose(body, [math.cos(0.3), -math.sin(0.3), 0.5], atol=1e-12)
    np.testing.assert_allclose(
        tomasi.ik([1.0, 0.0, 0.5], heading=MAX_ANGLE).wheel_speeds,
        tomasi.ik([math.cos(MAX_ANGLE), -math.sin(MAX_ANGLE), 0.5]).wheel_speeds,
        rtol=1e-12,
    )


@pytest.mark.parametrize(
    "steer, wheel",
    [
        ([1e20, 0.0], "front_left"),
        ([math.radians(90), math.radians(90)], "front_left"),
        ([0.0, -math.radians(36)], "front_right"),
        ([LIMIT + 1e-6, 0.0], "front_left"),
    ],
)
def test_steering_outside_the_wheel_limits_is_refused(ackermann, steer, wheel):
    speeds = [1.0, 1.0, 1.0, 1.0]
    for name, call in (
        ("steer", lambda: ackermann.fk(speeds, steer=steer)),
        ("steer", lambda: ackermann.jacobian(steer)),
        ("steer", lambda: ackermann.fk_matrix(steer)),
        ("steer", lambda: ackermann.fk_rows(steer)),
        ("steer", lambda: ackermann.fk_rank(steer)),
    ):
        with pytest.raises(InputError) as info:
            call()
        message = str(info.value)
        assert (
            message.startswith(f"{name}: wheel {wheel!r} steered to ") and "outside its limits [-35, 35] deg" in message
        )
        assert "\n" not in message


def test_a_steering_hint_is_a_preference_not_checked_against_the_limits(ackermann):
    # the hint only picks the branch; beyond the limits the wheel takes the one within them.
    # Front wheels of a turn to the left (omega > 0): both steer positive, within +-35 deg.
    twist = [0.2, 0.0, 0.1]
    expected = ackermann.ik(twist).steer_angles
    for hint in ([math.radians(90), math.radians(90)], [0.0, -math.radians(36)], [LIMIT + 1e-6, 0.0]):
        np.testing.assert_allclose(ackermann.ik(twist, steer_hint=hint).steer_angles, expected)
    with pytest.raises(InputError, match=r"^steer_hint: wheel 'front_left' steered to .* beyond"):
        ackermann.ik(twist, steer_hint=[1e20, 0.0])  # not an angle at all: refused


def test_steering_at_the_limits_is_accepted(ackermann):
    """At +35 deg on both front wheels with the rear wheels still: forward kinematics of the
    least-squares fit; at the limit exactly, nothing is refused (the bound is inclusive)."""
    res = ackermann.fk([1.0, 1.0, 1.0, 1.0], steer=[LIMIT, -LIMIT])
    assert np.all(np.isfinite(res.twist))
    ackermann.fk([1.0, 1.0, 1.0, 1.0], steer=np.radians([35.0, -35.0]))


def test_steering_of_a_stack_names_the_sample(ackermann):
    steer = np.zeros((5, 2))
    steer[3, 1] = 2.0
    with pytest.raises(InputError, match=r"^steer at index \(3,\): wheel 'front_right' steered to 2 rad"):
        ackermann.fk(np.ones((5, 4)), steer=steer)


def test_wheels_that_turn_all_the_way_round_accept_any_orientation_up_to_the_bound():
    """villasenor-omni3's legs steer without limits: 193 deg is the orientation -167 deg (the
    interval steering of odometry crosses +-180 deg) and gives the same matrix."""
    v = load_robot("villasenor-omni3")
    a = np.radians([193.0, 0.0, -400.0])
    b = np.radians([193.0 - 360.0, 0.0, -400.0 + 360.0])
    np.testing.assert_allclose(v.jacobian(a), v.jacobian(b), atol=1e-12)
    with pytest.raises(InputError, match=r"^steer: wheel 'leg2' steered to 1e\+07 rad .* beyond \+-1e\+06 rad"):
        v.jacobian([0.0, 1e7, 0.0])


@pytest.mark.parametrize(
    "argv, contains",
    [
        (["ik", "tomasi-omni3", "1", "0", "0", "--heading", "1e308"], "heading: 1e+308 rad is beyond"),
        (["fk", "ackermann", "1", "1", "1", "1", "--steer-deg", "1e20", "0"], "outside its limits [-35, 35] deg"),
        (["fk", "ackermann", "1", "1", "1", "1", "--steer-deg", "90", "90"], "(90 deg), outside its limits"),
    ],
)
def test_command_line_refuses_absurd_angles(argv, contains):
    proc = run_entry_point(*argv, timeout=60)
    assert proc.returncode == 2 and proc.stdout == ""
    assert contains in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr


def test_steering_limits_are_public_in_radians_and_read_only(ackermann):
    """Robot.steer_limits: the file's -35 .. 35 deg in radians for ackermann's front wheels,
    -inf .. inf for villasenor-omni3's legs, which turn all the way round; the robot keeps
    them, so a caller cannot change them (nor what the model then accepts)."""
    lower, upper = ackermann.steer_limits
    np.testing.assert_allclose(lower, [-LIMIT, -LIMIT], rtol=1e-15)
    np.testing.assert_allclose(upper, [LIMIT, LIMIT], rtol=1e-15)
    with pytest.raises(ValueError, match="read-only"):
        upper[0] = math.pi
    lower, upper = load_robot("villasenor-omni3").steer_limits
    assert lower.tolist() == [-math.inf] * 3 and upper.tolist() == [math.inf] * 3


def test_no_module_reaches_into_the_private_members_of_a_robot():
    """Other modules use Robot's public interface: no ``robot._steer_limits`` (whose caching or
    meaning may change with the model) outside omnikin/kinematics/robot.py."""
    import ast

    from support.paths import SRC

    package = Path(SRC) / "omnikin"
    model = ast.parse((package / "kinematics" / "robot.py").read_text(encoding="utf-8"))
    robot = next(n for n in model.body if isinstance(n, ast.ClassDef) and n.name == "Robot")
    private = {
        name
        for n in ast.walk(robot)
        for name in (
            [n.name]
            if isinstance(n, ast.FunctionDef)
            else [t.id for t in n.targets if isinstance(t, ast.Name)]
            if isinstance(n, ast.Assign)
            else []
        )
        if name.startswith("_") and not name.startswith("__")
    }
    assert {"_steer_array", "_fk_rows"} <= private
    reached = [
        f"{path.relative_to(package)}:{n.lineno}: {ast.unparse(n)}"
        for path in sorted(package.rglob("*.py"))
        if path != package / "kinematics" / "robot.py"
        for n in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(n, ast.Attribute)
        and n.attr in private
        and not (isinstance(n.value, ast.Name) and n.value.id in ("self", "cls"))
    ]
    assert reached == []
