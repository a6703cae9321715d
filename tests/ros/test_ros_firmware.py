"""The whole chain on the seed robot's real chip: three simulated Arduino Nanos (ATmega328P in
simavr, each running the stepper firmware built for its wheel, firmware/Makefile), omnikin's
serial back-end on their pseudo-terminals, and ``omnikin ros tomasi-omni3 --backend serial``,
driven over ``cmd_vel`` on a real ROS 2 graph.

The truth is the simulated shafts (``simboard``'s ``angle``: the steps the firmware made, each
turning the shaft by 2 pi / (200 * 8)). With no rotation commanded the heading stays 0, so the
body's displacement is the inverse of Tomasi and Todt's kinematics (wheel i at angle_i on a circle
of radius d, driving along the counter-clockwise tangent) applied to the wheels' total angles:

    r dphi_i = -sin(angle_i) dx + cos(angle_i) dy + d dtheta

and the odometry, made from the encoders' counts, may differ from it by the quantisation of a
600 ppr encoder counted on one edge: at most one count (2 pi / 600) per wheel, mapped through
that inverse.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from firmware_build import AVR_MISSING, build_dir, firmware
from simboard import SIMAVR_MISSING, SimBoard, build_simboard
from test_ros_node import (  # noqa: E402 (after the importorskips there)
    DiagnosticStatus,
    _ros_environment,  # noqa: F401 (the module's ROS environment, autouse)
    start,
    wait_for,
    yaw_of,
)

pytestmark = [
    pytest.mark.ros,
    pytest.mark.serial,
    pytest.mark.compiler,
    pytest.mark.skipif(AVR_MISSING is not None, reason=str(AVR_MISSING)),
    pytest.mark.skipif(SIMAVR_MISSING is not None, reason=str(SIMAVR_MISSING)),
]

ANGLES = np.radians([0.0, 120.0, 240.0])  # tomasi-omni3: wheel i at angle_i (robot file)
D, R = 0.113, 0.04125  # hub distance and wheel radius [m]
RAD_PER_COUNT = 2 * math.pi / 600
INVERSE = np.column_stack([-np.sin(ANGLES), np.cos(ANGLES), np.full(3, D)]) / R  # wheel rad per body (m, m, rad)
FORWARD = np.linalg.inv(INVERSE)
QUANTUM = np.abs(FORWARD).sum(axis=1) * RAD_PER_COUNT  # |pose error| bound of one count per wheel


def pose(msg) -> np.ndarray:
    p = msg.pose.pose
    return np.array([p.position.x, p.position.y, yaw_of(p.orientation)])


@pytest.fixture
def nanos():
    """Three simulated Nanos in real time, wheel i running the stepper firmware built for index i."""
    exe = build_simboard(build_dir())
    boards = [SimBoard(exe, firmware("stepper", wheel=i).elf, "--motor", "stepper") for i in range(3)]
    try:
        yield boards
    finally:
        for b in boards:
            b.close()


def angles(boards) -> np.ndarray:
    return np.array([b.stats()["angle"] for b in boards])


def test_cmd_vel_turns_the_simulated_wheels_and_odometry_follows_within_one_count(tmp_path, nanos):
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        start_angles = angles(nanos)
        g.drive(vx=0.2, duration=1.5)
        g.drive(vy=-0.15, duration=1.0)
        g.send()
        still = g.wait_still(timeout=5.0)
        moved = angles(nanos) - start_angles
        truth = FORWARD @ moved
        assert truth[0] > 0.2 and truth[1] < -0.1, f"the wheels did not carry the robot: {truth}"
        err = np.abs(pose(still) - truth)
        assert np.all(err <= QUANTUM + 1e-9), f"odometry {pose(still)} vs the shafts {truth}: {err} > {QUANTUM}"
        # each wheel turned as Tomasi and Todt's inverse kinematics says for that motion
        assert np.allclose(moved, INVERSE @ truth, atol=1e-9)
        diag = g.next_diag()[2]
        assert diag["link_lost"] == "False" and int(diag["link_corrupt"]) == 0, diag
    finally:
        g.close()
        proc.close()


def test_a_silenced_board_stops_the_robot_and_the_node_reports_it(tmp_path, nanos):
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        g.drive(vx=0.2, duration=1.0)
        nanos[1].silence(True)
        g.drive(vx=0.2, duration=1.0)  # keep commanding: the lost link must win
        assert wait_for(lambda: "wheels stopped" in g.last_diag()[3].message, 5.0), g.last_diag()
        assert g.last_diag()[3].level != DiagnosticStatus.OK
        assert "w2" in g.last_diag()[3].message
        time.sleep(0.3)
        before = [b.stats()["steps"]["count"] for b in nanos]
        time.sleep(1.0)
        after = [b.stats()["steps"]["count"] for b in nanos]
        assert after == before, f"the wheels still step after the link was lost: {before} -> {after}"
        assert proc.proc.poll() is None, proc.stderr()
    finally:
        g.close()
        proc.close()


def test_a_board_reset_while_driving_neither_moves_nor_loses_the_odometry(tmp_path, nanos):
    """A reset board restarts its counter at 0 and says RESET; the host re-zeroes that wheel
    without moving its angle. The steps made between its last report and the reset are lost to
    the odometry (at most one report period, 20 ms, of that wheel's motion) and nothing else."""
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        start_angles = angles(nanos)
        g.drive(vx=0.2, duration=1.0)
        nanos[2].reset()
        g.drive(vx=0.2, duration=1.0)
        g.send()
        still = g.wait_still(timeout=5.0)
        with g.lock:
            xs = np.array([m.pose.pose.position.x for _, m in g.odom])
        assert np.max(np.abs(np.diff(xs))) < 0.2 * 0.05, "the odometry jumped at the reset"
        diag = g.next_diag()[2]
        assert int(diag["link_resets"]) >= 1, diag
        truth = FORWARD @ (angles(nanos) - start_angles)
        lost_motion = np.abs(FORWARD[:, 2]) * 0.2 / R * 0.02 * 2  # two report periods of wheel 3 at top
        err = np.abs(pose(still) - truth)
        assert np.all(err <= QUANTUM + lost_motion), f"odometry {pose(still)} vs the shafts {truth}"
    finally:
        g.close()
        proc.close()


def test_corrupted_bytes_on_a_board_uart_are_counted_not_fatal(tmp_path, nanos):
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        nanos[0].corrupt("tx", 97)
        nanos[0].corrupt("rx", 89)
        start_angles = angles(nanos)
        g.drive(vx=0.2, duration=2.0)
        g.send()
        still = g.wait_still(timeout=5.0)
        diag = g.next_diag()[2]
        assert int(diag["link_corrupt"]) + int(diag["link_short"]) > 0, diag
        assert diag["link_lost"] == "False", diag
        truth = FORWARD @ (angles(nanos) - start_angles)
        assert truth[0] > 0.3
        assert np.all(np.abs(pose(still) - truth) <= QUANTUM + 1e-9)
        assert nanos[0].stats()["corrupted_tx"] > 0
    finally:
        g.close()
        proc.close()
