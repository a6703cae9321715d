"""The wheel-controller firmware built for the ATmega328P with ``firmware/Makefile``, as a user
builds it (``make -C firmware MOTOR=... WHEEL_INDEX=...``), into one temporary build folder per test
process (the Arduino core is compiled once and shared by every variant)."""

from __future__ import annotations

import atexit
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from support.paths import ROOT

FIRMWARE = ROOT / "firmware"
ARDUINO_CORE = Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h")
NANO_FLASH = 30720
"""Flash for the program on a Nano [bytes]: 32 KB less the 2 KB boot loader (boards.txt maximum_size)."""
NANO_RAM = 2048
"""SRAM of the ATmega328P [bytes]."""


def _missing() -> str | None:
    for tool, package in (("make", "make"), ("avr-gcc", "gcc-avr avr-libc"), ("avr-size", "binutils-avr")):
        if shutil.which(tool) is None:
            return f"{tool} not found (apt-get install {package})"
    if not ARDUINO_CORE.is_file():
        return f"no Arduino core at {ARDUINO_CORE.parent} (apt-get install arduino-core-avr)"
    return None


AVR_MISSING = _missing()
"""Why the firmware cannot be built here (one line), or None."""

_build_dir: Path | None = None


def build_dir() -> Path:
    """This process's build folder (removed when it exits)."""
    global _build_dir
    if _build_dir is None:
        _build_dir = Path(tempfile.mkdtemp(prefix="omnikin-fw-"))
        atexit.register(shutil.rmtree, _build_dir, True)
    return _build_dir


def make(*targets: str, **variables: str | int) -> subprocess.CompletedProcess:
    """``make -C firmware TARGETS VAR=value ...`` with BUILD set to :func:`build_dir` unless given;
    output captured (text), never raises on failure."""
    variables.setdefault("BUILD", str(build_dir()))
    return subprocess.run(
        ["make", "--no-print-directory", "-C", str(FIRMWARE), *targets, *(f"{k}={v}" for k, v in variables.items())],
        capture_output=True,
        text=True,
        timeout=600,
    )


@dataclass(frozen=True)
class Firmware:
    """One built variant: its ELF and HEX, and its sections' sizes [bytes] from ``avr-size -A``."""

    elf: Path
    hex: Path
    sections: dict[str, int]

    @property
    def flash(self) -> int:
        """Program memory [bytes]: code and the initial values of data (.text + .data)."""
        return self.sections.get(".text", 0) + self.sections.get(".data", 0)

    @property
    def static_ram(self) -> int:
        """RAM taken before the program runs [bytes]: .data + .bss + .noinit."""
        return sum(self.sections.get(s, 0) for s in (".data", ".bss", ".noinit"))


def firmware(motor: str = "stepper", wheel: int = 0, defines: str = "") -> Firmware:
    """Build (or reuse) the firmware variant; raises AssertionError with make's output if it fails."""
    done = make("firmware", MOTOR=motor, WHEEL_INDEX=wheel, DEFINES=defines)
    assert done.returncode == 0, f"make failed ({done.returncode}):\n{done.stdout}\n{done.stderr}"
    out = build_dir() / f"{motor}-w{wheel}"
    if defines:  # another -D set: its own folder, so that variants built in one session do not clash
        dest = build_dir() / f"{motor}-w{wheel}-{abs(hash(defines)):x}"
        shutil.rmtree(dest, ignore_errors=True)
        shutil.copytree(out, dest)
        out = dest
    sections = {}
    for line in (out / "size.txt").read_text().splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0].startswith(".") and parts[1].isdigit():
            sections[parts[0]] = int(parts[1])
    return Firmware(out / "omnikin_wheel.elf", out / "omnikin_wheel.hex", sections)


def symbol(elf: Path, name: str) -> tuple[int, int]:
    """(SRAM address in the data space, size) of a variable of the firmware, from ``avr-nm``."""
    out = subprocess.run(["avr-nm", "-S", "-C", str(elf)], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[3] == name and parts[2].lower() in "bd":
            return int(parts[0], 16) - 0x800000, int(parts[1], 16)
    raise AssertionError(f"no variable {name} in {elf}")
