"""Workloads for the firmware on its simulated chip (``simboard``): a host that drives one board over
its pseudo-terminal as omnikin's serial back-end would, at the protocol's rates or flat out, and
reads back what the board measured. Shared by tests/firmware and benchmarks/bench_firmware.py."""

from __future__ import annotations

import time
from dataclasses import dataclass

import serial

from firmware_build import Firmware, symbol
from omnikin.runtime.protocol import FrameEncoder, StreamDecoder
from simboard import SimBoard

F_CPU = 16_000_000
"""The Nano's clock [Hz]: simulated cycles per second."""
TOP_SPEED = 30.0
"""The firmware's MAX_SPEED [rad/s] (omnikin_wheel.ino default)."""


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


def parser_frames(board: SimBoard, fw: Firmware) -> int:
    """The firmware's count of valid frames received, modulo 2**16 (``parser.frames_ok`` of
    omnikin_protocol.h: after the 72-byte buffer and two one-byte fields; the AVR has no padding)."""
    addr, size = symbol(fw.elf, "parser")
    raw = board.peek(addr, size)
    offset = 72 + 2
    return int.from_bytes(raw[offset : offset + 2], "little")
