"""The simulated Arduino Nano board for the firmware tests: builds ``firmware/simboard/simboard.c``
(libsimavr 1.6) and runs it as a process driven through its stdin/stdout JSON protocol, its UART
on a pseudo-terminal (``SimBoard.path``). ``simboard --help`` documents pins, models and commands."""

from __future__ import annotations

import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from support.firmware_build import make

HEADER = Path("/usr/include/simavr/sim_avr.h")
READY_S = 10.0
"""How long the board may take to load a firmware and report ``ready`` [s] (milliseconds here)."""
COMMAND_S = 10.0
"""How long a command may wait for its answer [s] (the board polls stdin every 100 us simulated)."""
QUIT_S = 10.0
"""How long ``quit`` may take before the process is killed [s]."""
RUN_S = 120.0
"""How long a lockstep ``run`` of one simulated second may take [s of wall time] before the test
gives up: a hang guard only (the board runs about 7 simulated seconds per wall second when the
machine is idle, and a busy machine only makes it later)."""
F_CPU = 16_000_000
"""The simulated ATmega328P's clock [Hz]: simulated cycles per second."""
RX_CHUNK = 510
"""The most bytes one ``rx`` command carries (``rx `` and two hex digits a byte: a command line
is at most 1024 characters)."""


def _missing() -> str | None:
    for tool in ("cc", "make", "avr-gcc"):
        if shutil.which(tool) is None:
            return f"{tool} not found on PATH (the simulated board needs cc, make, avr-gcc and libsimavr-dev)"
    if not HEADER.exists():
        return f"{HEADER} missing: install libsimavr-dev (simavr 1.6)"
    return None


SIMAVR_MISSING: str | None = _missing()
"""One line saying what is missing to build and run the simulated board, or ``None``."""


def build_simboard(build_dir: Path) -> Path:
    """Build the harness as ``firmware/Makefile`` does (``make -C firmware BUILD=build_dir
    simboard``; make rebuilds it only when the source changed); returns the executable's path."""
    done = make("simboard", BUILD=str(build_dir))
    if done.returncode != 0:
        raise RuntimeError(f"building the simulated board failed ({done.returncode}):\n{done.stdout}{done.stderr}")
    return build_dir / "simboard"


class SimBoard:
    """A running simulated board: ``SimBoard(exe, elf, *args, speed=1.0, pty=True)`` starts
    ``exe [args] --speed SPEED [--no-pty] elf`` and waits for its ``ready`` line. Use it as a
    context manager: leaving the block (also on a failure) quits the process, and kills it if
    it does not end, so no board outlives its test.

    ``lockstep=True`` starts ``exe [args] --lockstep elf``: the board waits at cycle 0 and runs
    only when told (:meth:`run`); the host's bytes reach its UART at the cycle the board is paused
    at (:meth:`rx`) and its UART output comes back with each run. Everything the chip does is
    then a function of the commands alone, whatever the pace of the machine: a test that drives
    the chip this way asserts in simulated time only."""

    def __init__(self, exe: Path, elf: Path, *args: str, speed: float = 1.0, pty: bool = True, lockstep: bool = False):
        self.lockstep = lockstep
        argv = [str(exe), *[str(a) for a in args]]
        if lockstep:
            argv.append("--lockstep")
        else:
            argv += ["--speed", repr(float(speed))]
            if not pty:
                argv.append("--no-pty")
        argv.append(str(elf))
        self._stderr = tempfile.TemporaryFile()
        self.process = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr)
        self._buffer = b""
        self.final: dict | None = None
        try:
            ready = self._read_line(READY_S)
        except Exception:
            self.close()
            raise
        if ready.get("event") != "ready":
            self.close()
            raise RuntimeError(f"simboard did not report ready: {ready}")
        self.path: str | None = ready["pty"]
        self.pid: int = ready["pid"]

    def __enter__(self) -> SimBoard:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def stderr(self) -> str:
        """What the board wrote on stderr so far."""
        self._stderr.seek(0)
        return self._stderr.read().decode(errors="replace")

    def _read_line(self, timeout: float) -> dict:
        """The next JSON line on the board's stdout, or an error naming the board's stderr."""
        out = self.process.stdout
        assert out is not None
        deadline = time.monotonic() + timeout
        while b"\n" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"simboard gave no answer in {timeout} s; stderr: {self.stderr()!r}")
            ready, _, _ = select.select([out], [], [], left)
            if ready:
                chunk = os.read(out.fileno(), 65536)
                if not chunk:
                    raise RuntimeError(f"simboard ended (status {self.process.poll()}); stderr: {self.stderr()!r}")
                self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        return json.loads(line)

    def command(self, line: str, timeout: float = COMMAND_S) -> dict:
        """Send one command line and return its JSON answer (events in between are skipped)."""
        return self.commands(line, timeout=timeout)[0]

    def commands(self, *lines: str, timeout: float = COMMAND_S) -> list[dict]:
        """Send several commands in one write, so the board answers them all at the same
        simulated instant (e.g. ``stats`` and a ``peek``), and return their answers in order."""
        if any("\n" in line for line in lines):
            raise ValueError("a command is one line: no newline inside")
        stdin = self.process.stdin
        assert stdin is not None
        stdin.write("".join(line + "\n" for line in lines).encode())
        stdin.flush()
        answers: list[dict] = []
        while len(answers) < len(lines):
            answer = self._read_line(timeout)
            if answer.get("event") != "halted":
                answers.append(answer)
        return answers

    def wait_final(self, timeout: float) -> dict:
        """Wait for the board to end by itself (``--duration``) and return its final stats line."""
        while self.final is None:
            line = self._read_line(timeout)
            if line.get("event") == "final":
                self.final = line
        self.process.wait(QUIT_S)
        return self.final

    def stats(self) -> dict:
        """The board's measurements (``simboard --help`` lists them)."""
        return self.command("stats")

    def clear(self) -> dict:
        """Restart the measurement window."""
        return self.command("clear")

    def peek(self, addr: int, n: int) -> bytes:
        """``n`` bytes of the chip's data memory from data-space address ``addr``."""
        answer = self.command(f"peek {addr:#x} {n}")
        if "error" in answer:
            raise ValueError(answer["error"])
        return bytes.fromhex(answer["hex"])

    def run(self, seconds: float) -> bytes:
        """Lockstep: run ``seconds`` of simulated time (rounded to whole cycles) and return the
        bytes the chip's UART sent since the previous run."""
        cycles = round(seconds * F_CPU)
        answer = self.command(f"run {cycles}", timeout=RUN_S * max(seconds, 0.1))
        if answer.get("ok") != "run":
            raise RuntimeError(f"simboard: run {cycles}: {answer}")
        return bytes.fromhex(answer["tx"])

    def rx(self, data: bytes) -> None:
        """Put ``data`` on the chip's RX line from the current cycle on (back to back at the line
        rate, after any bytes still queued)."""
        for i in range(0, len(data), RX_CHUNK):
            answer = self.command(f"rx {data[i : i + RX_CHUNK].hex()}")
            if answer.get("ok") != "rx":
                raise RuntimeError(f"simboard: rx: {answer}")

    def reset(self) -> dict:
        """Reset the chip (the program restarts; the shaft keeps its angle)."""
        return self.command("reset")

    def silence(self, on: bool) -> dict:
        """Cut (``True``) or restore the board-to-host UART wire."""
        return self.command(f"silence {'on' if on else 'off'}")

    def corrupt(self, direction: str, every: int) -> dict:
        """Flip one bit in every ``every``-th byte in ``direction`` ``tx`` or ``rx`` (0: off)."""
        return self.command(f"corrupt {direction} {every}")

    def close(self) -> dict | None:
        """Quit the board and return its final stats line (``None`` if it had to be killed)."""
        if self.process.poll() is None:
            try:
                assert self.process.stdin is not None
                self.process.stdin.write(b"quit\n")
                self.process.stdin.flush()
                while self.final is None:
                    line = self._read_line(QUIT_S)
                    if line.get("event") == "final":
                        self.final = line
            except (OSError, RuntimeError, TimeoutError, ValueError):
                pass
            try:
                self.process.wait(QUIT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                try:
                    stream.close()
                except OSError:
                    pass
        return self.final
