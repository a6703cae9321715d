"""The whole chain on the seed robot's real chip: three simulated Arduino Nanos (ATmega328P in
simavr, each running the stepper firmware built for its wheel, firmware/Makefile), omnikin's
serial back-end on their pseudo-terminals, and ``omnikin ros tomasi-omni3 --backend serial``,
driven over ``cmd_vel`` on a real ROS 2 graph.

The truth is the simulated shafts (``simboard``'s ``angle``: the steps the firmware made, each
turning the shaft by 2 pi / (200 * 8)) and the chips' own clocks (``time_s``: their simulated
cycles). Every check holds in simulated or recorded time, whatever the pace of the machine: on a
busy one the chips fall behind the wall clock, and the wheels turn slower than the command per
second of the host's clock while they turn exactly as commanded per second of their own. Three
checks, each against a closed form:

- the wheels follow the command: while they cruise, each shaft's speed over a window of its
  chip's time is the command mapped through the inverse of Tomasi and Todt's kinematics (wheel i
  at angle_i on a circle of radius d, driving along the counter-clockwise tangent:
  r dphi_i = -sin(angle_i) dx + cos(angle_i) dy + d dtheta) to within one step at each end of the
  window and the protocol's speed unit (1e-4 rad/s);
- the counts come back: every wheel position the node publishes (``joint_states``) is the
  shaft's angle to within the quantisation of a 600 ppr encoder counted on one edge, one count
  (2 pi / 600 rad);
- the odometry integrates the counts: between two ``odom`` messages of the cruise, the body's
  velocity from the odometry (displacement in the body frame over the difference of the stamps)
  is the forward kinematics of the wheel positions the node published with the same stamps, to
  within one count per wheel at each end.

The link. Each chip stops its wheel after link_timeout (0.5 s) of its own time without a frame
from the host, as on the real robot. The host, on its side, calls a controller lost when it has
sent nothing for a time of the host's clock; a simulated chip on a busy machine can fall seconds
behind that clock (its process waits for a core), and a real controller cannot. So the node runs
with ``--link-timeout`` HOST_LINK_TIMEOUT: a silence the host sees is a lost link only when no
simulated chip could have been that slow (docs/firmware.md). The silenced board is still found.

The robot's path while the wheels ramp is not a closed form: the boards apply a new speed up to
one control period apart and each ramps its own wheel, so a short rotation is real (the three
Nanos of the paper behave the same way); the checks above do not depend on it.
"""

from __future__ import annotations

import math
import threading
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

from support.firmware_build import AVR_MISSING, build_dir, firmware
from support.kinematics import constant_twist_pose
from support.simboard import SIMAVR_MISSING, SimBoard, build_simboard

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
STEP_RAD = 2 * math.pi / (200 * 8)  # one step of the stepper (200 steps/rev, 8 microsteps) [rad]
INVERSE = np.column_stack([-np.sin(ANGLES), np.cos(ANGLES), np.full(3, D)]) / R  # wheel rad per body (m, m, rad)
FORWARD = np.linalg.inv(INVERSE)
QUANTUM = np.abs(FORWARD).sum(axis=1) * RAD_PER_COUNT  # |pose error| bound of one count per wheel
REPORT_PERIOD = 0.02  # [s], the protocol's
HOST_LINK_TIMEOUT = 10.0
"""[s of the host's clock] how long the node lets a simulated chip stay silent: 20 times the
controllers' own link_timeout, so that a chip whose process is held back by the machine for
seconds is not taken for a lost one."""


def start_node(tmp_path, boards):
    """The node on the boards' pseudo-terminals, with the host's link timeout for simulated chips.
    The test's ``cmd_vel`` comes from a thread of the test process on the host's clock; a busy
    machine can hold that thread back for longer than the default cmd_vel_timeout (0.5 s), and the
    node would brake, as it must when a real teleop stalls. The command is constant over each
    measured window, so the node holds it as long as it holds a silent link."""
    ports = [b.path for b in boards]
    args = ["tomasi-omni3", "--backend", "serial", "--port", *ports, "--link-timeout", HOST_LINK_TIMEOUT]
    return start(tmp_path, [*args, "--ros-args", "-p", f"cmd_vel_timeout:={HOST_LINK_TIMEOUT}"])


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
    """The wheel positions of the last ``joint_states`` (waiting for the first one)."""
    assert wait_for(lambda: len(g.joints) > 0, 60.0), "no joint_states received"
    with g.lock:
        msg = g.joints[-1][1]
    return np.array([dict(zip(msg.name, msg.position, strict=True))[w] for w in ("w1", "w2", "w3")])


def relative(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """Pose ``p1`` (x, y, yaw) in the frame of pose ``p0``."""
    c, s = math.cos(p0[2]), math.sin(p0[2])
    dx, dy = p1[0] - p0[0], p1[1] - p0[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, math.remainder(p1[2] - p0[2], 2 * math.pi)])


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose ``b`` given in the frame of pose ``a``, in the frame ``a`` is given in."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def odometry_and_counts(g, stamps: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Between the ``odom`` messages stamped ``stamps`` [s]: the odometry's motion (the second
    pose in the frame of the first), and the motion the published wheel positions give in closed
    form, each interval between two ``joint_states`` a constant body twist (forward kinematics of
    the wheel increments) followed along its arc (:func:`support.kinematics.constant_twist_pose`)."""
    with g.lock:
        poses = {stamp_s(m.header.stamp): pose(m) for _, m in g.odom}
        joints = [(stamp_s(m.header.stamp), m) for _, m in g.joints]
    wheels = [
        np.array([dict(zip(m.name, m.position, strict=True))[w] for w in ("w1", "w2", "w3")])
        for t, m in joints
        if stamps[0] <= t <= stamps[1]
    ]
    motion = np.zeros(3)
    for q0, q1 in zip(wheels[:-1], wheels[1:], strict=True):
        motion = compose(motion, constant_twist_pose(FORWARD @ (q1 - q0), 1.0))
    motion[2] = math.remainder(motion[2], 2 * math.pi)
    return relative(poses[stamps[0]], poses[stamps[1]]), motion


def chip_clocks(boards) -> np.ndarray:
    """Each board's simulated time [s]."""
    return np.array([b.stats()["time_s"] for b in boards])


def drive_in_chip_time(g, boards, command, window: tuple[float, float], rate: float = 20.0):
    """Publish ``command`` at ``rate`` [Hz, host clock, from a thread of its own] until every board
    has simulated ``window[1]`` s since the start; returns, for the window's two ends (every board
    past ``window[0]``, then past ``window[1]``, of its own time), the boards' (times, shaft
    angles) and the stamp of the last ``odom`` received then. A safety timeout only (a busy
    machine slows the chips, it does not fail the test)."""
    done = threading.Event()

    def publish():
        while not done.is_set():
            g.send(*command)
            done.wait(1.0 / rate)

    start = chip_clocks(boards)
    sender = threading.Thread(target=publish, daemon=True)
    sender.start()
    ends = []
    deadline = time.monotonic() + 600.0
    try:
        for edge in window:
            while np.min(chip_clocks(boards) - start) < edge:
                assert time.monotonic() < deadline, "the simulated boards did not advance"
                time.sleep(0.01)
            with g.lock:
                stamp = stamp_s(g.odom[-1][1].header.stamp)
            states = [b.stats() for b in boards]
            ends.append((np.array([s["time_s"] for s in states]), np.array([s["angle"] for s in states]), stamp))
    finally:
        done.set()
        sender.join()
    return ends


def wait_chip_time(boards, seconds: float) -> None:
    """Wait until every board has simulated ``seconds`` more [s of chip time] (safety timeout only)."""
    start = chip_clocks(boards)
    deadline = time.monotonic() + 600.0
    while np.min(chip_clocks(boards) - start) < seconds:
        assert time.monotonic() < deadline, "the simulated boards did not advance"
        time.sleep(0.01)


def shafts_at_rest(boards) -> np.ndarray:
    """Wait until no shaft moves over 0.1 s of its chip's time; their angles then [rad]."""
    before = angles(boards)
    while True:
        wait_chip_time(boards, 0.1)
        now = angles(boards)
        if np.array_equal(now, before):
            return now
        before = now


def counts_reach(g, shafts: np.ndarray, bound) -> np.ndarray:
    """Wait until the wheel positions the node publishes are within ``bound`` of ``shafts``; fail
    if they are not after a safety timeout (the node reads a count when the machine lets it)."""
    wait_for(lambda: np.all(np.abs(joint_positions(g) - shafts) <= bound), 60.0)
    counted = joint_positions(g)
    assert np.all(np.abs(counted - shafts) <= bound), f"counts {counted} vs shafts {shafts}"
    return counted


def test_cmd_vel_turns_the_simulated_wheels_the_counts_come_back_and_odometry_follows(tmp_path, nanos):
    proc, g = start_node(tmp_path, nanos)
    try:
        start_angles = angles(nanos) - joint_positions(g)
        # bytes the boards sent before the node opened their ports may have been cut where the
        # pty's buffer overflowed: count damage from here on
        corrupt_before = int(g.next_diag()[2]["link_corrupt"])
        for command in ((0.2, 0.0, 0.0), (0.0, -0.15, 0.0), (0.0, 0.0, 0.8)):
            # the window starts 1 s of chip time after the command: the host's ramp (A_LIN, on
            # the host's clock, which runs at least as fast as the chips') and the chips' own
            # ramp (STEP_ACCEL) are over
            (t0, a0, s0), (t1, a1, s1) = drive_in_chip_time(g, nanos, command, (1.0, 2.5))
            wheel_speed = (a1 - a0) / (t1 - t0)
            expected = INVERSE @ command
            bound = 2 * STEP_RAD / (t1 - t0) + 0.5e-4
            assert np.all(np.abs(wheel_speed - expected) <= bound), (
                f"shaft speeds {wheel_speed} rad/s of chip time for the command {command}: expected {expected}"
            )
            odometry, counted = odometry_and_counts(g, (s0, s1))
            assert np.all(np.abs(odometry - counted) <= QUANTUM), (
                f"odometry {odometry} vs the motion of its counts {counted} for the command {command}"
            )
        g.send()
        shafts = shafts_at_rest(nanos) - start_angles
        assert np.abs(shafts).max() > 5.0, f"the wheels did not turn: {shafts}"
        counts_reach(g, shafts, RAD_PER_COUNT + 1e-9)
        diag = g.next_diag()[2]
        assert diag["link_link_lost"] == "False" and int(diag["link_corrupt"]) == corrupt_before, diag
    finally:
        g.close()
        proc.close()


def test_a_silenced_board_stops_the_robot_and_the_node_reports_it(tmp_path, nanos):
    proc, g = start_node(tmp_path, nanos)
    try:
        g.drive(vx=0.2, duration=1.0)
        nanos[1].silence(True)
        g.drive(vx=0.2, duration=1.0)  # keep commanding: the lost link must win
        assert wait_for(lambda: "wheels stopped" in g.last_diag()[3].message, HOST_LINK_TIMEOUT + 60.0), g.last_diag()
        assert g.last_diag()[3].level != DiagnosticStatus.OK
        assert "w2" in g.last_diag()[3].message
        wait_chip_time(nanos, 0.3)  # the steppers ramp down (30 rad/s at 60 rad/s^2: 0.5 s at most)
        wait_chip_time(nanos, 0.3)
        before = [b.stats()["steps"]["count"] for b in nanos]
        wait_chip_time(nanos, 1.0)
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
    proc, g = start_node(tmp_path, nanos)
    try:
        start_angles = angles(nanos) - joint_positions(g)
        drive_in_chip_time(g, nanos, (0.2, 0.0, 0.0), (0.0, 1.0))
        nanos[2].reset()
        drive_in_chip_time(g, nanos, (0.2, 0.0, 0.0), (0.0, 1.0))
        g.send()
        shafts = shafts_at_rest(nanos) - start_angles
        bound = np.full(3, RAD_PER_COUNT + 1e-9)
        bound[2] += abs(INVERSE @ (0.2, 0.0, 0.0))[2] * 2 * REPORT_PERIOD
        counts_reach(g, shafts, bound)
        with g.lock:
            xs = np.array([m.pose.pose.position.x for _, m in g.odom])
            stamps = np.array([stamp_s(m.header.stamp) for _, m in g.odom])
        # between two messages the robot moves at most 0.2 m/s for the time between their stamps
        # (the chips' time runs no faster than the host's), and a late count catches up by a few
        # centimetres at most; a count restarting from zero would jump by the wheel's whole turn
        # over the last second of chip time (about 0.1 m of x)
        jumps = np.abs(np.diff(xs)) - 0.2 * np.diff(stamps)
        assert np.max(jumps) < 0.03, f"the odometry jumped at the reset by {np.max(jumps):.3f} m"
        diag = g.next_diag()[2]
        assert int(diag["link_resets"]) >= 1, diag
    finally:
        g.close()
        proc.close()


def test_corrupted_bytes_on_a_board_uart_are_counted_not_fatal(tmp_path, nanos):
    """Bit flips in both directions of one board's UART: the host counts the damaged frames, the
    board reports the damaged commands (ERROR_REPORT CRC), the link holds, and every count still
    comes back (a lost report only delays a count: the next one carries it)."""
    proc, g = start_node(tmp_path, nanos)
    try:
        start_angles = angles(nanos) - joint_positions(g)
        nanos[0].corrupt("tx", 97)
        nanos[0].corrupt("rx", 89)
        drive_in_chip_time(g, nanos, (0.2, 0.1, 0.0), (0.0, 2.0))
        g.send()
        shafts_at_rest(nanos)
        nanos[0].corrupt("tx", 0)
        nanos[0].corrupt("rx", 0)
        board = nanos[0].stats()
        assert board["corrupted_tx"] > 0 and board["corrupted_rx"] > 0, board
        wait_chip_time(nanos, 0.1)  # clean reports after the last flipped one
        diag = g.next_diag()[2]
        assert int(diag["link_corrupt"]) + int(diag["link_short"]) > 0, diag
        assert diag["link_link_lost"] == "False" and "CRC" in diag["link_last_error"] + diag.get("link_errors", ""), (
            diag
        )
        shafts = angles(nanos) - start_angles
        assert np.abs(shafts).max() > 3.0, shafts
        counts_reach(g, shafts, RAD_PER_COUNT + 1e-9)
    finally:
        g.close()
        proc.close()
