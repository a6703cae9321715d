"""Workloads for the firmware on its simulated chip (``simboard``): a host that drives one board as
omnikin's serial back-end would, at the protocol's rates or flat out, and reads back what the
board measured. Shared by tests/firmware and benchmarks/bench_firmware.py.

The board runs in lockstep (``simboard --lockstep``): the host puts its bytes on the chip's line
at chosen simulated times and lets simulated time pass by the amount it says. A host writing to
the board's pseudo-terminal on its own clock would hand the chip its bytes whenever the host's
scheduler let it: on a busy machine, several periods' commands at once; then what the chip
measured (how late a control step ran, how many steps it made in a second of the host's clock)
would be a measurement of the machine, not of the firmware."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from omnikin.runtime.protocol import FrameEncoder, StreamDecoder, load_protocol
from support.firmware_build import Firmware, symbol
from support.simboard import SimBoard

F_CPU = 16_000_000
"""The Nano's clock [Hz]: simulated cycles per second."""
CONTROL_PERIOD = 10e-3 * F_CPU
"""The firmware's CONTROL_PERIOD_US [cycles] (omnikin_wheel.ino default: 10 ms)."""
TOP_SPEED = 30.0
"""The firmware's MAX_SPEED [rad/s] (omnikin_wheel.ino default)."""
PPR = 600
"""Encoder pulses per wheel turn (the seed's encoders; simboard's default ``--ppr``)."""
STEPS_PER_RAD = 200 * 8 / (2 * math.pi)
"""Steps per wheel radian of the stepper variant (motor_stepper.h defaults: 200 steps x 8
microsteps, the wheel on the motor shaft)."""


REPORT_PERIOD = 0.02
"""The host's command period [s]: one SPEED_CMD per wheel every report period, as omnikin's serial
back-end sends them (the protocol's report_period)."""


@dataclass
class ChipLink:
    """The host side of one lockstep board's UART (``SimBoard(..., lockstep=True)``): frames go on
    the chip's RX line at the cycle the board is paused at, and the frames the chip sends come
    back decoded with every :meth:`run`. The host's bytes reach the chip at simulated times the
    test chooses, never at the times the host's scheduler happened to pick, so what the chip does
    with them is the same on an idle and on a busy machine."""

    board: SimBoard
    encoder: FrameEncoder
    decoder: StreamDecoder
    received: list

    @classmethod
    def open(cls, board: SimBoard) -> ChipLink:
        assert board.lockstep, "a ChipLink drives a lockstep board"
        return cls(board, FrameEncoder(), StreamDecoder(), [])

    def send(self, *frames: bytes) -> None:
        """Put ``frames`` on the chip's RX line now (back to back at the line rate)."""
        self.board.rx(b"".join(frames))

    def speed(self, wheel: int, speed: float) -> bytes:
        return self.encoder.encode("SPEED_CMD", wheel=wheel, speed=speed)

    def run(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass and decode what the chip sent meanwhile."""
        self.received += self.decoder.feed(self.board.run(seconds))


def every_phase(k: int) -> float:
    """Period ``k``'s place in the control schedule for :func:`drive` ``after_step``: 50 periods
    put the input at 50 evenly spread places of a control period, in a scrambled order."""
    return ((k * 37) % 50 + 0.5) / 50


def costly_garbage() -> bytes:
    """Bytes that cost the firmware's parser the most: one buffer's worth (the longest frame) with
    a candidate header every 6 bytes, each announcing the longest payload that still ends inside
    the buffer and none with a valid CRC. When the first fails, every later one is complete and
    is checked in the same call: about a dozen CRCs over up to 70 bytes for one received byte."""
    protocol = load_protocol()
    size = protocol.max_frame
    block = bytearray(i % 0x80 + 1 for i in range(size))  # no stray sync byte
    for i in range(0, size - protocol.header_size - 2, 6):
        length = min(protocol.max_payload, size - i - protocol.header_size - 2)
        block[i : i + 6] = bytes([*protocol.sync, protocol.version, 1, 0, length])
    return bytes(block)


def drive(
    link: ChipLink,
    speed: float,
    seconds: float,
    wheel: int = 0,
    bus: bool = True,
    after_step: Callable[[int], float] | None = None,
) -> None:
    """Command ``speed`` [rad/s] to ``wheel`` once every report period (20 ms of simulated time)
    for ``seconds`` of simulated time, with the commands of two other wheels on the same bus
    (``bus``), as a host driving three boards on one port would. The commands of period ``k`` go
    out at its start, or, with ``after_step``, ``after_step(k)`` control periods (0 to 1) after a
    control step (the probe's rising edge): where in the control schedule the chip gets its input."""
    for k in range(round(seconds / REPORT_PERIOD)):
        wait = 0.0
        if after_step is not None:
            stats = link.board.stats()
            step = stats["probe"]["last_rise"]  # the latest control step's cycle
            assert step > 0, "no control step yet"
            wait = ((step + after_step(k) * CONTROL_PERIOD - stats["cycle"]) % CONTROL_PERIOD) / F_CPU
            if wait:
                link.run(wait)
        frames = [link.speed(wheel, speed)]
        if bus:
            frames += [link.speed((wheel + 1) % 255, -speed), link.speed((wheel + 2) % 255, speed)]
        link.send(*frames)
        link.run(REPORT_PERIOD - wait)


def drive_through_garbage(exe: Path, fw: Firmware, motor: str, seconds: float) -> tuple[dict, int, int]:
    """A board of ``motor`` driven at the top speed for 0.5 s, then, for ``seconds`` of simulated
    time with a fresh measurement window, every 20 ms a SPEED_CMD of the top speed for wheel 0 and
    three buffers of :func:`costly_garbage`; returns the board's stats, the frames sent and the
    frames the firmware's parser accepted meanwhile."""
    garbage = costly_garbage()
    with SimBoard(exe, fw.elf, "--motor", motor, lockstep=True) as board:
        link = ChipLink.open(board)
        drive(link, TOP_SPEED, 0.5, bus=False)
        board.clear()
        before, sent = parser_frames(board, fw), 0
        for _ in range(round(seconds / REPORT_PERIOD)):
            link.send(link.speed(0, TOP_SPEED), garbage, garbage, garbage)
            sent += 1
            link.run(REPORT_PERIOD)  # 13 + 216 bytes take 19.5 ms on the line
        return board.stats(), sent, (parser_frames(board, fw) - before) % 2**16


def flood(link: ChipLink, fw: Firmware, n: int) -> int:
    """Send ``n`` SPEED_CMD frames for another wheel back to back (the line's full rate: 13 bytes a
    frame at the chip's 117647 baud, UBRR 16 with U2X, take 1.1 ms each) and return how many the
    firmware's parser accepted within the line time of the frames plus 50 ms of simulated time."""
    board = link.board
    before = parser_frames(board, fw)
    link.send(*(link.speed(1, 1.0) for _ in range(n)))  # another wheel's: parsed, then ignored
    link.run(n * 13 * 10 * 8 * 17 / F_CPU + 0.05)  # a byte: 10 bits of 8 x (UBRR 16 + 1) cycles
    return (parser_frames(board, fw) - before) % 2**16


def parser_frames(board: SimBoard, fw: Firmware) -> int:
    """The firmware's count of valid frames received, modulo 2**16 (``parser.frames_ok`` of
    omnikin_protocol.h: after the 72-byte buffer and two one-byte fields; the AVR has no padding)."""
    addr, size = symbol(fw.elf, "parser")
    raw = board.peek(addr, size)
    offset = 72 + 2
    return int.from_bytes(raw[offset : offset + 2], "little")


def control_lateness(probe: dict) -> float:
    """The longest delay of a control step behind its fixed-rate schedule that the probe's periods
    show [cycles]: a step late by d makes its period T + d and the next one T - d."""
    return max(probe["period_max"] - CONTROL_PERIOD, CONTROL_PERIOD - probe["period_min"])


def encoder_counts(board: SimBoard, fw: Firmware) -> tuple[int, int]:
    """The firmware's ``encoder_count`` and the count the shaft's quadrature state q calls for,
    floor((q + 3) / 4) (one count per pulse, docs/firmware.md), read at one simulated instant."""
    addr, _ = symbol(fw.elf, "encoder_count")
    peek, stats = board.commands(f"peek {addr:#x} 4", "stats")
    return int.from_bytes(bytes.fromhex(peek["hex"]), "little", signed=True), (stats["q"] + 3) // 4


def encoder_miscount(exe: Path, fw: Firmware, pulses_per_s: float, seconds: float, bus: bool = True) -> int:
    """Counts the firmware gained (+) or lost (-) against the shaft over ``seconds`` of simulated
    time, the shaft turning at a constant ``pulses_per_s`` (simboard ``--motor none
    --shaft-speed``). With ``bus``, a host drives this wheel at the top speed (the stepper
    variant's step interrupt runs at 7639 steps/s) with the commands of two other wheels on the
    bus every 20 ms, so the encoder interrupt waits behind the others; without, the chip only
    counts. Either end of the window may catch an edge whose interrupt has not run yet: +-1 is
    that, not a miscount."""
    omega = 2 * math.pi * pulses_per_s / PPR
    with SimBoard(exe, fw.elf, "--motor", "none", "--shaft-speed", repr(omega), lockstep=True) as board:
        link = ChipLink.open(board)
        link.run(0.1)  # setup() has attached the interrupt
        count0, due0 = encoder_counts(board, fw)
        for _ in range(round(seconds / REPORT_PERIOD)):
            if bus:
                link.send(link.speed(0, TOP_SPEED), link.speed(1, 1.0), link.speed(2, 1.0))
            link.run(REPORT_PERIOD)
        count1, due1 = encoder_counts(board, fw)
    return (count1 - count0) - (due1 - due0)
