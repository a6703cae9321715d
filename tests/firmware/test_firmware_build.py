"""``firmware/Makefile`` builds the wheel controller for the Arduino Nano (ATmega328P, 16 MHz) with
Debian's avr-gcc and Arduino core: both motor variants, any wheel index, an ELF and an Intel HEX
that fit the Nano, and one-line refusals of settings that cannot be built."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from support.firmware_build import AVR_MISSING, FIRMWARE, NANO_FLASH, NANO_RAM, firmware, make

pytestmark = [pytest.mark.compiler, pytest.mark.skipif(AVR_MISSING is not None, reason=str(AVR_MISSING))]


def intel_hex_bytes(text: str) -> int:
    """Data bytes of an Intel HEX file, every record's checksum verified (the two's complement of
    the sum of its bytes, Intel's "Hexadecimal Object File Format Specification", rev. A)."""
    total = 0
    for n, line in enumerate(text.split(), 1):
        assert line.startswith(":"), f"line {n}: no record mark"
        rec = bytes.fromhex(line[1:])
        assert sum(rec) % 256 == 0, f"line {n}: bad checksum"
        assert rec[0] == len(rec) - 5, f"line {n}: length byte {rec[0]} for {len(rec) - 5} data bytes"
        if rec[3] == 0x00:
            total += rec[0]
    assert text.split()[-1] == ":00000001FF", "no end-of-file record"
    return total


@pytest.mark.parametrize("motor", ["stepper", "dc"])
def test_both_variants_build_into_an_elf_and_a_hex_that_fit_the_nano(motor):
    fw = firmware(motor)
    assert fw.elf.read_bytes()[:4] == b"\x7fELF"
    head = subprocess.run(["avr-objdump", "-f", str(fw.elf)], capture_output=True, text=True, check=True).stdout
    assert "architecture: avr:5" in head, head  # the ATmega328P's core (avr5)
    assert intel_hex_bytes(fw.hex.read_text()) == fw.flash  # the HEX holds exactly the program
    assert 1000 < fw.flash <= NANO_FLASH
    assert 100 < fw.static_ram < NANO_RAM // 2


def test_the_variant_is_chosen_at_build_time():
    """Only the stepper variant has a Timer1 compare-match A handler (vector 11 of the ATmega328P;
    vectors without a handler are weak aliases, "W", of avr-libc's __bad_interrupt)."""

    def vectors(elf):
        out = subprocess.run(["avr-nm", str(elf)], capture_output=True, text=True, check=True).stdout
        return {ln.split()[2] for ln in out.splitlines() if ln.split()[1] == "T" and "__vector_" in ln}

    assert "__vector_11" in vectors(firmware("stepper").elf)
    assert "__vector_11" not in vectors(firmware("dc").elf)


@pytest.mark.parametrize(
    "variables, expected",
    [
        ({"MOTOR": "servo"}, "MOTOR must be stepper or dc"),
        ({"WHEEL_INDEX": "255"}, "WHEEL_INDEX must be a whole number from 0 to 254"),
        ({"WHEEL_INDEX": "-1"}, "WHEEL_INDEX must be a whole number from 0 to 254"),
        ({"WHEEL_INDEX": "1; rm -rf x"}, "WHEEL_INDEX must be a whole number from 0 to 254"),
        ({"WHEEL_INDEX": "0'; touch pwned; echo '"}, "WHEEL_INDEX must be a whole number from 0 to 254"),
        ({"WHEEL_INDEX": "007"}, "WHEEL_INDEX must be a whole number from 0 to 254"),
        ({"DEFINES": "-UWHEEL_INDEX"}, "DEFINES takes -DNAME or -DNAME=VALUE words"),
        ({"DEFINES": "-DX='1'"}, "DEFINES takes -DNAME or -DNAME=VALUE words"),
        ({"DEFINES": "-O0"}, "DEFINES takes -DNAME or -DNAME=VALUE words"),
        ({"BUILD": ""}, "BUILD must be one word"),
        ({"BUILD": "/tmp/a b"}, "BUILD must be one word"),
        ({"BUILD": "."}, "BUILD must not be this folder or one that holds it"),
        ({"BUILD": "/"}, "BUILD must not be this folder or one that holds it"),
        ({"BUILD": "omnikin_wheel"}, "BUILD must not be inside the sources"),
        ({"DEFINES": "-DMAX_SPEED=-5.0f"}, "MAX_SPEED must be in (0, 1000] rad/s"),
        ({"DEFINES": "-DMAX_SPEED=NAN"}, "MAX_SPEED must be in (0, 1000] rad/s"),
        ({"DEFINES": "-DSTEP_ACCEL=-60.0f"}, "STEP_ACCEL must be > 0"),
        ({"DEFINES": "-DMICROSTEPS=0"}, "MICROSTEPS must be >= 1"),
        ({"DEFINES": "-DTICKS_PER_REV=0.0f"}, "TICKS_PER_REV must be >= 1"),
        ({"DEFINES": "-DSPEED_FILTER=2.0f"}, "SPEED_FILTER must be in (0, 1]"),
        ({"DEFINES": "-DCONTROL_PERIOD_US=7000UL"}, "CONTROL_PERIOD_US must divide"),
    ],
)
def test_settings_that_cannot_be_built_are_refused_in_one_line(variables, expected):
    """Refused before anything is built, by make, or by the compiler on the sketch's own checks
    (settings that would build into a controller that moves wrongly: a negative MAX_SPEED turned
    the wheel at a zero command, a negative STEP_ACCEL ran it away backwards)."""
    done = make("firmware", **variables)
    assert done.returncode != 0
    assert expected in done.stderr, done.stderr
    assert not (FIRMWARE / "pwned").exists() and not (FIRMWARE / "omnikin_wheel" / "stepper-w0").exists()


def test_clean_removes_what_the_build_made_and_nothing_else(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    assert make("firmware", BUILD=str(tmp_path)).returncode == 0
    assert (tmp_path / "stepper-w0" / "omnikin_wheel.hex").exists()
    assert make("clean", BUILD=str(tmp_path)).returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


# a user's files with the names and extensions of build products, beside them, inside their
# folders and in folders named like theirs
USER_FILES = (
    "mynotes.hex",
    "my.o",
    "simboard.c",
    "stepper-w0/mynotes.hex",
    "stepper-w0/old.o",
    "core-atmega328p/mine.o",
    "core-atmega328p/core.a.bak",
    "stepper-w0x/omnikin_wheel.hex",
    "stepper-w12-old/omnikin_wheel.elf",
    "dc-w1 copy/size.txt",
    "core-notes/core.a",
    "core-/flags.txt",
)


def test_clean_keeps_a_users_files_that_look_like_build_products(tmp_path):
    build = tmp_path / "build"
    assert make("firmware", BUILD=str(build)).returncode == 0
    products = sorted(p.relative_to(build) for p in build.rglob("*") if p.is_file() and p.name != ".lock")
    assert Path("stepper-w0/omnikin_wheel.hex") in products and Path("core-atmega328p/core.a") in products
    for name in USER_FILES:
        (build / name).parent.mkdir(parents=True, exist_ok=True)
        (build / name).write_text(f"the user's {name}")
    sketch = FIRMWARE / "omnikin_wheel"
    before = {p.name: p.read_bytes() for p in sketch.iterdir()}
    assert make("clean", BUILD=str(build)).returncode == 0
    for name in USER_FILES:
        assert (build / name).read_text() == f"the user's {name}", name
    assert not any((build / p).exists() for p in products), [str(p) for p in products if (build / p).exists()]
    assert {p.name: p.read_bytes() for p in sketch.iterdir()} == before  # the sources untouched


def test_two_makes_of_one_variant_into_one_folder_leave_the_hex_their_flags_name(tmp_path):
    """Two makes with other DEFINES at once: one waits for the other (a lock on the folder), so the
    HEX is the one a build with the DEFINES that flags.txt names makes on its own."""
    build = tmp_path / "shared"
    args = ["make", "--no-print-directory", "-C", str(FIRMWARE), "firmware", f"BUILD={build}"]
    runs = [subprocess.Popen([*args, f"DEFINES=-DMAX_SPEED={v}.0f"], stdout=subprocess.DEVNULL) for v in (10, 20)]
    assert [r.wait(600) for r in runs] == [0, 0]
    flags = (build / "stepper-w0" / "flags.txt").read_text()
    speed = "10" if "-DMAX_SPEED=10.0f" in flags else "20"
    alone = tmp_path / "alone"
    assert make("firmware", BUILD=str(alone), DEFINES=f"-DMAX_SPEED={speed}.0f").returncode == 0
    hex_file = "stepper-w0/omnikin_wheel.hex"
    assert (build / hex_file).read_bytes() == (alone / hex_file).read_bytes()
