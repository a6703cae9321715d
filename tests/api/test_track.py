"""``omnikin.track``: the robot starts on the path's first pose and its run comes back in the
path's frame; the summary's numbers against closed forms; refusals in one line before anything
is driven."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnikin
from omnikin.control import polyline
from omnikin.errors import InputError, ResourceLimitError


def test_a_path_away_from_the_origin_is_driven_from_its_first_pose_and_reported_in_its_frame(tmp_path):
    f = tmp_path / "up.csv"
    f.write_text("x,y\n5,2\n5,3\n")  # one metre north, far from the origin: tangent heading +90 deg
    done = omnikin.track("tomasi-omni3", f)
    run = done.run
    assert run.truth[0] == pytest.approx([5.0, 2.0, math.pi / 2], abs=1e-12)
    assert run.reference[0] == pytest.approx([5.0, 2.0, math.pi / 2], abs=1e-12)
    assert run.reference[-1] == pytest.approx([5.0, 3.0, math.pi / 2], abs=1e-9)
    assert run.truth[-1, :2] == pytest.approx([5.0, 3.0], abs=1e-4)
    assert np.max(np.abs(run.truth[:, 0] - 5.0)) < 1e-4  # on the line x = 5 all along


def test_a_straight_line_takes_the_time_of_its_speed_and_acceleration_limits():
    # along body x at a fixed heading every wheel speed is J[:, 0] v: the fastest wheel binds, so
    # the line is a trapezoid of top speed W / max|J[:, 0]| and acceleration A / max|J[:, 0]|
    robot = omnikin.load_robot("tomasi-omni3")
    per_speed = float(np.max(np.abs(robot.ik_matrix[:, 0])))
    speed, accel = 6.0, 20.0
    v, a, length = speed / per_speed, accel / per_speed, 2.0
    expected = length / v + v / a if v * v / a < length else 2 * math.sqrt(length / a)
    path = polyline([(0.0, 0.0), (length, 0.0)], heading="fixed")
    done = omnikin.track(robot, path, max_wheel_speed=speed, max_wheel_accel=accel)
    summary = done.summary()
    assert summary["duration_s"] == pytest.approx(expected, rel=2e-3)
    assert summary["path_length_m"] == pytest.approx(length, rel=1e-12)
    assert summary["max_wheel_speed_rad_s"] <= speed * (1 + 1e-9)
    # an exact model at 50 Hz: the truth leaves the straight line by rounding only
    assert summary["max_error_m"] < 1e-9
    assert summary["rms_heading_error_rad"] < 1e-9
    assert summary["samples"] == math.floor((expected + 1.0) * 50 + 1e-6) + 1
    assert set(summary["solve_time_ms"]) == {"p50", "p95", "max"}


def test_the_estimate_is_told_before_the_run_and_a_run_beyond_the_budget_is_refused():
    told = []
    with pytest.raises(ResourceLimitError, match=r"track: about .* s for \d+ control ticks, more than max_time 0.001"):
        omnikin.track("tomasi-omni3", "circle 1", max_time=1e-3, on_cost=told.append)
    (cost,) = told
    # ticks: the reference's duration and the one second of settling at 50 Hz
    duration = omnikin.track("tomasi-omni3", "circle 1").trajectory.duration
    assert cost.ticks == math.floor((duration + 1.0) * 50) + 1
    assert cost.step is None
    # a wheel limit a billion times too low makes a run of years: refused, not started
    with pytest.raises(ResourceLimitError, match=r"raise max_wheel_speed"):
        omnikin.track("tomasi-omni3", "circle 1", max_wheel_speed=1e-8, max_wheel_accel=1e-8)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"controller": "pid"}, r"controller must be one of feedback, mpc, pursuit, got 'pid'"),
        ({"seed": -1}, r"seed must be a whole number >= 0"),
        ({"rate": 0}, r"rate must be in \(0, 10000\] Hz"),
        ({"max_wheel_speed": -1}, r"max_wheel_speed \(--max-wheel-speed\) must be a finite number > 0, got -1"),
        ({"heading": "sideways"}, r"unknown heading 'sideways'"),
        ({"blend": 0.2}, r"blend is for path files"),
        ({"engine": "physics", "noise": "typical"}, r"the physics engine has no random error model"),
        ({"on_cost": 5}, r"on_cost must be a function"),
        ({"rate": float("nan")}, r"rate must be in \(0, 10000\] Hz"),
        ({"rate": "50"}, r"rate must be in \(0, 10000\] Hz"),
        ({"rate": 0.1}, r"rate \(--rate\) 0.1 Hz gives 2 control tick\(s\) over the"),
        ({"settle": float("nan")}, r"settle must be in \[0, 3600\] s"),
        ({"heading": [0]}, r"heading must be one of \['tangent', 'fixed', 'free'\] or an angle"),
        ({"heading": True}, r"heading must be one of"),
        ({"engine": "physics", "rate": 300}, r"rate \(--rate\) 300 Hz: its period 3.333 ms is not a whole number"),
    ],
)
def test_bad_arguments_are_refused_in_one_line(kwargs, message):
    with pytest.raises(InputError, match=message) as info:
        omnikin.track("tomasi-omni3", "figure8 1", **kwargs)
    assert "\n" not in str(info.value)


def test_a_robot_that_cannot_strafe_is_refused_a_path_that_needs_it():
    # a differential drive holding its heading on a circle would have to move sideways
    with pytest.raises(InputError, match=r"diff-drive.*s = ") as info:
        omnikin.track("diff-drive", "circle 1", heading="fixed")
    assert "\n" not in str(info.value)
    # along the tangent it can drive the circle, but the feedback controller needs sideways motion
    with pytest.raises(InputError, match=r"cannot move sideways.*feedback controller"):
        omnikin.track("diff-drive", "circle 1", heading="tangent", controller="feedback")


def test_a_layout_with_fixed_wheels_is_tracked_by_the_mpc_along_the_tangent_by_default():
    done = omnikin.track("diff-drive", "circle 1")
    summary = done.summary()
    assert summary["controller"] == "mpc"
    # the heading along the tangent: a quarter of the way round it has turned a quarter turn
    quarter = np.argmin(np.abs(done.path.s - done.path.length / 4))
    assert done.path.pose[quarter, 2] == pytest.approx(math.pi / 2, abs=1e-3)
    # the MPC keeps every wheel within its limit itself: nothing left for the runtime to saturate
    assert summary["saturated_samples"] == 0 and summary["largest_excess_percent"] < 1e-4
    assert summary["max_error_m"] < 1e-5


def test_a_car_is_tracked_by_pure_pursuit_by_default():
    summary = omnikin.track("ackermann", "circle 5").summary()
    assert summary["controller"] == "pursuit"
    assert summary["max_error_m"] < 1e-6  # a circle started on is pure pursuit's fixed point


def test_a_differential_drive_takes_a_path_file_that_gives_its_headings(tmp_path):
    # headings along the tangent, given in the file: the robot's default heading mode must not
    # collide with them
    f = tmp_path / "l.csv"
    f.write_text("x,y,theta\n0,0,0\n1,0,0\n")
    summary = omnikin.track("diff-drive", f).summary()
    assert summary["controller"] == "mpc"
    assert summary["max_error_m"] < 1e-9
