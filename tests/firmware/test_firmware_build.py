"""``firmware/Makefile`` builds the wheel controller for the Arduino Nano (ATmega328P, 16 MHz) with
Debian's avr-gcc and Arduino core: both motor variants, any wheel index, an ELF and an Intel HEX
that fit the Nano, and one-line refusals of settings that cannot be built."""

from __future__ import annotations

import subprocess

import pytest

from firmware_build import AVR_MISSING, NANO_FLASH, NANO_RAM, firmware, make

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
    ],
)
def test_settings_that_cannot_be_built_are_refused_in_one_line(variables, expected):
    done = make("firmware", **variables)
    assert done.returncode != 0
    assert expected in done.stderr, done.stderr
