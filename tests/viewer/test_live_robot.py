"""The robot behind the viewer: held keys drive it through the runtime's command filter.

Expected motions come from the documented semantics of the filter (the twist ramps towards
the target by ``accel * dt`` per step; the kinematic engine moves at the speed written at a
step until the next one), summed step by step, never from the code under test.
"""

import math
import re

import numpy as np
import pytest

from omnikin.io.robot_file import load_robot
from omnikin.motion.limits import MotionLimits
from omnikin.viewer.live import KEY_SILENCE, LiveRobot
from support.browser import wait_until
from support.kinematics import distance_to_polyline

DT = 0.02
ACCEL = 0.5  # MotionLimits' default linear acceleration [m/s^2]
SPEED = 0.2


def drive(live, steps, on_step=None, start=0):
    snapshot = None
    for k in range(start, start + steps + 1):
        t = k * DT
        if on_step:
            on_step(k, t)
        snapshot, _ = live.step(t)
    return snapshot


def ramp_distance(speed, accel, press_step, release_step, steps):
    """Distance covered when the twist ramps (by accel*DT per step) to ``speed`` from the
    press and back to zero from the release, each step's speed held until the next."""
    v, x = 0.0, 0.0
    for k in range(steps):
        target = speed if press_step <= k < release_step else 0.0
        v = v + max(-accel * DT, min(accel * DT, target - v)) if k > 0 else 0.0
        x += v * DT
    return x


def test_holding_w_drives_forward_as_the_ramped_command_says_and_releasing_stops():
    live = LiveRobot(load_robot("tomasi-omni3"), speed=SPEED, limits=MotionLimits(linear=0.3))

    def keys(k, t):
        if k == 0:
            live.key({"type": "press", "action": "forward"})
        elif k == 50:
            live.key({"type": "release", "action": "forward"})
        elif k % 5 == 0 and k < 50:
            live.key({"type": "alive"})

    s = drive(live, 100, keys)
    expected = ramp_distance(SPEED, ACCEL, 0, 50, 100)
    assert s.truth[0] == pytest.approx(expected, abs=1e-9)
    assert abs(s.truth[1]) < 1e-12 and abs(s.truth[2]) < 1e-12
    assert s.command == (0.0, 0.0, 0.0)


def test_a_held_key_whose_page_falls_silent_is_released():
    live = LiveRobot(load_robot("tomasi-omni3"), speed=SPEED)
    s = drive(live, 100, lambda k, t: live.key({"type": "press", "action": "left"}) if k == 0 else None)
    release = next(k for k in range(101) if k * DT > KEY_SILENCE)
    assert s.truth[1] == pytest.approx(ramp_distance(SPEED, ACCEL, 0, release, 100), abs=1e-9)
    assert s.command == (0.0, 0.0, 0.0)


def test_a_differential_drive_does_not_strafe_but_turns_on_q():
    live = LiveRobot(load_robot("diff-drive"), speed=SPEED, turn=0.5)

    def keys(k, t):
        live.key({"type": "press" if k == 0 else "alive", "action": "left"} if k == 0 else {"type": "alive"})

    s = drive(live, 25, keys)
    assert np.allclose(s.truth, 0.0, atol=1e-12)
    live.key({"type": "release", "action": "left"})
    live.key({"type": "press", "action": "turn_left"})
    for k in range(26, 76):
        live.key({"type": "alive"})
        s, _ = live.step(k * DT)
    assert s.truth[2] > 0.1 and math.hypot(s.truth[0], s.truth[1]) < 1e-9


def test_brackets_steer_the_steerable_wheels_at_rest_and_camera_keys_come_back_as_actions():
    robot = load_robot("ackermann")
    live = LiveRobot(robot)
    live.key({"type": "press", "action": "steer_left"})
    live.key({"type": "press", "action": "camera_top"})
    s, actions = live.step(0.0)
    s, _ = live.step(DT)
    names = [w.name for w in live.description.wheels]
    steered = [names.index(n) for n in robot.steer_names]
    assert actions == ["camera_top"]
    np.testing.assert_allclose(s.steer[steered], math.radians(15.0), atol=1e-12)
    assert np.all(np.isnan(np.delete(s.steer, steered)))


def test_the_page_s_twist_holds_until_stop_and_wheel_angles_follow_the_inverse_kinematics():
    robot = load_robot("tomasi-omni3")
    live = LiveRobot(robot)
    live.set_twist((0.0, 0.0, 0.4))
    s = drive(live, 150)
    assert s.command[2] == pytest.approx(0.4)
    # every wheel of an omni3 turns at omega * L / r at a pure rotation: its angle is the
    # heading turned times L / r
    l_over_r = [math.hypot(w.x, w.y) / w.radius for w in robot.wheels]
    np.testing.assert_allclose(s.wheel_angles, s.truth[2] * np.array(l_over_r), rtol=1e-9)
    live.stop()
    s = drive(live, 60, start=151)
    assert s.command == (0.0, 0.0, 0.0)


def test_rollers_turn_as_the_sideways_slide_of_their_contact_says():
    """Omni wheels (roller angle 0) translating by Y along y: the rim's contact point slides
    along the axle n = (-sin delta, cos delta) by cos(delta) Y, which the roller in contact takes
    up by turning -cos(delta) Y / b (b its radius at the contact, right-hand about its axis)."""
    live = LiveRobot(load_robot("tomasi-omni3"))
    live.set_twist((0.0, 0.15, 0.0))
    s = drive(live, 100)
    live.stop()
    s = drive(live, 40, start=101)
    travelled = s.truth[1]
    assert travelled > 0.1 and abs(s.truth[0]) < 1e-12
    for i, wheel in enumerate(live.description.wheels):
        expected = -math.cos(wheel.drive) * travelled / wheel.rollers.radius
        assert s.roller_angles[i] == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_a_flood_of_inputs_makes_a_bounded_number_of_extra_control_steps():
    from omnikin.viewer.live import MAX_SUBSTEPS

    live = LiveRobot(load_robot("tomasi-omni3"))
    arrivals = iter(np.linspace(0.001, 0.0199, 500))
    live.clock = lambda: float(next(arrivals))
    live.step(0.0)
    steps = live.runtime.steps
    for _ in range(500):
        live.key({"type": "alive"})
    live.step(0.02)
    assert live.runtime.steps - steps <= MAX_SUBSTEPS + 1


def test_one_page_s_heartbeat_does_not_keep_another_page_s_held_key():
    live = LiveRobot(load_robot("tomasi-omni3"))

    def keys(k, t):
        if k == 0:
            live.key({"type": "press", "action": "forward", "source": "a"})  # then page a falls silent
        live.key({"type": "alive", "source": "b"})  # page b is alive and holds nothing

    s = drive(live, 100, keys)
    release = next(k for k in range(101) if k * DT > KEY_SILENCE)
    assert s.truth[0] == pytest.approx(ramp_distance(SPEED, ACCEL, 0, release, 100), abs=1e-9)


def test_a_page_that_closes_releases_its_keys_only():
    live = LiveRobot(load_robot("tomasi-omni3"))
    live.key({"type": "press", "action": "forward", "source": "a"})
    live.key({"type": "press", "action": "turn_left", "source": "b"})
    live.step(0.0)
    live.key({"type": "release_all", "source": "a"})
    s, _ = live.step(DT)
    assert s.target == (0.0, 0.0, live.teleop.turn)


@pytest.mark.parametrize("goal", [(float("nan"), 0.0, 0.0), (1.0, 0.0, float("inf")), ("a", 1, 2), (1.0,)])
def test_a_bad_goal_from_the_page_is_refused_in_one_line_and_the_robot_goes_on(goal):
    live = LiveRobot(load_robot("tomasi-omni3"))
    live.set_twist((0.1, 0.0, 0.0))
    live.step(0.0)
    live.go_to(goal)
    s, _ = live.step(DT)
    assert "a goal is three finite numbers" in live.notice and "\n" not in live.notice
    assert live.seeker is None and s.target == (0.1, 0.0, 0.0)


def test_the_echo_records_each_key_action_at_the_control_step_of_its_arrival():
    """A key arriving between two steps acts from a step at its arrival: the echo gives that time
    and the pose there, and the next step's command is the ramp from it (accel * (t - arrival))."""
    import io

    live = LiveRobot(load_robot("tomasi-omni3"), speed=SPEED)
    live.echo = io.StringIO()
    arrival = {"t": 0.0}
    live.clock = lambda: arrival["t"]
    live.step(0.0)
    live.step(0.02)
    arrival["t"] = 0.027
    live.key({"type": "press", "action": "forward"})
    s, _ = live.step(0.04)
    assert s.command[0] == pytest.approx(ACCEL * (0.04 - 0.027), abs=1e-12)
    arrival["t"] = 0.051
    live.key({"type": "release", "action": "forward"})
    live.step(0.06)
    lines = live.echo.getvalue().splitlines()
    assert lines[0] == "0.027 s  forward  x +0.0000 m  y +0.0000 m  theta +0.0000 rad"
    # from 0.027 to 0.04 at speed 0, then at accel * 0.013 until the release at 0.051
    x = ACCEL * 0.013 * (0.051 - 0.04)
    found = re.fullmatch(r"0\.051 s  release  x (\S+) m  y (\S+) m  theta (\S+) rad", lines[1])
    assert found, lines[1]
    assert tuple(float(v) for v in found.groups()) == pytest.approx((x, 0.0, 0.0), abs=1e-4)
    assert [e["key"] for e in live.events] == ["forward", "release"]
    assert [e["t"] for e in live.events] == [0.027, 0.051]


def test_a_loop_that_runs_late_drives_as_one_that_steps_every_control_period():
    """Steps every 0.02 s and one step over a 1 s stall give the same motion: the stall's steps are
    made up in simulated time (the ramp of ``ramp_distance``, summed step by step)."""
    live = LiveRobot(load_robot("tomasi-omni3"), speed=SPEED)
    live.step(0.0)
    live.key({"type": "press", "action": "forward"})
    live.step(0.02)  # the ramp from step 0 (dt 0.02), as ramp_distance with the press at step 0
    s, _ = live.step(1.02)  # a stall of 1 s (50 control periods)
    assert s.truth[0] == pytest.approx(ramp_distance(SPEED, ACCEL, 0, 10**6, 51), abs=1e-9)


def planned(live, start: int = 0) -> None:
    """Hand the page's path to the planning thread (one control step at ``start``) and wait until
    it is planned: the control steps after this one begin it."""
    live.step(start * DT)
    wait_until(lambda: not live.planning, "the path planned")


def test_a_path_followed_from_the_page_ends_on_its_last_waypoint_without_leaving_the_segments():
    live = LiveRobot(load_robot("omni4"))
    corners = [(0.0, 0.0), (0.5, 0.0), (0.5, 0.5)]
    live.follow(corners[1:], smooth=False, heading="fixed")  # from the robot at the origin
    planned(live)
    truth = []
    drive(live, 1000, lambda k, t: truth.append(live.backend.truth.copy()) if k else None)
    assert live.follower.state == "done" and live.notice == ""
    truth = np.array(truth)
    assert truth[-1] == pytest.approx([0.5, 0.5, 0.0], abs=1e-6)
    assert distance_to_polyline(truth[:, :2], corners).max() < 1e-4


def test_a_key_stops_the_path_followed_and_a_path_that_goes_nowhere_is_refused_in_one_line():
    live = LiveRobot(load_robot("omni4"))
    live.follow([(2.0, 0.0)])
    planned(live)
    drive(live, 50)
    assert live.follower.following
    drive(live, 2, lambda k, t: live.key({"type": "press", "action": "left"}) if k == 51 else None, start=51)
    assert live.follower.state == "stopped" and live.follower.note == "a key took over"
    live.follow([(live.pose[0] + 0.0002, live.pose[1])])
    planned(live, start=54)
    drive(live, 1, start=55)
    assert live.follower.state == "refused"
    nowhere = r"path 'plan': it does not go anywhere \(every waypoint within 1 mm of the robot\)"
    assert re.fullmatch(nowhere, live.notice)
