"""The whole chain on the seed robot's real chip: three simulated Arduino Nanos (ATmega328P in
simavr, each running the stepper firmware built for its wheel, firmware/Makefile), omnikin's
serial back-end on their pseudo-terminals, and ``omnikin ros tomasi-omni3 --backend serial``,
driven over ``cmd_vel`` on a real ROS 2 graph.

The truth is the simulated shafts (``simboard``'s ``angle``: the steps the firmware made, each
turning the shaft by 2 pi / (200 * 8)). Two checks, each against a closed form:

- the counts come back: every wheel position the node publishes (``joint_states``) is the
  shaft's angle to within the quantisation of a 600 ppr encoder counted on one edge, one count
  (2 pi / 600 rad);
- the odometry follows the command: while the wheels cruise, the body's velocity from the
  odometry (displacement over a window, in the body frame) is the commanded twist to within one
  count and one report period of motion per wheel at each end of the window (the boards report
  out of phase and the host stamps a count when it reads it), mapped through the inverse of Tomasi
  and Todt's kinematics (wheel i at angle_i on a circle of radius d, driving along the
  counter-clockwise tangent: r dphi_i = -sin(angle_i) dx + cos(angle_i) dy + d dtheta).

The robot's path while the wheels ramp is not a closed form: the boards apply a new speed up to
one control period apart and each ramps its own wheel, so a short rotation is real (the three
Nanos of the paper behave the same way); the checks above do not depend on it.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from test_ros_node import (  # noqa: E402 (after the importorskips there)
    DiagnosticStatus,
    _ros_environment,  # noqa: F401 (the module's ROS environment, autouse)
    stamp_s,
    start,
    wait_for,
    yaw_of,
)

from firmware_build import AVR_MISSING, build_dir, firmware
from simboard import SIMAVR_MISSING, SimBoard, build_simboard

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
REPORT_PERIOD = 0.02  # [s], the protocol's


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


def joint_positions(g) -> np.ndarray:
    with g.lock:
        msg = g.joints[-1][1]
    return np.array([dict(zip(msg.name, msg.position, strict=True))[w] for w in ("w1", "w2", "w3")])


def body_velocity(g, t0: float, t1: float) -> tuple[np.ndarray, float]:
    """The odometry's mean velocity between receive times t0 and t1 [monotonic s]: (vx, vy) in the
    body frame at the window's mean heading, and the yaw rate; and the window's length [s]."""
    with g.lock:
        window = [m for t, m in g.odom if t0 <= t <= t1]
    a, b = window[0], window[-1]
    dt = stamp_s(b.header.stamp) - stamp_s(a.header.stamp)
    pa, pb = pose(a), pose(b)
    yaw = 0.5 * (pa[2] + pb[2])
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = pb[0] - pa[0], pb[1] - pa[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, pb[2] - pa[2]]) / dt, dt


def test_cmd_vel_turns_the_simulated_wheels_the_counts_come_back_and_odometry_follows(tmp_path, nanos):
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        start_angles = angles(nanos) - joint_positions(g)
        # bytes the boards sent before the node opened their ports may have been cut where the
        # pty's buffer overflowed: count damage from here on
        corrupt_before = int(g.next_diag()[2]["link_corrupt"])
        for command in ((0.2, 0.0, 0.0), (0.0, -0.15, 0.0), (0.0, 0.0, 0.8)):
            first, last = g.drive(*command, duration=2.0)
            velocity, dt = body_velocity(g, first + 0.8, last)
            # each wheel: one count, and its motion over one report period (the boards report
            # out of phase, and the host stamps a count when it reads it), at each end
            per_wheel = RAD_PER_COUNT + np.abs(INVERSE @ command) * REPORT_PERIOD
            bound = 2 * np.abs(FORWARD) @ per_wheel / dt
            assert np.all(np.abs(velocity - command) <= bound), f"odometry {velocity} for the command {command}"
        g.send()
        g.wait_still(timeout=5.0)
        shafts = angles(nanos) - start_angles
        assert np.abs(shafts).max() > 5.0, f"the wheels did not turn: {shafts}"
        counted = joint_positions(g)
        assert np.all(np.abs(counted - shafts) <= RAD_PER_COUNT + 1e-9), f"counts {counted} vs shafts {shafts}"
        diag = g.next_diag()[2]
        assert diag["link_link_lost"] == "False" and int(diag["link_corrupt"]) == corrupt_before, diag
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


def test_a_board_reset_while_driving_loses_at_most_two_report_periods_of_its_wheel(tmp_path, nanos):
    """A reset board restarts its counter and says RESET; the host takes its next report's count as
    the new zero. The turns between the board's last report before the reset and its first after
    it are lost: at most two report periods of that wheel's motion. The other wheels keep every
    count, and the odometry does not jump."""
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        start_angles = angles(nanos) - joint_positions(g)
        g.drive(vx=0.2, duration=1.0)
        nanos[2].reset()
        g.drive(vx=0.2, duration=1.0)
        g.send()
        g.wait_still(timeout=5.0)
        with g.lock:
            xs = np.array([m.pose.pose.position.x for _, m in g.odom])
        assert np.max(np.abs(np.diff(xs))) < 0.2 * 0.05, "the odometry jumped at the reset"
        diag = g.next_diag()[2]
        assert int(diag["link_resets"]) >= 1, diag
        shafts = angles(nanos) - start_angles
        counted = joint_positions(g)
        bound = np.full(3, RAD_PER_COUNT + 1e-9)
        bound[2] += abs(INVERSE @ (0.2, 0.0, 0.0))[2] * 2 * REPORT_PERIOD
        assert np.all(np.abs(counted - shafts) <= bound), f"counts {counted} vs shafts {shafts}"
    finally:
        g.close()
        proc.close()


def test_corrupted_bytes_on_a_board_uart_are_counted_not_fatal(tmp_path, nanos):
    """Bit flips in both directions of one board's UART: the host counts the damaged frames, the
    board reports the damaged commands (ERROR_REPORT CRC), the link holds, and every count still
    comes back (a lost report only delays a count: the next one carries it)."""
    proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", *(b.path for b in nanos)])
    try:
        start_angles = angles(nanos) - joint_positions(g)
        nanos[0].corrupt("tx", 97)
        nanos[0].corrupt("rx", 89)
        g.drive(vx=0.2, vy=0.1, duration=2.0)
        g.send()
        g.wait_still(timeout=5.0)
        nanos[0].corrupt("tx", 0)
        nanos[0].corrupt("rx", 0)
        board = nanos[0].stats()
        assert board["corrupted_tx"] > 0 and board["corrupted_rx"] > 0, board
        time.sleep(0.3)  # a clean report after the last flipped one
        diag = g.next_diag()[2]
        assert int(diag["link_corrupt"]) + int(diag["link_short"]) > 0, diag
        assert diag["link_link_lost"] == "False" and "CRC" in diag["link_last_error"] + diag.get("link_errors", ""), (
            diag
        )
        shafts = angles(nanos) - start_angles
        assert np.abs(shafts).max() > 3.0, shafts
        counted = joint_positions(g)
        assert np.all(np.abs(counted - shafts) <= RAD_PER_COUNT + 1e-9), f"counts {counted} vs shafts {shafts}"
    finally:
        g.close()
        proc.close()
