"""A simulated wheel controller speaking the omnikin protocol on a pseudo-terminal.

:class:`FakeController` opens a pty (``os.openpty``), gives its device path (:attr:`path`) to
whoever plays the host (:class:`~.serial_backend.SerialBackend`, a terminal program) and,
in a thread, behaves like the firmware of ``firmware/omnikin_wheel``: it holds the speed last
commanded to each of its wheels while the link is alive, integrates it into an encoder count
(ideal speed control), sends ENCODER_REPORT every ``report_period`` and HEARTBEAT every
``heartbeat_period``, announces itself with ERROR_REPORT ``RESET``, and stops its motors and
reports ``LINK_LOST`` when the host has been silent for ``link_timeout``. One fake may host
several wheels (several controllers on one port); use one fake per port for one controller
per wheel.

Faults for tests (each applies to the next outgoing frames): :meth:`inject_garbage`,
:meth:`inject_corrupt`, :meth:`inject_short`, :meth:`inject_out_of_order`,
:meth:`inject_duplicate`, :meth:`inject_bad_version`, :meth:`inject_unknown_type`, and
:attr:`silent` (stop sending, keep listening: a broken TX wire or a hung board).

Without hardware::

    with FakeController.for_robot(load_robot("tomasi-omni3")) as fake:
        backend = SerialBackend(robot, fake.path)
"""

from __future__ import annotations

import collections
import os
import select
import threading
import time
import tty
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .protocol import (
    FrameEncoder,
    Protocol,
    StreamDecoder,
    encode,
    frame_bytes,
    load_protocol,
)


@dataclass
class FakeWheel:
    """One simulated wheel: protocol ``index``, encoder ticks per wheel radian (negative when the
    counter runs against the wheel's positive direction, i.e. ``invert``), starting ``count``."""

    index: int
    ticks_per_rad: float
    count: int = 0
    max_speed: float | None = None


class _WheelState:
    def __init__(self, w: FakeWheel):
        self.spec = w
        self.speed = 0.0  # commanded, rad/s (what the motor does: ideal control)
        self.angle = 0.0  # true wheel angle since start [rad]
        self.ticks_frac = 0.0  # accumulated ticks (float) since start
        self.offset = 0  # ticks added by advance()
        self.last_rx: float | None = None
        self.link_ok = False
        self.link_lost_events = 0
        self.commands: collections.deque = collections.deque(maxlen=10000)

    @property
    def ticks(self) -> int:
        """Unwrapped counter: start count + round(accumulated ticks) + jumps."""
        return self.spec.count + round(self.ticks_frac) + self.offset


class FakeController:
    """Simulated controller(s) on a pty (module docstring). Use as a context manager or
    :meth:`start` / :meth:`close`."""

    def __init__(
        self,
        wheels,
        *,
        protocol: Protocol | None = None,
        report_period: float | None = None,
        heartbeat_period: float | None = None,
        link_timeout: float | None = None,
        announce_reset: bool = True,
        seed: int = 0,
        tick: float = 0.001,
    ):
        self.protocol = p = protocol or load_protocol()
        wheels = list(wheels)
        if not wheels or len({w.index for w in wheels}) != len(wheels):
            raise InputError("fake controller: expected wheels with distinct indices")
        self.report_period = report_period or p.timing.report_period
        self.heartbeat_period = heartbeat_period or p.timing.heartbeat_period
        self.link_timeout = link_timeout or p.timing.link_timeout
        self.announce_reset = announce_reset
        self.tick = tick
        self.wheels = {w.index: _WheelState(w) for w in wheels}
        self.decoder = StreamDecoder(p, "host_to_controller")
        self.received: collections.deque = collections.deque(maxlen=10000)
        self._encoder = FrameEncoder(p)
        self._rng = np.random.default_rng(seed)
        self._faults: collections.deque = collections.deque()
        self._garbage = 0
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.silent = False
        self.frames_sent = 0
        self.bytes_dropped = 0
        self.suppressed = 0
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no line editing until the host configures its side
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        self._t0 = time.monotonic()

    @classmethod
    def for_robot(cls, robot, wheels=None, start_counts=None, **kwargs) -> FakeController:
        """Controllers for the robot's driven (encoded) wheels, or the named subset ``wheels``;
        ``start_counts`` maps wheel names to starting counter values."""
        names = robot.encoded_names if wheels is None else list(wheels)
        start_counts = start_counts or {}
        specs = []
        for n in names:
            w = robot.wheel(n)
            if w.encoder is None:
                raise InputError(f"fake controller: wheel {n!r} has no encoder")
            specs.append(
                FakeWheel(
                    robot.rolling_index([n])[0], 1.0 / w.encoder.rad_per_tick, int(start_counts.get(n, 0)), w.max_speed
                )
            )
        return cls(specs, **kwargs)

    # --- life cycle ------------------------------------------------------------------------------
    def start(self) -> FakeController:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="omnikin-fake-controller", daemon=True)
            self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass
        self._master = self._slave = -1

    stop = close

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    # --- observation -----------------------------------------------------------------------------
    def speed(self, index: int) -> float:
        """Speed [rad/s] the wheel turns at now (last command; 0 when the link is lost)."""
        with self._lock:
            return self.wheels[index].speed

    def commands(self, index: int) -> list:
        """Every speed [rad/s] commanded to the wheel so far (last 10000)."""
        with self._lock:
            return list(self.wheels[index].commands)

    def ticks(self, index: int) -> int:
        """Unwrapped counter value (the reported count is this, wrapped to the counter width)."""
        with self._lock:
            return self.wheels[index].ticks

    def angle(self, index: int) -> float:
        """True wheel angle since start [rad] (without the jumps of :meth:`advance`)."""
        with self._lock:
            return self.wheels[index].angle

    def link_ok(self, index: int) -> bool:
        with self._lock:
            return self.wheels[index].link_ok

    def link_lost_events(self, index: int) -> int:
        with self._lock:
            return self.wheels[index].link_lost_events

    @property
    def faults_pending(self) -> int:
        """Injected faults (and queued error reports) not yet applied."""
        with self._lock:
            return len(self._faults) + (1 if self._garbage else 0)

    # --- test hooks ------------------------------------------------------------------------------
    def advance(self, index: int, ticks: int) -> None:
        """Jump the counter by ``ticks`` (as if the wheel had turned that far at once)."""
        with self._lock:
            self.wheels[index].offset += int(ticks)

    def inject_garbage(self, nbytes: int) -> None:
        """Send ``nbytes`` random bytes before the next frame."""
        with self._lock:
            self._garbage += int(nbytes)

    def _inject(self, kind: str, n: int) -> None:
        with self._lock:
            self._faults.extend([kind] * int(n))

    def inject_corrupt(self, n: int = 1) -> None:
        """Flip one payload bit of each of the next ``n`` frames (their CRC fails)."""
        self._inject("corrupt", n)

    def inject_short(self, n: int = 1) -> None:
        """Cut each of the next ``n`` frames after half its bytes."""
        self._inject("short", n)

    def inject_out_of_order(self, n: int = 1) -> None:
        """Give each of the next ``n`` frames a sequence number from the past."""
        self._inject("out_of_order", n)

    def inject_duplicate(self, n: int = 1) -> None:
        """Send each of the next ``n`` frames twice."""
        self._inject("duplicate", n)

    def inject_bad_version(self, n: int = 1) -> None:
        self._inject("bad_version", n)

    def inject_unknown_type(self, n: int = 1) -> None:
        self._inject("unknown_type", n)

    def simulate_reset(self, index: int, announce: bool = True) -> None:
        """The controller of wheel ``index`` restarts: counter to 0, its sequence numbers from 0,
        ERROR_REPORT RESET first (the wheel itself does not move). ``announce=False``: the RESET
        frame is lost on the wire."""
        with self._lock:
            w = self.wheels[index]
            w.offset -= w.ticks
            self._encoder.reset(index)
            if announce:
                self._faults.appendleft(("error", index, "RESET", "restart"))

    def send_error(self, index: int, code: str, text: str = "") -> None:
        """Send an ERROR_REPORT (code name) in the thread's next cycle."""
        with self._lock:
            self._faults.append(("error", index, code, text))

    # --- thread ----------------------------------------------------------------------------------
    def _now_us(self, now: float) -> int:
        return int((now - self._t0) * 1e6) & 0xFFFFFFFF

    def _run(self) -> None:
        last = time.monotonic()
        next_report = next_hb = last
        if self.announce_reset:
            with self._lock:
                for i in self.wheels:
                    self._emit(
                        "ERROR_REPORT", wheel=i, code=self.protocol.error_code("RESET"), text="fake controller start"
                    )
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self._master], [], [], self.tick)
            except (OSError, ValueError):
                break
            now = time.monotonic()
            if ready:
                try:
                    data = os.read(self._master, 4096)
                except (BlockingIOError, InterruptedError):
                    data = b""
                except OSError:  # EIO: no one has the slave open (cannot happen while we hold it)
                    data = b""
                    time.sleep(self.tick)
                for msg in self.decoder.feed(data):
                    self._on_host(msg, now)
            with self._lock:
                dt = now - last
                for w in self.wheels.values():
                    w.angle += w.speed * dt
                    w.ticks_frac += w.speed * dt * w.spec.ticks_per_rad
                    if w.link_ok and w.last_rx is not None and now - w.last_rx > self.link_timeout:
                        w.link_ok = False
                        w.speed = 0.0
                        w.link_lost_events += 1
                        self._emit(
                            "ERROR_REPORT",
                            wheel=w.spec.index,
                            code=self.protocol.error_code("LINK_LOST"),
                            text="host silent; motor stopped",
                        )
                last = now
                while self._faults and isinstance(self._faults[0], tuple):
                    _, i, code, text = self._faults.popleft()
                    self._emit("ERROR_REPORT", wheel=i, code=self.protocol.error_code(code), text=text)
                if now >= next_report:
                    for w in self.wheels.values():
                        self._emit(
                            "ENCODER_REPORT",
                            wheel=w.spec.index,
                            time_us=self._now_us(now),
                            count=w.ticks,
                            speed=w.speed,
                        )
                    next_report = max(next_report + self.report_period, now)
                if now >= next_hb:
                    for w in self.wheels.values():
                        status = (self.protocol.status_bit("LINK_OK") if w.link_ok else 0) | (
                            self.protocol.status_bit("MOTOR_ENABLED") if w.link_ok else 0
                        )
                        self._emit("HEARTBEAT", wheel=w.spec.index, status=status, time_us=self._now_us(now))
                    next_hb = max(next_hb + self.heartbeat_period, now)

    def _on_host(self, msg, now: float) -> None:
        with self._lock:
            self.received.append(msg)
            w = self.wheels.get(msg.wheel)
            if w is None:  # another controller's frame on a shared bus
                return
            w.last_rx = now
            w.link_ok = True
            if msg.name == "SPEED_CMD":
                speed = float(msg.fields["speed"])
                w.commands.append(speed)
                limit = w.spec.max_speed
                if limit is not None and abs(speed) > limit:
                    speed = float(np.clip(speed, -limit, limit))
                    self._emit(
                        "ERROR_REPORT",
                        wheel=msg.wheel,
                        code=self.protocol.error_code("SPEED_CLAMPED"),
                        text=f"{msg.fields['speed']:.3f} rad/s",
                    )
                w.speed = speed

    def _emit(self, name: str, **values) -> None:
        """Encode (with the next pending fault) and send one frame; called with the lock held or
        from the thread before others can see the fake."""
        p = self.protocol
        fault = self._faults.popleft() if self._faults and not isinstance(self._faults[0], tuple) else None
        if fault == "out_of_order":
            seq = (self._encoder.peek(values["wheel"]) - 2) % 256
            frame = encode(name, seq, p, **values)
        else:
            frame = self._encoder.encode(name, **values)
        if fault == "corrupt":
            b = bytearray(frame)
            k = p.header_size + int(self._rng.integers(len(frame) - p.header_size - 2))
            b[k] ^= 1 << int(self._rng.integers(8))
            frame = bytes(b)
        elif fault == "short":
            frame = frame[: len(frame) // 2]
        elif fault == "duplicate":
            frame = frame + frame
        elif fault in ("bad_version", "unknown_type"):
            body = frame[p.header_size : -2]
            unused = next(i for i in range(255, 0, -1) if i not in p.by_id)
            frame = frame_bytes(
                p,
                unused if fault == "unknown_type" else frame[3],
                frame[4],
                body,
                version=p.version + 1 if fault == "bad_version" else None,
            )
        if self._garbage:
            frame = self._rng.integers(0, 256, self._garbage, dtype=np.uint8).tobytes() + frame
            self._garbage = 0
        self._send(frame)

    def _send(self, data: bytes) -> None:
        if self.silent:
            self.suppressed += 1
            return
        try:
            n = os.write(self._master, data)
        except (BlockingIOError, InterruptedError):
            n = 0
        except OSError:
            n = 0
        self.bytes_dropped += len(data) - n
        self.frames_sent += 1
