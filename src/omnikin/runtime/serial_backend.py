"""Wheel back-end over serial links to wheel controllers (``docs/protocol.md``).

:class:`SerialBackend` implements the :class:`~omnikin.runtime.backends.WheelBackend`
interface with the omnikin wheel protocol (:mod:`.protocol`), through pyserial
(``pip install "omnikin[serial]"``). Ports are pyserial URLs or device paths
(``/dev/ttyUSB0``, ``COM3``, a pty such as ``/dev/pts/5``, ``loop://``).

Wheels and ports. The driven wheels are the robot's rolling wheels with an encoder, in file
order. A wheel's protocol index is its position among the robot's rolling wheels
(``robot.rolling_names``), the position of its speed in ``write``. ``ports`` is

* one port (``str``): every wheel's controller on it (one board for all wheels, or several
  controllers on a shared bus); frames carry the wheel index;
* a list with one port per driven wheel, in file order (one microcontroller per wheel, as the
  Arduino Nanos of the seed robot); a port may appear several times;
* a dict ``{wheel name: port}`` covering every driven wheel.

A frame from a wheel that does not belong to the port it arrived on is counted as
``misrouted`` and ignored.

Time. As everywhere in the runtime, every call carries the caller's time [s]; the link
timeout and the heartbeat period are measured on it, and ``WheelState.t`` is the time of the
``read`` call. Positions are the latest reported counts, unwrapped (counter of
``counter_bits`` bits, :func:`omnikin.odometry.counters.wrap_scalar`) and converted with each wheel's
encoder (``ticks_per_rev``, ``gear_ratio``, ``invert``); the first report of a wheel is its
zero, and an ERROR_REPORT ``RESET`` (the controller restarted, its counter from 0) re-zeroes
the counter without moving the angle. Velocities are the controllers' measured speeds.

Link loss. Each wheel must send a valid frame (report, heartbeat or error) at least every
``link_timeout`` [s] (the first within ``connect_timeout`` after the first call: boards such as
the Nano reset when their port opens). Otherwise, or when a port fails, the link is lost: the
back-end sends zero speeds to every wheel at once and from then on, whatever ``write`` is given,
and every ``read`` raises :class:`LinkLostError` naming the wheel and port, until
:meth:`SerialBackend.reconnect` (reopens the ports, then re-arms) or
:meth:`SerialBackend.reset_link` (re-arms only). After re-arming, the controllers must be heard
from again within ``connect_timeout``; their counts continue from the angles held at the loss
(motion during the outage is not counted: a controller may have restarted). ``write`` never
raises for link problems (the node's stop path calls it). Heartbeats go to every wheel at least
every ``heartbeat_period`` [s].

Steerable wheels are not supported: protocol version 1 carries wheel speeds only.
"""

from __future__ import annotations

import os
import time

import numpy as np

from ..common.arrays import whole_problem
from ..common.messages import digits_apart
from ..errors import InputError, LinkError, LinkLostError, OmnikinError, ProtocolError
from ..kinematics.robot import Robot
from ..odometry.counters import wrap_scalar
from .backends import WheelState
from .protocol import FrameEncoder, Protocol, StreamDecoder, load_protocol

BAUD_RANGE = (50, 12_000_000)
"""Baud rates of a serial link [bit/s]: from 50, the slowest rate of POSIX terminals (``B50``),
to 12 Mbaud, the fastest USB-serial bridges (FTDI FT232H). Beyond them no UART runs: a rate
outside is a typo, refused before a port is opened."""


def check_baud(baud, name: str = "baud") -> int:
    """``baud`` [bit/s] as an int if it is a whole number in :data:`BAUD_RANGE`, else an
    :class:`~omnikin.errors.InputError` naming ``name`` (``--baud``)."""
    problem = whole_problem(baud, *BAUD_RANGE)
    if problem:
        raise InputError(f"{name}: the baud rate {problem} (the rates of UARTs)")
    return int(baud)


def _require_serial():
    try:
        import serial
    except ImportError:
        raise InputError('the serial back-end needs pyserial: pip install "omnikin[serial]"') from None
    return serial


class _Port:
    def __init__(self, url: str, link, decoder: StreamDecoder, wheels: list):
        self.url = url
        self.link = link
        self.decoder = decoder
        self.wheels = wheels


class SerialBackend:
    """Wheel controllers on serial ports (module docstring).

    Parameters
    ----------
    robot : Robot
        The robot; its rolling wheels with an encoder are driven (no steerable wheels).
    ports : str, os.PathLike, list or dict
        One port for every wheel, one per driven wheel in file order, or ``{wheel name: port}``
        (pyserial URLs or device paths; module docstring).
    baud : int, optional
        Line rate [bit/s] (default: ``protocol.yaml``).
    link_timeout : float, optional
        Longest silence [s] of a wheel before the link counts as lost (default: ``protocol.yaml``).
    connect_timeout : float, optional
        Time [s] a wheel has to be heard from first, and after re-arming (default:
        ``protocol.yaml``).
    heartbeat_period : float, optional
        Longest time [s] between two frames sent to a wheel (default: ``protocol.yaml``).
    write_timeout : float
        Longest blocked write [s] (then counted in ``tx_errors``).
    protocol : Protocol, optional
        The protocol description (default: the shipped ``protocol.yaml``).
    """

    MAX_READS_PER_PORT = 64  # reads of up to 4096 bytes per port and call: a flooding device cannot hang read()

    def __init__(
        self,
        robot: Robot,
        ports,
        baud: int | None = None,
        *,
        link_timeout: float | None = None,
        connect_timeout: float | None = None,
        heartbeat_period: float | None = None,
        write_timeout: float = 0.05,
        protocol: Protocol | None = None,
    ):
        self.robot = robot
        self.protocol = p = protocol or load_protocol()
        if robot.steerable:
            raise InputError(
                f"robot {robot.name!r}: the serial back-end (protocol version {p.version}) carries "
                f"wheel speeds only; steerable wheels {robot.steer_names} are not supported"
            )
        self.encoded = robot.encoded_names
        if not self.encoded:
            raise InputError(f"robot {robot.name!r}: the serial back-end needs driven wheels with an encoder")
        self.index = dict(zip(self.encoded, robot.rolling_index(self.encoded), strict=True))
        too_high = [n for n, i in self.index.items() if i > p.wheel_index_max]
        if too_high:
            raise InputError(f"robot {robot.name!r}: wheels {too_high} have indices beyond {p.wheel_index_max}")
        self._by_index = {i: n for n, i in self.index.items()}
        self.link_timeout = self._positive(link_timeout, p.timing.link_timeout, "link_timeout")
        self.connect_timeout = self._positive(connect_timeout, p.timing.connect_timeout, "connect_timeout")
        self.heartbeat_period = self._positive(heartbeat_period, p.timing.heartbeat_period, "heartbeat_period")
        self.baud = check_baud(baud if baud is not None else p.serial["baud"], "serial back-end: baud")
        self.port_of = self._map_ports(ports)
        self._rpt = dict(zip(self.encoded, robot.rad_per_tick(self.encoded).tolist(), strict=True))
        self._ticks = {n: 0 for n in self.encoded}
        self._last_count: dict[str, int | None] = {n: None for n in self.encoded}
        self._velocity = {n: 0.0 for n in self.encoded}
        self._last_rx: dict[str, float | None] = {n: None for n in self.encoded}
        self._status = {n: None for n in self.encoded}
        self._time_us = {n: None for n in self.encoded}
        self._reported: set[str] = set()
        self._encoder = FrameEncoder(p)
        self._start_t: float | None = None
        self._t: float | None = None
        self._hb_due: float | None = None
        self._lost: tuple | None = None  # (message, wheel, port)
        self._closed = False
        self.counters = {
            "writes": 0,
            "reads": 0,
            "tx_frames": 0,
            "tx_errors": 0,
            "heartbeats_tx": 0,
            "reports": 0,
            "heartbeats_rx": 0,
            "errors_rx": 0,
            "resets": 0,
            "misrouted": 0,
            "timeouts": 0,
            "port_errors": 0,
            "reconnects": 0,
        }
        self.last_error = ""
        self.last_tx_error = ""
        self._ports: dict[str, _Port] = {}
        self._write_timeout = write_timeout
        self._open_ports()

    # --- set-up ------------------------------------------------------------------------------
    @staticmethod
    def _positive(value, default, name):
        v = default if value is None else value
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v <= 0:
            raise InputError(f"serial back-end: {name} must be a time > 0 [s], got {value!r}")
        return float(v)

    def _map_ports(self, ports) -> dict:
        enc = self.encoded
        if isinstance(ports, (str, os.PathLike)):
            mapping = {n: os.fspath(ports) for n in enc}
        elif isinstance(ports, dict):
            unknown = [k for k in ports if k not in enc]
            missing = [n for n in enc if n not in ports]
            if unknown or missing:
                raise InputError(
                    f"serial back-end: ports must map every driven wheel {enc} to a port"
                    + (f"; unknown wheel(s) {unknown}" if unknown else "")
                    + (f"; missing {missing}" if missing else "")
                )
            mapping = {n: os.fspath(ports[n]) for n in enc}
        else:
            try:
                ports = [os.fspath(x) for x in ports]
            except TypeError:
                raise InputError(
                    f"serial back-end: ports must be a port, a list of ports or a dict {{wheel: port}}, got {ports!r}"
                ) from None
            if len(ports) == 1:
                ports = ports * len(enc)
            if len(ports) != len(enc):
                raise InputError(
                    f"serial back-end: {len(ports)} ports for {len(enc)} driven wheels {enc}; give one "
                    "port for all or one per driven wheel in file order"
                )
            mapping = dict(zip(enc, ports, strict=True))
        bad = [n for n, u in mapping.items() if not u]
        if bad:
            raise InputError(f"serial back-end: empty port name for wheel(s) {bad}")
        return mapping

    def _open_ports(self) -> None:
        for url in dict.fromkeys(self.port_of.values()):
            wheels = [n for n in self.encoded if self.port_of[n] == url]
            try:
                link = self._open(url, wheels)
            except OmnikinError:
                self.close()
                raise
            self._ports[url] = _Port(url, link, StreamDecoder(self.protocol, "controller_to_host"), wheels)

    def _open(self, url: str, wheels: list):
        """A pyserial link to ``url`` with the protocol's settings, or an error naming port and wheels."""
        serial = _require_serial()
        parity = {"none": serial.PARITY_NONE, "even": serial.PARITY_EVEN, "odd": serial.PARITY_ODD}
        ser = self.protocol.serial
        try:
            return serial.serial_for_url(
                url,
                baudrate=self.baud,
                bytesize=int(ser["bytesize"]),
                parity=parity[ser["parity"]],
                stopbits=ser["stopbits"],
                timeout=0,
                write_timeout=self._write_timeout,
            )
        except (serial.SerialException, OSError, ValueError) as exc:
            raise LinkError(f"serial back-end: cannot open {url!r} for wheel(s) {wheels}: {exc}") from None

    # --- WheelBackend ------------------------------------------------------------------------------
    def write(self, t: float, speeds, steer=None) -> None:
        """Send each driven wheel its speed [rad/s] (zero while the link is lost); never raises for the link."""
        n = len(self.robot.rolling_names)
        speeds = np.asarray(speeds, dtype=float)
        if speeds.shape != (n,) or not np.all(np.isfinite(speeds)):
            raise InputError(
                f"serial back-end: expected {n} finite wheel speeds for {self.robot.rolling_names}, got {speeds}"
            )
        self._clock(t)
        if self._lost is not None:
            speeds = np.zeros(n)
        try:
            self._send_speeds(speeds)
        except ProtocolError as exc:
            raise InputError(f"serial back-end: wheel speeds {speeds.tolist()} cannot be sent: {exc}") from None
        self._heartbeat(float(t))
        self.counters["writes"] += 1

    def read(self, t: float) -> WheelState:
        """Drain the ports, decode, check the link (raises :class:`LinkLostError`), return the latest state."""
        t = float(t)
        self._clock(t)
        self.counters["reads"] += 1
        if self._lost is None:
            self._drain(t)
        self._heartbeat(t)
        if self._lost is None:
            self._check_link(t)
        if self._lost is not None:
            message, wheel, port = self._lost
            raise LinkLostError(message, wheel, port)
        positions = np.array([self._ticks[n] * self._rpt[n] for n in self.encoded])
        velocities = np.array([self._velocity[n] for n in self.encoded])
        return WheelState(t, positions, velocities, None)

    def stats(self) -> dict:
        out = {
            "backend": "serial",
            "ports": ",".join(self._ports) or ",".join(dict.fromkeys(self.port_of.values())),
            "link_lost": self._lost is not None,
        }
        out.update(self.counters)
        total = None
        for port in self._ports.values():
            if total is None:
                total = type(port.decoder.stats)()
            total.add(port.decoder.stats)
        if total is not None:
            out.update(total.as_dict())
        out["last_error"] = self.last_error
        out["last_tx_error"] = self.last_tx_error
        out["waiting_for"] = ",".join(n for n in self.encoded if n not in self._reported)  # not heard since (re)arming
        if self._lost is not None:
            out["link_lost_reason"] = self._lost[0]
        if self._t is not None:
            for n in self.encoded:
                last_rx = self._last_rx[n]
                if last_rx is not None:
                    out[f"age_{n}"] = round(self._t - last_rx, 6)
        return out

    def close(self) -> None:
        """Command zero speeds (best effort) and close the ports; safe to call twice."""
        if self._closed:
            return
        self._closed = True
        try:
            self._send_speeds(np.zeros(len(self.robot.rolling_names)))
        except Exception:  # closing must not fail
            pass
        for port in self._ports.values():
            try:
                port.link.flush()
            except Exception:
                pass
            try:
                port.link.close()
            except Exception:
                pass

    # --- extras ----------------------------------------------------------------------------------
    @property
    def link_lost(self) -> bool:
        return self._lost is not None

    def reconnect(self) -> None:
        """Reopen every port (one that failed, or whose device came back under the same name
        without an error), then :meth:`reset_link`. Raises :class:`LinkError` naming the port
        when one cannot be reopened yet (the link then stays lost: try again later), or when the
        back-end was closed."""
        if self._closed:
            raise LinkError("serial back-end: closed; create a new one instead of reconnecting")
        for port in self._ports.values():
            try:
                port.link.close()
            except Exception:  # the old link may be dead anyway
                pass
            port.link = self._open(port.url, port.wheels)
        self.reset_link()
        self.counters["reconnects"] += 1

    def reset_link(self) -> None:
        """Leave the lost state: wheels are timed from the next call as if the ports had just opened."""
        self._lost = None
        self._start_t = None
        for n in self.encoded:
            self._last_rx[n] = None
            self._last_count[n] = None
        self._reported.clear()
        for port in self._ports.values():
            port.decoder.restart_stream()

    def wait_ready(self, timeout: float | None = None, clock=time.monotonic, poll: float = 0.005) -> WheelState:
        """Read (on ``clock``) until every driven wheel has reported once; raises
        :class:`LinkLostError` after ``timeout`` [s] (default ``connect_timeout``)."""
        timeout = self.connect_timeout if timeout is None else timeout
        t0 = clock()
        while True:
            state = self.read(clock())
            if len(self._reported) == len(self.encoded):
                return state
            if clock() - t0 > timeout:
                missing = [n for n in self.encoded if n not in self._reported]
                raise LinkLostError(
                    f"serial back-end: no encoder report from wheel(s) "
                    f"{[(n, self.port_of[n]) for n in missing]} within {timeout:g} s",
                    missing[0],
                    self.port_of[missing[0]],
                )
            time.sleep(poll)

    # --- internals -----------------------------------------------------------------------------
    def _clock(self, t: float) -> None:
        if self._start_t is None:
            self._start_t = float(t)
        self._t = float(t)

    def _send_speeds(self, speeds: np.ndarray) -> None:
        out: dict[str, list[bytes]] = {}
        for name in self.encoded:
            i = self.index[name]
            frame = self._encoder.encode("SPEED_CMD", wheel=i, speed=float(speeds[i]))
            out.setdefault(self.port_of[name], []).append(frame)
        for url, frames in out.items():
            self._send(url, b"".join(frames), len(frames))

    def _send(self, url: str, data: bytes, nframes: int) -> None:
        port = self._ports.get(url)
        if port is None:
            return
        try:
            port.link.write(data)
            self.counters["tx_frames"] += nframes
        except Exception as exc:  # serial.SerialTimeoutException, SerialException, OSError
            self.counters["tx_errors"] += 1
            self.last_tx_error = f"{url}: {exc}"

    def _heartbeat(self, t: float) -> None:
        if self._hb_due is not None and t < self._hb_due:
            return
        self._hb_due = t + self.heartbeat_period
        time_us = round(t * 1e6) & 0xFFFFFFFF
        for url, port in self._ports.items():
            frames = [
                self._encoder.encode("HEARTBEAT", wheel=self.index[n], status=0, time_us=time_us) for n in port.wheels
            ]
            self._send(url, b"".join(frames), len(frames))
            self.counters["heartbeats_tx"] += len(frames)

    def _drain(self, t: float) -> None:
        for url, port in self._ports.items():
            try:
                for _ in range(self.MAX_READS_PER_PORT):
                    data = port.link.read(4096)
                    if not data:
                        break
                    for msg in port.decoder.feed(data):
                        self._handle(port, msg, t)
            except Exception as exc:  # SerialException / OSError: unplugged, closed
                self.counters["port_errors"] += 1
                self._lose(
                    t,
                    f"serial back-end: link lost: port {url} failed ({exc}) for wheel(s) {port.wheels}; "
                    "all wheels commanded to zero",
                    port.wheels[0],
                    url,
                )
                return

    def _handle(self, port: _Port, msg, t: float) -> None:
        name = self._by_index.get(msg.wheel)
        if name is None or self.port_of[name] != port.url:
            self.counters["misrouted"] += 1
            return
        self._last_rx[name] = t
        if msg.restarted:  # the controller restarted and its RESET was lost: its counter is new
            self._last_count[name] = None
        if msg.name == "ENCODER_REPORT":
            count = msg.raw["count"]
            last = self._last_count[name]
            before = self._time_us[name]
            if before is not None and (msg.raw["time_us"] - before) % 2**32 >= 2**31:
                last = None  # the controller's clock went back: it restarted unannounced
            if last is not None:
                self._ticks[name] += wrap_scalar(count - last, self.protocol.counter_bits)
            self._last_count[name] = count
            self._velocity[name] = float(msg.fields["speed"])
            self._time_us[name] = msg.raw["time_us"]
            self._reported.add(name)
            self.counters["reports"] += 1
        elif msg.name == "HEARTBEAT":
            self._status[name] = msg.raw["status"]
            self.counters["heartbeats_rx"] += 1
        elif msg.name == "ERROR_REPORT":
            code = msg.raw["code"]
            text = msg.fields["text"]
            self.counters["errors_rx"] += 1
            self.last_error = f"{name} on {port.url}: {self.protocol.error_name(code)}" + (f" ({text})" if text else "")
            if code == self.protocol.error_code("RESET"):
                self._last_count[name] = None  # the next report's count is the new zero
                self._time_us[name] = None
                self.counters["resets"] += 1

    def _check_link(self, t: float) -> None:
        for name in self.encoded:
            last = self._last_rx[name]
            if last is None:
                start = t if self._start_t is None else self._start_t
                silent, limit, what = t - start, self.connect_timeout, "connect_timeout"
            else:
                silent, limit, what = t - last, self.link_timeout, "link_timeout"
            if silent > limit:
                url = self.port_of[name]
                never = " (never heard from it)" if last is None else ""
                self._lose(
                    t,
                    f"serial back-end: link lost: wheel {name!r} (index {self.index[name]}) on {url} "
                    f"sent no valid frame for {silent:.{digits_apart(silent, limit, 3)}g} s{never}, beyond {what} "
                    f"{limit:g} s; "
                    "all wheels commanded to zero",
                    name,
                    url,
                )
                self.counters["timeouts"] += 1
                return

    def _lose(self, t: float, message: str, wheel: str, url: str) -> None:
        self._lost = (message, wheel, url)
        self._send_speeds(np.zeros(len(self.robot.rolling_names)))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
