"""The simulated Arduino Nano (firmware/simboard) measured against AVR test programs whose answers
follow in closed form from the ATmega328P's datasheet timings (tests/firmware/programs/*.c):
timer periods, instruction cycle counts, stack frames, UART frame times and the motor and encoder
models of ``simboard --help``."""

from __future__ import annotations

import contextlib
import json
import math
import os
import random
import select
import signal
import subprocess
import time
import tty
from pathlib import Path

import pytest

from support.firmware_build import symbol
from support.simboard import SIMAVR_MISSING, SimBoard, build_simboard

pytestmark = [pytest.mark.compiler, pytest.mark.skipif(SIMAVR_MISSING is not None, reason=SIMAVR_MISSING or "")]

PROGRAMS = Path(__file__).parent / "programs"
F_CPU = 16_000_000
RAMEND = 0x8FF
TIMER1_COMPA_VECTOR = 11
"""ATmega328P datasheet, table 12-6 (interrupt vectors): TIMER1 COMPA is vector 11."""


@pytest.fixture(scope="module")
def build(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("simboard")


@pytest.fixture(scope="module")
def exe(build) -> Path:
    return build_simboard(build)


def program(build: Path, name: str, *defines: str) -> Path:
    """Compile ``programs/NAME.c`` for the ATmega328P (no Arduino core) into an ELF."""
    elf = build / f"{name}{''.join(defines)}.elf"
    if not elf.exists():
        flags = [f"-D{d}" for d in defines]
        cmd = ["avr-gcc", "-mmcu=atmega328p", "-DF_CPU=16000000UL", "-Os", *flags, "-o", str(elf)]
        subprocess.run([*cmd, str(PROGRAMS / f"{name}.c")], check=True, capture_output=True, timeout=60)
    return elf


def u16(data: bytes, i: int = 0) -> int:
    return int.from_bytes(data[2 * i : 2 * i + 2], "little")


def run_for(exe: Path, elf: Path, seconds: float, *args: str, speed: float = 0.0) -> dict:
    """Run the board for ``seconds`` simulated seconds (as fast as it can unless ``speed``); its
    final stats."""
    with SimBoard(exe, elf, *args, "--duration", str(seconds), speed=speed, pty=False) as board:
        return board.wait_final(timeout=60)


# --------------------------------------------------------------------------- stepper and timers


def test_timer_toggled_step_pulses_are_exactly_two_compare_periods_apart_and_turn_the_shaft(exe, build):
    interval = 2 * (249 + 1) * 8  # CTC toggle: one rising edge per two compare matches
    final = run_for(exe, program(build, "step_toggle"), 0.1)
    steps = final["steps"]
    assert steps["interval_min"] == steps["interval_max"] == interval
    assert steps["interval_mean"] == interval and steps["interval_std"] == 0
    assert abs(steps["count"] - 0.1 * F_CPU / interval) <= 1
    assert steps["forward"] == steps["count"] and steps["backward"] == steps["ignored"] == 0
    assert final["angle"] == pytest.approx(steps["count"] * 2 * math.pi / (200 * 8), rel=1e-12)
    # the rotor runs one step behind the STEP edges (it turns at the step rate, it does not jump):
    # the encoder is between the states of the last two steps, floor(angle 4 ppr / 2 pi)
    assert (steps["count"] - 1) * 4 * 600 // (200 * 8) <= final["q"] <= steps["count"] * 4 * 600 // (200 * 8)
    assert final["transitions"] == final["q"] and final["enabled"] is True and final["dir"] == 1


def test_steps_with_dir_low_turn_backward_and_steps_with_enable_high_are_ignored(exe, build):
    back = run_for(exe, program(build, "step_toggle", "BACKWARD"), 0.05, "--ppr", "100")
    n = back["steps"]["count"]
    assert back["steps"]["backward"] == n > 0 and back["dir"] == 0
    assert back["angle"] == pytest.approx(-n * 2 * math.pi / 1600, rel=1e-12)
    assert -((n * 400 + 1599) // 1600) <= back["q"] <= -(((n - 1) * 400 + 1599) // 1600)  # floor, one step behind
    off = run_for(exe, program(build, "step_toggle", "DISABLED"), 0.05)
    assert off["steps"]["ignored"] == off["steps"]["count"] > 0
    assert off["angle"] == 0 and off["q"] == 0 and off["transitions"] == 0 and off["enabled"] is False


# --------------------------------------------------------------------------- probe and interrupts


def test_probe_period_and_high_time_are_the_counted_cycles_of_the_pulse_loop(exe, build):
    # the loop (avr-objdump): sbi (2) + 3000 delay + cbi (2) + 7000 delay + rjmp (2); the board
    # sees each pin write at the start of its instruction: high = 2 + 3000
    final = run_for(exe, program(build, "probe_pulse"), 0.1)
    probe = final["probe"]
    assert probe["period_min"] == probe["period_max"] == probe["period_mean"] == 10006
    assert probe["high_max"] == probe["high_mean"] == 3002
    assert abs(probe["count"] - 0.1 * F_CPU / 10006) <= 1


def test_isr_load_and_count_of_a_timer_interrupt_are_its_instruction_cycles_at_its_rate(exe, build):
    # per interrupt: the vector's jmp (3) + 500 busy + reti (4); simavr 1.6 enters a vector in 0
    # cycles (the real chip takes 4 more). Interrupts every OCR1A + 1 = 2000 cycles.
    seconds, period, per_isr = 0.1, 2000, 3 + 500 + 4
    final = run_for(exe, program(build, "isr_load"), seconds)
    vec = final["isr"][str(TIMER1_COMPA_VECTOR)]
    assert list(final["isr"]) == [str(TIMER1_COMPA_VECTOR)]
    assert seconds * F_CPU // period - 1 <= vec["count"] <= seconds * F_CPU // period
    assert vec["count"] * per_isr - per_isr < vec["cycles"] <= vec["count"] * per_isr
    assert final["isr_cycles"] == vec["cycles"]
    assert final["isr_cycles"] / final["window_cycles"] == pytest.approx(per_isr / period, abs=per_isr / 1e5)


def test_window_restarts_on_clear_and_counts_only_what_follows(exe, build):
    with SimBoard(exe, program(build, "isr_load"), lockstep=True) as board:
        board.run(0.05)
        assert board.clear()["ok"] == "clear"
        board.run(0.01)
        stats = board.stats()
        vec = stats["isr"].get(str(TIMER1_COMPA_VECTOR), {"count": 0, "cycles": 0})
        assert abs(vec["count"] - stats["window_cycles"] / 2000) <= 1
        assert stats["cycle"] > stats["window_cycles"]


# --------------------------------------------------------------------------- stack


def test_stack_bytes_is_the_lowest_stack_pointer_the_program_reached(exe, build):
    elf = program(build, "stack_depth")
    with SimBoard(exe, elf, lockstep=True) as board:
        board.run(0.01)
        stats, before, after, levels = board.commands(
            "stats",
            f"peek {symbol(elf, 'sp_before_alloca')[0]} 2",
            f"peek {symbol(elf, 'sp_after_alloca')[0]} 2",
            f"peek {symbol(elf, 'level_sp')[0]} 22",
        )
    sp_before, sp_after = u16(bytes.fromhex(before["hex"])), u16(bytes.fromhex(after["hex"]))
    level = [u16(bytes.fromhex(levels["hex"]), d) for d in range(11)]
    assert sp_after == sp_before - 300  # alloca(300) moves SP by exactly 300 bytes
    frames = {level[d + 1] - level[d] for d in range(10)}
    assert len(frames) == 1 and frames.pop() >= 24 + 2  # equal frames: 24 locals + return address at least
    assert stats["ramend"] == RAMEND
    assert stats["sp_min"] == level[0]  # the deepest level, recorded by the program
    assert stats["stack_bytes"] == RAMEND - level[0]


# --------------------------------------------------------------------------- UART


def read_exactly(fd: int, n: int, timeout: float = 10.0) -> bytes:
    data = b""
    deadline = time.monotonic() + timeout
    while len(data) < n and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.05)
        if ready:
            data += os.read(fd, n - len(data))
    return data


def nothing_arrives(fd: int, seconds: float) -> bool:
    ready, _, _ = select.select([fd], [], [], seconds)
    return not ready


@pytest.fixture()
def echo(exe, build):
    elf = program(build, "uart_echo")
    with SimBoard(exe, elf, speed=0) as board:
        fd = os.open(board.path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(fd)
        try:
            assert read_exactly(fd, 1) == b"B"  # the boot byte
            yield board, fd, elf
        finally:
            with contextlib.suppress(OSError):  # a test may have closed it
                os.close(fd)


def test_uart_echo_comes_back_at_the_line_rate_of_115200_baud(echo):
    board, fd, elf = echo
    payload = bytes(range(100))
    os.write(fd, payload)
    assert read_exactly(fd, 100) == payload
    count, first, last = (u16(board.peek(symbol(elf, name)[0], 2)) for name in ("received", "first_tick", "last_tick"))
    assert count == 100
    # 115200 baud with U2X: a bit is 8 (UBRR + 1) = 136 cycles, a byte 10 bits = 1360 cycles = 170
    # ticks of Timer1 at F_CPU / 8; the bytes were queued at once, so they arrive back to back
    assert (last - first) % 65536 == pytest.approx(99 * 170, abs=2)
    stats = board.stats()
    assert stats["baud"] == pytest.approx(F_CPU / 136)
    assert stats["rx_bytes"] == 100 and stats["tx_bytes"] == 101 and stats["rx_backlog_max"] >= 50


def test_corrupt_tx_flips_one_bit_per_byte_cycling_through_the_bit_indexes(echo):
    board, fd, _ = echo
    assert board.corrupt("tx", 1)["every"] == 1
    os.write(fd, bytes(8))
    assert read_exactly(fd, 8) == bytes(1 << k for k in range(8))
    assert board.stats()["corrupted_tx"] == 8
    board.corrupt("tx", 0)
    board.corrupt("rx", 2)  # every second byte the chip receives: bits 0, 1, ...
    os.write(fd, bytes(4))
    assert read_exactly(fd, 4) == bytes([0, 1, 0, 2])
    assert board.stats()["corrupted_rx"] == 2


def test_silence_drops_the_boards_output_and_reset_restarts_the_program(echo):
    board, fd, elf = echo
    board.silence(True)
    os.write(fd, b"abc")
    assert nothing_arrives(fd, 0.5)
    stats = board.stats()
    assert stats["rx_bytes"] == 3 and stats["tx_dropped"] == 3
    board.silence(False)
    os.write(fd, b"d")
    assert read_exactly(fd, 1) == b"d"
    assert board.reset()["ok"] == "reset"
    assert read_exactly(fd, 1) == b"B"  # the program started again
    assert u16(board.peek(symbol(elf, "received")[0], 2)) == 0


# --------------------------------------------------------------------------- encoder and DC motor


@pytest.mark.parametrize("omega", [10.0, -7.5])
def test_int0_counts_every_encoder_a_rising_edge_at_a_constant_shaft_speed(exe, build, omega):
    elf = program(build, "int0_counter")
    ppr = 600
    with SimBoard(exe, elf, "--motor", "none", "--shaft-speed", str(omega), lockstep=True) as board:
        board.run(0.1)
        stats, rising, b_high = board.commands(
            "stats", f"peek {symbol(elf, 'rising')[0]} 4", f"peek {symbol(elf, 'b_high')[0]} 4"
        )
    t = stats["cycle"] / F_CPU
    count = int.from_bytes(bytes.fromhex(rising["hex"]), "little")
    assert t > 0.05
    assert abs(count - math.floor(abs(omega) * t * ppr / (2 * math.pi))) <= 1
    assert stats["q"] == math.floor(omega * t * ppr * 4 / (2 * math.pi))
    assert stats["transitions"] == abs(stats["q"])
    # turning forward B is low at A's rising edge, turning backward it is high
    assert int.from_bytes(bytes.fromhex(b_high["hex"]), "little") == (0 if omega > 0 else count)


def encoder_levels(q: int) -> tuple[int, int]:
    """(A, B) of quadrature state q: A = [0,1,1,0][q mod 4], B = [0,0,1,1][q mod 4]."""
    return (0, 1, 1, 0)[q % 4], (0, 0, 1, 1)[q % 4]


def test_encoder_lines_keep_the_shaft_angle_across_a_chip_reset(exe, build):
    elf = program(build, "int0_counter")
    pind = 0x29  # PIND in data space
    args = ("--motor", "none", "--shaft-speed", "3", "--ppr", "1000")
    with SimBoard(exe, elf, *args, lockstep=True) as board:
        for _ in range(2):
            board.run(0.05)
            stats, pins = board.commands("stats", f"peek {pind} 1")
            level = int(pins["hex"], 16)
            assert ((level >> 2) & 1, (level >> 3) & 1) == encoder_levels(stats["q"])
            reset, pins, stats = board.commands("reset", f"peek {pind} 1", "stats")
            assert reset["ok"] == "reset" and stats["sp_min"] == RAMEND  # the program restarted
            level = int(pins["hex"], 16)
            assert ((level >> 2) & 1, (level >> 3) & 1) == encoder_levels(stats["q"])
            assert stats["q"] == math.floor(3 * stats["cycle"] / F_CPU * 4000 / (2 * math.pi))


def test_dc_motor_speed_follows_the_first_order_step_response(exe, build):
    top, tau, duty = 40.0, 0.05, 128 / 255
    final = run_for(exe, program(build, "dc_pwm"), tau, "--motor", "dc")
    # omega(t) = W u (1 - exp(-t/tau)); angle(t) = W u (t - tau (1 - exp(-t/tau))); the PWM
    # starts a few microseconds after reset and the model updates every 10 us: 30 us of lag
    lag = 30e-6
    omega = top * duty * (1 - math.exp(-1))
    assert final["time_s"] == pytest.approx(tau, abs=4 / F_CPU) and final["duty"] == pytest.approx(duty, abs=1e-6)
    assert final["omega"] == pytest.approx(omega, abs=top * duty * lag / tau)
    angle = top * duty * (tau - tau * (1 - math.exp(-1)))
    assert final["angle"] == pytest.approx(angle, abs=top * duty * lag)
    assert abs(final["q"] - math.floor(final["angle"] * 4 * 600 / (2 * math.pi))) <= 1


# --------------------------------------------------------------------------- lockstep


BYTE_CYCLES = 10 * 8 * (16 + 1)  # one 8N1 byte at UBRR 16 with U2X: 10 bits of 8 (UBRR + 1) cycles


def test_a_lockstep_board_runs_only_when_told_and_its_uart_is_on_the_command_channel(exe, build):
    """``--lockstep``: the board waits at cycle 0, a run of N cycles ends N cycles later (to within
    one instruction), a paused board stays where it is however long the host takes, and a byte
    given with ``rx`` at cycle C is readable at its stop bit, C + 10 bit times, and echoed in
    the next run's answer."""
    elf = program(build, "uart_echo")
    with SimBoard(exe, elf, lockstep=True) as board:
        assert board.stats()["cycle"] == 0
        assert board.run(0.001) == b"B"  # the boot byte
        paused = board.stats()["cycle"]
        assert F_CPU // 1000 <= paused <= F_CPU // 1000 + 4
        time.sleep(0.2)
        assert board.stats()["cycle"] == paused  # the host's time is not the chip's
        board.rx(b"xy")
        assert board.run((BYTE_CYCLES - 10) / F_CPU) == b""  # the first byte is still on the line
        assert board.run(3 * BYTE_CYCLES / F_CPU) == b"xy"
        later = board.stats()["cycle"] + 12345
        board.run(12345 / F_CPU)
        board.rx(b"z")
        assert board.run(3 * BYTE_CYCLES / F_CPU) == b"z"
        first, last = (u16(board.peek(symbol(elf, name)[0], 2)) for name in ("first_tick", "last_tick"))
        stats = board.stats()
    # Timer1 counts at F_CPU / 8: 'x' and 'z' were put on the line ``later - paused`` cycles apart
    # and become readable one byte time after that; the loop polls RXC0 every few cycles
    assert abs((last - first) % 2**16 - (later - paused) / 8) <= 1
    assert stats["rx_bytes"] == 3 and stats["tx_bytes"] == 4


def test_lockstep_refuses_what_it_cannot_do(exe, build, tmp_path):
    elf = program(build, "uart_echo")
    with SimBoard(exe, elf, speed=0, pty=False) as board:
        assert "only with --lockstep" in board.command("run 100")["error"]
    with SimBoard(exe, elf, lockstep=True) as board:
        for line in ("run 0", "run -5", "run x", "rx 1", "rx zz", "rx " + "00" * 511):
            answer = board.command(line)
            assert set(answer) == {"error"} and len(answer["error"]) < 200, line
        assert board.run(0.001) == b"B"
    link = tmp_path / "board"
    done = subprocess.run([str(exe), "--lockstep", "--link", str(link), str(elf)], capture_output=True, text=True)
    assert done.returncode == 2 and done.stderr.startswith("simboard: error: --link") and not link.exists()


# --------------------------------------------------------------------------- pacing and ending


@pytest.mark.parametrize("speed", [1.0, 2.0])
def test_speed_paces_simulated_time_against_the_wall_clock(exe, build, speed):
    seconds = 0.4
    start = time.monotonic()
    final = run_for(exe, program(build, "isr_load"), seconds, speed=speed)
    wall = time.monotonic() - start
    assert final["time_s"] == pytest.approx(seconds, abs=4 / F_CPU)  # ends after an instruction
    # never ahead of the wall clock (a busy machine can only make it later); how closely it keeps
    # up is the machine's pace: benchmarks/bench_firmware.py reports it ("pacing")
    assert seconds / speed - 0.02 <= final["wall_s"] <= wall and final["behind_s"] >= 0


@pytest.mark.parametrize("how", ["eof", "sigterm", "sigint"])
def test_end_of_input_and_signals_end_the_board_with_a_final_stats_line(exe, build, how):
    board = SimBoard(exe, program(build, "step_toggle"), speed=0, pty=False)
    try:
        process = board.process
        assert process.stdin is not None
        if how == "eof":
            process.stdin.close()
        else:
            process.send_signal(signal.SIGTERM if how == "sigterm" else signal.SIGINT)
        final = board.wait_final(timeout=10)
        assert final["event"] == "final" and process.returncode == 0
    finally:
        board.close()


def test_with_a_duration_the_board_runs_it_whatever_its_input(exe, build):
    """``simboard --duration 0.2 ... < /dev/null`` (as from a script or the README): no commands
    is not a request to stop before the duration ends."""
    done = subprocess.run(
        [str(exe), "--speed", "0", "--no-pty", "--duration", "0.2", str(program(build, "step_toggle"))],
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=60,
    )
    final = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 0 and final["event"] == "final"
    assert final["time_s"] == pytest.approx(0.2, abs=4 / F_CPU)


def test_a_host_may_close_and_reopen_the_pty(echo):
    board, fd, _ = echo
    os.close(fd)  # no host
    time.sleep(0.1)
    again = os.open(board.path, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(again, b"xy")
        assert read_exactly(again, 2) == b"xy"
    finally:
        os.close(again)
    assert board.stats()["rx_bytes"] == 2


# --------------------------------------------------------------------------- usage and commands


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["--motor", "servo"], "--motor"),
        (["--ppr", "0"], "--ppr"),
        (["--ppr", "12x"], "--ppr"),
        (["--steps-per-rev", "-3"], "--steps-per-rev"),
        (["--microsteps", "1e9"], "--microsteps"),
        (["--dc-tau", "0"], "--dc-tau"),
        (["--dc-top-speed", "inf"], "--dc-top-speed"),
        (["--shaft-speed", "nan"], "--shaft-speed"),
        (["--shaft-speed", "1e6"], "--shaft-speed"),
        (["--speed", "-1"], "--speed"),
        (["--duration", "0"], "--duration"),
        (["--bogus"], "--bogus"),
        (["--ppr"], "--ppr"),
        (["--no-pty", "--link", "x"], "--link"),
        ([], "FIRMWARE"),
    ],
)
def test_each_bad_option_gives_one_line_naming_it_and_exit_2(exe, build, args, named):
    elf = [] if not args else [str(program(build, "step_toggle"))]
    done = subprocess.run([str(exe), *args, *elf], capture_output=True, text=True, timeout=10)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("simboard: error: ") and done.stderr.count("\n") == 1
    assert named in done.stderr


def test_a_file_that_is_not_an_avr_elf_is_refused_in_one_line(exe, tmp_path):
    text = tmp_path / "notes.elf"
    text.write_text("not a program\n")
    for path in (text, Path("/bin/sh"), tmp_path / "missing.elf"):
        done = subprocess.run([str(exe), str(path)], capture_output=True, text=True, timeout=10)
        assert done.returncode == 2 and done.stdout == ""
        assert done.stderr.startswith("simboard: error: ") and done.stderr.count("\n") == 1


def test_damaged_avr_elfs_are_refused_or_run_but_never_crash_the_board(exe, build, tmp_path):
    original = program(build, "step_toggle").read_bytes()
    damaged = [original[:20], original[:100], original[: len(original) // 2]]
    for seed in range(8):  # bytes overwritten after the ELF header (seed 1 reaches a crash in libsimavr's reader)
        rng = random.Random(seed)
        data = bytearray(original)
        for _ in range(200):
            data[rng.randrange(52, len(data))] = rng.randrange(256)
        damaged.append(bytes(data))
    for i, data in enumerate(damaged):
        elf = tmp_path / f"damaged{i}.elf"
        elf.write_bytes(data)
        argv = [str(exe), "--speed", "0", "--no-pty", "--duration", "0.01", str(elf)]
        with subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as p:
            out, err = p.communicate(timeout=10)  # stdin closed: a running board ends at once
        assert p.returncode in (0, 2), (i, p.returncode)
        if p.returncode == 2:
            assert out == b"" and err.startswith(b"simboard: error: ") and err.count(b"\n") == 1


def test_link_is_a_symlink_to_the_pty_removed_on_exit_and_never_replaces_a_file(exe, build, tmp_path):
    elf = program(build, "step_toggle")
    link = tmp_path / "wheel"
    with SimBoard(exe, elf, "--link", str(link), speed=0) as board:
        assert os.readlink(link) == board.path
    assert not link.exists() and not link.is_symlink()
    link.write_text("precious")
    done = subprocess.run([str(exe), "--link", str(link), str(elf)], capture_output=True, text=True, timeout=10)
    assert done.returncode == 2 and "--link" in done.stderr and link.read_text() == "precious"


def test_link_replaces_only_a_dead_boards_link(exe, build, tmp_path):
    """A user's symlink, or a link to a pseudo-terminal that is in use, stays; a link to a
    pseudo-terminal that is gone (a board killed before it could remove it) is replaced."""
    elf = program(build, "step_toggle")
    (tmp_path / "precious.txt").write_text("mine")
    mine = tmp_path / "mine"
    mine.symlink_to(tmp_path / "precious.txt")
    live = tmp_path / "live"
    master, slave = os.openpty()
    try:
        live.symlink_to(os.ttyname(slave))
        for link in (mine, live):
            target = os.readlink(link)
            argv = [str(exe), "--link", str(link), str(elf)]
            done = subprocess.run(argv, capture_output=True, text=True, timeout=10)
            assert done.returncode == 2 and "not replacing it" in done.stderr and os.readlink(link) == target
    finally:
        os.close(master)
        os.close(slave)
    dead = tmp_path / "dead"
    dead.symlink_to("/dev/pts/999999")
    with SimBoard(exe, elf, "--link", str(dead), speed=0) as board:
        assert os.readlink(dead) == board.path


def test_malformed_commands_get_an_error_and_the_board_keeps_running(exe, build):
    with SimBoard(exe, program(build, "step_toggle"), speed=0, pty=False) as board:
        for line in ["", "  ", "warp 9", "peek 0x900 1", "peek 0x100 0", "peek 0x100 257", "peek 0x8ff 2",
                     "peek -1 1", "peek 010x 1", "corrupt xx 1", "corrupt tx -1", "silence maybe",
                     "stats now", "x" * 5000, "\x00\x01\x7f"]:  # fmt: skip
            if not line.strip():
                continue
            answer = board.command(line)
            assert set(answer) == {"error"} and len(answer["error"]) < 200, line
        assert board.peek(0x8FF, 1) and board.peek(256, 256)
        before = board.stats()["cycle"]
        time.sleep(0.05)
        assert board.stats()["cycle"] > before
    assert board.final is not None and board.final["event"] == "final"
