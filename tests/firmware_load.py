"""Workloads for the firmware on its simulated chip (``simboard``): a host that drives one board over
its pseudo-terminal as omnikin's serial back-end would, at the protocol's rates or flat out, and
reads back what the board measured. Shared by tests/firmware and benchmarks/bench_firmware.py."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import serial

from firmware_build import Firmware, symbol
from omnikin.runtime.protocol import FrameEncoder, StreamDecoder, load_protocol
from simboard import SimBoard

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


@dataclass
class HostLink:
    """The host side of one board's UART: frames out, decoded frames in."""

    port: serial.Serial
    encoder: FrameEncoder
    decoder: StreamDecoder
    received: list

    @classmethod
    def open(cls, board: SimBoard) -> HostLink:
        assert board.path is not None, "the board runs without a pty"
        return cls(serial.Serial(board.path, 115200, timeout=0), FrameEncoder(), StreamDecoder(), [])

    def send(self, *frames: bytes) -> None:
        self.port.write(b"".join(frames))

    def speed(self, wheel: int, speed: float) -> bytes:
        return self.encoder.encode("SPEED_CMD", wheel=wheel, speed=speed)

    def poll(self) -> None:
        self.received += self.decoder.feed(self.port.read(65536))

    def close(self) -> None:
        self.port.close()


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


def drive(board: SimBoard, link: HostLink, speed: float, seconds: float, wheel: int = 0, bus: bool = True) -> None:
    """Command ``speed`` [rad/s] to ``wheel`` every report period (20 ms) for ``seconds`` of wall
    time, with the commands of two other wheels on the same bus (``bus``), as a host driving three
    boards on one port would."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        frames = [link.speed(wheel, speed)]
        if bus:
            frames += [link.speed((wheel + 1) % 255, -speed), link.speed((wheel + 2) % 255, speed)]
        link.send(*frames)
        link.poll()
        time.sleep(0.02)


def drive_through_garbage(exe: Path, fw: Firmware, motor: str, seconds: float) -> tuple[dict, int, int]:
    """A board of ``motor`` driven at the top speed for 0.5 s, then, for ``seconds`` of wall time
    with a fresh measurement window, every 20 ms a SPEED_CMD of the top speed for wheel 0 and
    three buffers of :func:`costly_garbage`; returns the board's stats, the frames sent and the
    frames the firmware's parser accepted meanwhile."""
    garbage = costly_garbage()
    with SimBoard(exe, fw.elf, "--motor", motor) as board:
        link = HostLink.open(board)
        try:
            drive(board, link, TOP_SPEED, 0.5, bus=False)
            board.clear()
            before, sent = parser_frames(board, fw), 0
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                link.send(link.speed(0, TOP_SPEED), garbage, garbage, garbage)
                sent += 1
                time.sleep(0.02)
            time.sleep(0.1)  # the last bytes are in (13 + 216 bytes take 20 ms on the line)
            return board.stats(), sent, (parser_frames(board, fw) - before) % 2**16
        finally:
            link.close()


def flood(board: SimBoard, link: HostLink, fw: Firmware, n: int) -> int:
    """Send ``n`` SPEED_CMD frames for another wheel back to back (the line's full rate: 13 bytes a
    frame at the chip's 117647 baud, UBRR 16 with U2X, take 1.1 ms each) and return how many the
    firmware's parser accepted, waiting up to 5 s of wall time for them."""
    before = parser_frames(board, fw)
    link.send(*(link.speed(1, 1.0) for _ in range(n)))  # another wheel's: parsed, then ignored
    parsed = 0
    for _ in range(100):
        time.sleep(0.05)
        link.poll()
        parsed = (parser_frames(board, fw) - before) % 2**16
        if parsed >= n:
            break
    return parsed


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
    --shaft-speed``). With ``bus``, the board runs in real time and a host drives this wheel at the
    top speed (the stepper variant's step interrupt runs at 7639 steps/s) with the commands of two
    other wheels on the bus, so the encoder interrupt waits behind the others; without, the chip
    only counts (as fast as the simulation goes). Either end of the window may catch an edge whose
    interrupt has not run yet: +-1 is that, not a miscount."""
    omega = 2 * math.pi * pulses_per_s / PPR
    with SimBoard(
        exe, fw.elf, "--motor", "none", "--shaft-speed", repr(omega), speed=1.0 if bus else 0.0, pty=bus
    ) as board:
        link = HostLink.open(board) if bus else None
        try:
            while board.stats()["time_s"] < 0.1:  # setup() has attached the interrupt
                time.sleep(0.01)
            count0, due0 = encoder_counts(board, fw)
            start = board.stats()["time_s"]
            while board.stats()["time_s"] < start + seconds:
                if link is not None:
                    link.send(link.speed(0, TOP_SPEED), link.speed(1, 1.0), link.speed(2, 1.0))
                    link.poll()
                time.sleep(0.02)
            count1, due1 = encoder_counts(board, fw)
        finally:
            if link is not None:
                link.close()
    return (count1 - count0) - (due1 - due0)
