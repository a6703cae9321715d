"""SerialBackend against the fake wheel controller on pseudo-terminals.

Real time, bounded: every wait polls with a deadline. A loaded machine may starve the fake
controller's thread for most of a second, so the tests that are not about a lost link give it
``PATIENT`` seconds; those that are about one shorten it to ``LINK_TIMEOUT`` to keep the file well
under its time budget, and check the back-end's own account of the silence, not the test's clock."""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest

pytest.importorskip("serial")

from omnikin import load_robot
from omnikin.errors import LinkLostError, OmnikinError
from omnikin.io.robot_file import robot_from_dict
from omnikin.runtime.base import BaseRuntime
from omnikin.runtime.fake_controller import FakeController, FakeWheel
from omnikin.runtime.protocol import load_protocol
from omnikin.runtime.serial_backend import SerialBackend

pytestmark = pytest.mark.serial

LINK_TIMEOUT = 0.3
"""[s] the link timeout of the tests that lose the link."""
PATIENT = 5.0
"""[s] the link timeout of the others, and the longest wait of a condition that should hold soon."""
REPORT = 0.01
TWO_PI = 2 * math.pi


def robot_mixed():
    """Three omni wheels with different encoders (one inverted, one geared) and a passive castor."""
    return robot_from_dict(
        {
            "omnikin": 1,
            "name": "serial-test",
            "wheels": [
                {
                    "name": "a",
                    "type": "omni",
                    "distance": 0.1,
                    "angle_deg": 0,
                    "radius": 0.03,
                    "encoder": {"ticks_per_rev": 600},
                },
                {
                    "name": "b",
                    "type": "omni",
                    "distance": 0.1,
                    "angle_deg": 120,
                    "radius": 0.03,
                    "encoder": {"ticks_per_rev": 1000, "gear_ratio": 2.5},
                },
                {
                    "name": "c",
                    "type": "omni",
                    "distance": 0.1,
                    "angle_deg": 240,
                    "radius": 0.03,
                    "encoder": {"ticks_per_rev": 600, "invert": True},
                },
            ],
        }
    )


def poll(backend, until, timeout=PATIENT, speeds=None, reads=None):
    """Read (and write ``speeds``) every few ms until ``until(state)``; returns the state. The
    monotonic time of each read is appended to ``reads`` when given."""
    deadline = time.monotonic() + timeout
    while True:
        now = time.monotonic()
        if speeds is not None:
            backend.write(now, speeds)
        if reads is not None:
            reads.append(now)
        state = backend.read(now)
        if until(state):
            return state
        if now > deadline:
            raise AssertionError(f"condition not met within {timeout} s; last state {state}, stats {backend.stats()}")
        time.sleep(0.003)


def wait_for(cond, timeout=PATIENT):
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        time.sleep(0.003)


def make_rig(tomasi, link_timeout):
    """A fake controller of ``tomasi`` on a pseudo-terminal and a ready back-end on it."""
    fake = FakeController.for_robot(tomasi, report_period=REPORT, link_timeout=2 * PATIENT).start()
    backend = SerialBackend(tomasi, fake.path, link_timeout=link_timeout, connect_timeout=PATIENT)
    backend.wait_ready(PATIENT)
    return fake, backend


@pytest.fixture
def rig(tomasi):
    """A link that a busy machine does not lose (``PATIENT``)."""
    fake, backend = make_rig(tomasi, PATIENT)
    yield fake, backend
    backend.close()
    fake.close()


@pytest.fixture
def quick_rig(tomasi):
    """A link that is lost after ``LINK_TIMEOUT`` of silence."""
    fake, backend = make_rig(tomasi, LINK_TIMEOUT)
    yield fake, backend
    backend.close()
    fake.close()


def test_speeds_commanded_arrive_and_heartbeats_flow(rig):
    fake, backend = rig
    speeds = np.array([1.0, -2.5, 0.1234])
    poll(backend, lambda s: all(math.isclose(fake.speed(i), speeds[i], abs_tol=1e-12) for i in range(3)), speeds=speeds)
    state = poll(backend, lambda s: np.allclose(s.velocities, speeds), speeds=speeds)
    assert state.steer is None and state.positions.shape == (3,)

    # the link keeps flowing: wait for counts, not for a wall time (a loaded machine may starve
    # the fake controller's thread for a while without anything being wrong with the link)
    def flowing(_):
        s = backend.stats()
        seen = {m.wheel for m in list(fake.received) if m.name == "HEARTBEAT"}
        return seen == {0, 1, 2} and s["heartbeats_tx"] >= 3 * 3 and s["heartbeats_rx"] >= 3 and s["reports"] > 30

    poll(backend, flowing, timeout=10.0, speeds=speeds)
    beats = [m for m in fake.received if m.name == "HEARTBEAT"]
    assert {m.wheel for m in beats} == {0, 1, 2}
    s = backend.stats()
    assert s["frames_ok"] > 0 and s["corrupt"] == s["short"] == s["out_of_order"] == 0 and not s["link_lost"]
    assert fake.decoder.stats.frames_ok > 0 and fake.decoder.stats.corrupt == 0
    assert all(fake.decoder.stats.as_dict()[k] == 0 for k in ("lost", "duplicates", "out_of_order"))


def test_counts_become_angles_with_each_encoder():
    robot = robot_mixed()
    with FakeController.for_robot(robot, report_period=REPORT) as fake:
        with SerialBackend(robot, fake.path, link_timeout=PATIENT) as backend:
            backend.wait_ready(PATIENT)
            fake.advance(0, 600)  # one turn of a
            fake.advance(1, 1000 * 2.5)  # one turn of b (geared)
            fake.advance(2, 300)  # half a turn of c, counting backwards (invert)
            state = poll(backend, lambda s: np.allclose(s.positions, [TWO_PI, TWO_PI, -math.pi], atol=1e-12))
            assert np.allclose(state.positions, [TWO_PI, TWO_PI, -math.pi], rtol=0, atol=1e-12)


def test_counter_wrap_around(tomasi):
    top = 2**31 - 1
    starts = {"w1": top - 100, "w2": -(2**31) + 50, "w3": 0}
    with FakeController.for_robot(tomasi, start_counts=starts, report_period=REPORT) as fake:
        with SerialBackend(tomasi, fake.path, link_timeout=PATIENT) as backend:
            backend.wait_ready(PATIENT)
            fake.advance(0, 600)  # crosses +2**31 -> -2**31
            fake.advance(1, -600)  # crosses -2**31 -> +2**31 - 1 going back
            poll(backend, lambda s: np.allclose(s.positions, [TWO_PI, -TWO_PI, 0.0], atol=1e-12))
            # and while turning: 15 rad/s for a while, then stop; the angle is exactly the count moved
            speeds = np.array([15.0, -15.0, 0.0])
            t0 = time.monotonic()
            poll(backend, lambda s: time.monotonic() - t0 > 0.25, speeds=speeds)
            zero = np.zeros(3)
            poll(backend, lambda s: fake.speed(0) == 0.0 and fake.speed(1) == 0.0, speeds=zero)
            time.sleep(3 * REPORT)
            expected = [(fake.ticks(i) - (starts[n])) * TWO_PI / 600 for i, n in enumerate(("w1", "w2", "w3"))]
            assert fake.ticks(0) > top and fake.ticks(1) < -(2**31)  # the 32-bit counters did wrap
            state = poll(backend, lambda s: np.allclose(s.positions, expected, atol=1e-12), speeds=zero)
            assert state.positions[0] > TWO_PI + 1.0 and state.positions[1] < -TWO_PI - 1.0


def test_controller_reset_keeps_the_angle(rig):
    fake, backend = rig
    fake.advance(0, 150)
    poll(backend, lambda s: math.isclose(s.positions[0], math.pi / 2, abs_tol=1e-12))
    resets = backend.stats()["resets"]  # the start-up RESETs arrive or not, depending on when the port opened
    fake.simulate_reset(0)  # counter back to 0, sequence numbers from 0, RESET report first
    wait_for(lambda: fake.faults_pending == 0)
    # the RESET, then two rounds of reports (count 0 for this wheel) reach the back-end before the
    # wheel moves again: waited for, not slept for
    poll(backend, lambda s: backend.stats()["resets"] == resets + 1)
    reports = backend.stats()["reports"]
    poll(backend, lambda s: backend.stats()["reports"] >= reports + 6)
    fake.advance(0, 150)
    state = poll(backend, lambda s: math.isclose(s.positions[0], math.pi, abs_tol=1e-12))
    s = backend.stats()
    assert s["resets"] == resets + 1 and "RESET" in s["last_error"] and "w1" in s["last_error"]
    assert s["out_of_order"] == 0 and state.positions[0] == pytest.approx(math.pi)


def test_a_controller_restart_whose_reset_report_is_lost_does_not_move_the_angle(rig):
    """Without its RESET the host sees the restart in the sequence numbers (resync_after frames
    out of order, then adopted) and takes the next report's count as the new zero: the angle
    stays where it was (it does not jump back by the 150 counts the counter lost)."""
    fake, backend = rig
    fake.advance(0, 150)
    poll(backend, lambda s: math.isclose(s.positions[0], math.pi / 2, abs_tol=1e-12))
    resyncs = backend.stats()["resyncs"]
    fake.simulate_reset(0, announce=False)
    poll(backend, lambda s: backend.stats()["resyncs"] > resyncs)
    reports = backend.stats()["reports"]
    poll(backend, lambda s: backend.stats()["reports"] >= reports + 6)
    fake.advance(0, 150)
    state = poll(backend, lambda s: math.isclose(s.positions[0], math.pi, abs_tol=1e-12))
    assert state.positions[0] == pytest.approx(math.pi)


@pytest.mark.parametrize(
    "fault, n, counters, counted",
    [
        # the fake damages the next n frames it sends, back to back: one garbled stretch of bytes
        ("corrupt", 3, ("corrupt",), 1),
        ("short", 2, ("short", "corrupt"), 1),  # short or corrupt: depends on the lengths of the two cut frames
        ("out_of_order", 2, ("out_of_order",), 2),
        ("duplicate", 2, ("duplicates",), 2),
        ("bad_version", 1, ("bad_version",), 1),
        ("unknown_type", 1, ("unknown_type",), 1),
    ],
)
def test_bad_frames_are_counted_and_the_link_survives(rig, fault, n, counters, counted):
    fake, backend = rig
    before = backend.stats()
    getattr(fake, f"inject_{fault}")(n)
    wait_for(lambda: fake.faults_pending == 0)
    time.sleep(5 * REPORT)
    fake.advance(2, 600)
    state = poll(backend, lambda s: math.isclose(s.positions[2], TWO_PI, abs_tol=1e-12))
    after = backend.stats()
    assert sum(after[c] - before[c] for c in counters) == counted
    assert not after["link_lost"] and after["reports"] > before["reports"]
    assert state.positions[2] == pytest.approx(TWO_PI)


def test_garbage_is_skipped(rig):
    fake, backend = rig
    before = backend.stats()
    for _ in range(5):
        fake.inject_garbage(40)
        wait_for(lambda: fake.faults_pending == 0)
    time.sleep(5 * REPORT)
    fake.advance(1, -300)
    poll(backend, lambda s: math.isclose(s.positions[1], -math.pi, abs_tol=1e-12))
    after = backend.stats()
    assert after["skipped_bytes"] - before["skipped_bytes"] >= 200
    assert not after["link_lost"] and after["internal_errors"] == 0


def test_error_reports_are_kept(rig):
    fake, backend = rig
    before = backend.stats()["errors_rx"]
    fake.send_error(1, "MOTOR_FAULT", "overcurrent")
    poll(backend, lambda st: "MOTOR_FAULT" in backend.stats()["last_error"])
    s = backend.stats()
    assert s["last_error"] == f"w2 on {fake.path}: MOTOR_FAULT (overcurrent)" and s["errors_rx"] == before + 1


def test_silent_controller_loses_the_link_and_stops_the_wheels(quick_rig):
    fake, backend = quick_rig
    speeds = np.array([3.0, 3.0, 3.0])
    reads: list[float] = []
    poll(backend, lambda s: all(fake.speed(i) == 3.0 for i in range(3)), speeds=speeds, reads=reads)
    fake.silent = True
    with pytest.raises(LinkLostError) as info:
        poll(backend, lambda s: False, timeout=3.0, speeds=speeds, reads=reads)
    # the back-end's own account: silent for just over link_timeout, found by the first read
    # after it (the read before found the link alive, so at most the gap between the two later)
    silent = float(re.search(r"sent no valid frame for ([0-9.]+) s", str(info.value)).group(1))
    gap = reads[-1] - reads[-2]
    assert LINK_TIMEOUT - 0.0005 <= silent <= LINK_TIMEOUT + gap + 0.0005, (str(info.value), gap)  # printed to 1 ms
    err = info.value
    assert isinstance(err, OmnikinError)
    assert err.port == fake.path and err.wheel in ("w1", "w2", "w3")
    assert "link lost" in str(err) and fake.path in str(err) and repr(err.wheel) in str(err)
    # zero speeds went out at once, and keep going out whatever the runtime asks for
    wait_for(lambda: all(fake.speed(i) == 0.0 for i in range(3)))
    backend.write(time.monotonic(), speeds)
    time.sleep(0.05)
    assert all(fake.speed(i) == 0.0 and fake.commands(i)[-1] == 0.0 for i in range(3))
    with pytest.raises(LinkLostError):
        backend.read(time.monotonic())
    s = backend.stats()
    assert s["link_lost"] and s["timeouts"] == 1 and "link lost" in s["link_lost_reason"]
    # an explicit reset re-arms the link once the controller speaks again
    fake.silent = False
    backend.reset_link()
    backend.wait_ready(PATIENT)
    assert not backend.link_lost


def test_reconnect_re_arms_and_keeps_the_angles(quick_rig):
    """After a loss, reconnect() re-arms the link: the controller must be heard again, and the
    wheel angles continue from where they were held (no jump back to zero)."""
    fake, backend = quick_rig
    fake.advance(0, 150)
    poll(backend, lambda s: math.isclose(s.positions[0], math.pi / 2, abs_tol=1e-12))
    fake.silent = True
    with pytest.raises(LinkLostError):
        poll(backend, lambda s: False, timeout=3.0)
    fake.silent = False
    backend.reconnect()
    state = backend.wait_ready(PATIENT)
    assert not backend.link_lost and backend.stats()["reconnects"] == 1
    assert state.positions[0] == pytest.approx(math.pi / 2, abs=1e-12)
    fake.advance(0, 150)
    poll(backend, lambda s: math.isclose(s.positions[0], math.pi, abs_tol=1e-12))


def test_failed_port_is_reopened_or_named(tomasi):
    """A port that fails (here the controller's pseudo-terminal disappears) loses the link;
    reconnect() tries to reopen it and, while it cannot, says which port and stays lost."""
    fake = FakeController.for_robot(tomasi, report_period=REPORT).start()
    with SerialBackend(tomasi, fake.path, link_timeout=LINK_TIMEOUT, connect_timeout=PATIENT) as backend:
        backend.wait_ready(PATIENT)
        fake.close()
        with pytest.raises(LinkLostError) as info:
            poll(backend, lambda s: False, timeout=3.0)
        assert fake.path in str(info.value)
        with pytest.raises(OmnikinError, match="cannot open") as again:
            backend.reconnect()
        assert fake.path in str(again.value)
        assert backend.link_lost and backend.stats()["reconnects"] == 0
        with pytest.raises(LinkLostError):
            backend.read(time.monotonic())


def test_controller_that_never_answers(tomasi):
    with FakeController.for_robot(tomasi, report_period=REPORT) as fake:
        fake.silent = True
        with SerialBackend(tomasi, fake.path, connect_timeout=0.2) as backend:
            with pytest.raises(LinkLostError, match="never heard from it") as info:
                poll(backend, lambda s: False, timeout=2.0, speeds=np.zeros(3))
            assert info.value.port == fake.path


def test_one_port_per_wheel_and_misrouted_frames(tomasi):
    fakes = [
        FakeController([FakeWheel(0, 600 / TWO_PI), FakeWheel(1, 600 / TWO_PI)], report_period=REPORT),
        FakeController([FakeWheel(1, 600 / TWO_PI)], report_period=REPORT),
        FakeController([FakeWheel(2, 600 / TWO_PI)], report_period=REPORT),
    ]
    for f in fakes:
        f.start()
    try:
        with SerialBackend(tomasi, [f.path for f in fakes], link_timeout=PATIENT) as backend:
            backend.wait_ready(PATIENT)
            speeds = np.array([1.0, 2.0, 3.0])
            poll(backend, lambda s: [f.speed(i) for i, f in enumerate(fakes)] == [1.0, 2.0, 3.0], speeds=speeds)
            assert fakes[0].speed(1) == 0.0  # wheel 1's commands go to its own port only
            zero = np.zeros(3)
            poll(backend, lambda s: all(f.speed(i) == 0.0 for f, i in zip(fakes, range(3), strict=True)), speeds=zero)
            # wheel 1 stopped: wait until the back-end has its final count, not a fixed time
            rest = poll(
                backend,
                lambda s: math.isclose(s.positions[1], fakes[1].ticks(1) * TWO_PI / 600, abs_tol=1e-12),
                speeds=zero,
            )
            start = rest.positions[1]
            fakes[0].advance(1, 600)  # a wheel-1 controller on wheel 0's port: ignored
            fakes[1].advance(1, 300)
            poll(backend, lambda s: math.isclose(s.positions[1] - start, math.pi, abs_tol=1e-9), speeds=zero)
            time.sleep(3 * REPORT)
            assert backend.read(time.monotonic()).positions[1] - start == pytest.approx(math.pi, abs=1e-9)
            assert backend.stats()["misrouted"] > 0
            assert backend.stats()["ports"] == ",".join(f.path for f in fakes)
    finally:
        for f in fakes:
            f.close()


def test_port_mapping_and_set_up_errors(tomasi, tmp_path):
    with FakeController.for_robot(tomasi) as fake:
        p = fake.path
        for ports in ([p, p], {"w1": p, "w2": p}, {"w1": p, "w2": p, "w3": p, "w9": p}, 5, [p, "", p]):
            with pytest.raises(OmnikinError, match="port"):
                SerialBackend(tomasi, ports)
        b = SerialBackend(tomasi, {"w1": p, "w2": p, "w3": p})
        assert b.port_of == {"w1": p, "w2": p, "w3": p}
        with pytest.raises(OmnikinError, match="3 finite wheel speeds"):
            b.write(0.0, [1.0, float("nan"), 0.0])
        with pytest.raises(OmnikinError, match="cannot be sent"):
            b.write(0.0, [1e6, 0.0, 0.0])
        b.close()
        b.close()
    missing = str(tmp_path / "no-such-tty")
    with pytest.raises(OmnikinError, match="cannot open") as info:
        SerialBackend(tomasi, missing)
    assert missing in str(info.value) and "w1" in str(info.value)
    with pytest.raises(OmnikinError, match="steerable"):
        SerialBackend(load_robot("ackermann"), missing)
    with pytest.raises(OmnikinError, match="link_timeout"):
        SerialBackend(tomasi, missing, link_timeout=0)


def test_close_commands_zero(tomasi):
    with FakeController.for_robot(tomasi, report_period=REPORT) as fake:
        backend = SerialBackend(tomasi, fake.path, link_timeout=PATIENT)
        backend.wait_ready(PATIENT)
        poll(backend, lambda s: fake.speed(2) == -4.0, speeds=np.array([0.0, 0.0, -4.0]))
        backend.close()
        wait_for(lambda: fake.speed(2) == 0.0)


def test_fake_controller_stops_when_the_host_goes_quiet(tomasi):
    with FakeController.for_robot(tomasi, report_period=REPORT, link_timeout=0.15) as fake:
        with SerialBackend(tomasi, fake.path, link_timeout=PATIENT) as backend:
            backend.wait_ready(PATIENT)
            poll(backend, lambda s: fake.speed(0) == 2.0, speeds=np.array([2.0, 0.0, 0.0]))
            events = fake.link_lost_events(0)  # a busy machine may have kept the host quiet before
            # the host stops calling: no commands, no heartbeats
            wait_for(lambda: not fake.link_ok(0))
            assert fake.speed(0) == 0.0 and fake.link_lost_events(0) == events + 1
            poll(
                backend, lambda s: "LINK_LOST" in backend.stats()["last_error"] and s.velocities[0] == 0.0
            )  # reported by the controller, and its reports show the wheel stopped


def test_runtime_drives_the_fake_robot(tomasi):
    """End to end: BaseRuntime + SerialBackend + fake controllers. A forward command moves the
    odometry forward, and after the stop the odometry equals the forward kinematics of the
    counts the controllers integrated."""
    with FakeController.for_robot(tomasi, report_period=REPORT) as fake:
        with SerialBackend(tomasi, fake.path, link_timeout=PATIENT) as backend:
            backend.wait_ready(PATIENT)
            start = np.array([fake.ticks(i) for i in range(3)])
            rt = BaseRuntime(tomasi, backend, cmd_vel_timeout=0.0)
            last = []

            def drive(twist, until, timeout=2 * PATIENT):
                deadline = time.monotonic() + timeout
                while not until():
                    assert time.monotonic() < deadline, f"pose {rt.pose}, stats {backend.stats()}"
                    t = time.monotonic()
                    rt.command(twist, t)
                    last[:] = [rt.step(t)]
                    time.sleep(0.005)

            def angles():
                return (np.array([fake.ticks(i) for i in range(3)]) - start) * TWO_PI / 600

            drive((0.2, 0.0, 0.0), lambda: rt.pose[0] > 0.04)
            drive((0.0, 0.0, 0.0), lambda: all(fake.speed(i) == 0.0 for i in range(3)))
            # stopped: step until the odometry has consumed the controllers' final counts
            drive((0.0, 0.0, 0.0), lambda: np.allclose(last[0].state.positions, angles(), atol=1e-12))
            final = angles()
            x, y, th = rt.pose
            assert np.allclose((x, y, th), tomasi.fk(final).twist, atol=1e-3)
            assert x > 0.04 and abs(y) < 2e-3 and abs(th) < 1e-2
            assert backend.stats()["link_lost"] is False


def test_protocol_timing_is_the_default(tomasi):
    with FakeController.for_robot(tomasi) as fake:
        with SerialBackend(tomasi, fake.path) as backend:
            t = load_protocol().timing
            assert (backend.link_timeout, backend.connect_timeout, backend.heartbeat_period) == (
                t.link_timeout,
                t.connect_timeout,
                t.heartbeat_period,
            )
            assert backend.baud == 115200


@pytest.mark.parametrize("baud", [0, -5, 49, 12_000_001, 10**20, 115200.0, True, "115200"])
def test_a_baud_rate_no_uart_runs_at_is_refused_before_a_port_opens(tomasi, baud):
    """Baud 0 or 1e20 went to pyserial and failed as a link error; 50 (POSIX B50) to 12 Mbaud
    (FTDI FT232H) are the rates of UARTs, whole numbers."""
    from omnikin.errors import InputError

    with pytest.raises(InputError, match=r"^serial back-end: baud: the baud rate must be a whole number from 50 to"):
        SerialBackend(tomasi, "/dev/omnikin-no-such-port", baud)
