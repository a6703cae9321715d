"""The wheel-controller firmware on its simulated ATmega328P: the numbers of docs/firmware.md.

Needs the AVR toolchain, Debian's Arduino core and libsimavr-dev (``.ci/run`` installs them); the
firmware and the simulated board are built with ``make -C firmware`` into the tests' build folder.
Every time is in simulated cycles (16 per us), so the figures do not depend on this machine. The
references are the chip's budgets, stated by the firmware itself or the datasheet: 30720 B of
flash, 2048 B of RAM, the 10 ms control period, the top wheel speed's 2865 encoder pulses/s. For
each variant (stepper, DC):

* sizes: flash and static RAM (``avr-size``), and the deepest stack seen under the damaged-bus load;
* at the top speed (30 rad/s), commands for three wheels every 20 ms, over 1 s after 1 s of the
  same: control period and step duration (the probe pin), interrupt load per vector, step
  intervals, the speed held; then the same with one host byte in 50 damaged;
* a bus carrying SPEED_CMD frames back to back at the full line rate: frames parsed of 1000;
* the damaged bus again over 30 schedules whose commands go out at pseudo-random times of each
  20 ms period: the longest delay of a control step seen;
* bytes built to cost the parser the most (``costly_garbage``) between the commands: the longest
  control period, and the commands parsed of those sent;
* the highest encoder rate counted without a miss, by bisection (3 % steps) on a shaft turning at
  a constant speed, with the chip only counting and with the host driving it at the top speed;
* the simulation's own speed: simulated seconds per wall second of a board running flat out.

    python3 benchmarks/bench_firmware.py
"""

from __future__ import annotations

import math
import random
import time
from pathlib import Path

from _common import save
from support.firmware_build import AVR_MISSING, NANO_FLASH, NANO_RAM, build_dir, firmware
from support.firmware_load import (
    CONTROL_PERIOD,
    F_CPU,
    PPR,
    STEPS_PER_RAD,
    TOP_SPEED,
    ChipLink,
    control_lateness,
    drive,
    drive_through_garbage,
    encoder_miscount,
    every_phase,
    flood,
)
from support.simboard import SIMAVR_MISSING, SimBoard, build_simboard

MOTORS = ("stepper", "dc")
TOP_PULSES = TOP_SPEED * PPR / (2 * math.pi)  # [pulses/s] at the top wheel speed
FLOOD_FRAMES = 1000
SCHEDULES = 30
"""Schedules of the damaged bus with the commands at scattered places of the control period."""
VECTORS = {1: "INT0 (encoder)", 11: "TIMER1_COMPA (steps)", 16: "TIMER0_OVF (millis)", 18: "USART_RX", 19: "USART_UDRE"}
"""ATmega328P interrupt vector numbers (datasheet table 12-6, reset = 0) of the firmware's handlers."""


def _under_load(exe: Path, motor: str, damaged: int) -> dict:
    """1 s at the top speed with a busy bus (one host byte in ``damaged`` flipped, 0: none),
    measured over the second second; then, on the same board, the full-rate flood."""
    fw = firmware(motor)
    with SimBoard(exe, fw.elf, "--motor", motor, lockstep=True) as board:
        link = ChipLink.open(board)
        board.corrupt("rx", damaged)
        drive(link, TOP_SPEED, 1.0)
        board.clear()
        drive(link, TOP_SPEED, 1.0, after_step=every_phase)
        stats = board.stats()
        board.corrupt("rx", 0)
        parsed = flood(link, fw, FLOOD_FRAMES)
    window = stats["window_cycles"]
    probe, steps = stats["probe"], stats["steps"]
    return {
        "stack_bytes": stats["stack_bytes"],
        "control_period_cycles": {k: probe[f"period_{k}"] for k in ("mean", "min", "max")},
        "control_step_cycles": {k: probe[f"high_{k}"] for k in ("mean", "max")},
        "control_step_late_max": control_lateness(probe) / CONTROL_PERIOD,
        "isr_load": stats["isr_cycles"] / window,
        "isr": {
            VECTORS.get(int(name), name): {
                "per_s": v["count"] * F_CPU / window,
                "cycles_each": v["cycles"] / v["count"] if v["count"] else 0.0,
                "load": v["cycles"] / window,
            }
            for name, v in stats["isr"].items()
        },
        "steps": {k: steps[k] for k in ("count", "interval_mean", "interval_min", "interval_max", "interval_std")}
        if motor == "stepper"
        else None,
        "speed_held": stats["omega"] if motor == "dc" else F_CPU / steps["interval_mean"] / STEPS_PER_RAD,
        "flood_parsed": parsed,
    }


def _damaged_bus_worst(exe: Path, motor: str, schedules: int) -> float:
    """The longest delay of a control step [fraction of a period] over ``schedules`` runs of the
    damaged bus (one byte in 50; 1 s, then 1 s measured), each period's commands sent a
    pseudo-random time (0 to 19 ms, seeds 0, 1, ...) after its start: how late a step can be when a
    damaged header's rejection falls due with it, which one schedule alone may not show."""
    fw = firmware(motor)
    worst = 0.0
    for seed in range(schedules):
        rng = random.Random(seed)
        with SimBoard(exe, fw.elf, "--motor", motor, lockstep=True) as board:
            link = ChipLink.open(board)
            board.corrupt("rx", 50)
            for second in range(2):
                if second:
                    board.clear()
                for _ in range(50):
                    offset = round(rng.random() * 0.019, 5)
                    if offset > 0:
                        link.run(offset)
                    link.send(link.speed(0, TOP_SPEED), link.speed(1, -TOP_SPEED), link.speed(2, TOP_SPEED))
                    link.run(0.02 - offset)
            worst = max(worst, control_lateness(board.stats()["probe"]) / CONTROL_PERIOD)
    return worst


def _through_garbage(exe: Path, motor: str) -> dict:
    stats, sent, parsed = drive_through_garbage(exe, firmware(motor), motor, 1.0)
    return {"control_step_late_max": control_lateness(stats["probe"]) / CONTROL_PERIOD, "sent": sent, "parsed": parsed}


def _highest_encoder_rate(exe: Path, motor: str, bus: bool) -> float:
    """The highest pulse rate counted without a miss (bisection in 3 % steps) [pulses/s]."""
    fw = firmware(motor)
    lo, hi = TOP_PULSES, 200_000.0
    if abs(encoder_miscount(exe, fw, lo, 0.3, bus)) > 1:
        return 0.0
    while hi / lo > 1.03:
        mid = math.sqrt(lo * hi)
        if abs(encoder_miscount(exe, fw, mid, 0.3, bus)) <= 1:
            lo = mid
        else:
            hi = mid
    return lo


def _simulation_speed(exe: Path) -> float:
    """Simulated seconds per wall second of a stepper board running flat out with no host."""
    fw = firmware("stepper")
    t0 = time.perf_counter()
    with SimBoard(exe, fw.elf, "--duration", "2", speed=0.0, pty=False) as board:
        final = board.wait_final(120)
    return final["time_s"] / (time.perf_counter() - t0)


def _pacing(exe: Path) -> dict:
    """How closely a paced board (``--speed``) keeps to the wall clock: the wall time of 1 s of
    simulated time against the time the speed asks for (1.0: on time), and the most it fell behind."""
    fw = firmware("stepper")
    paced = {}
    for speed in (1.0, 2.0):
        with SimBoard(exe, fw.elf, "--duration", "1", speed=speed, pty=False) as board:
            final = board.wait_final(120)
        paced[f"speed_{speed:g}"] = {
            "wall_vs_asked": final["wall_s"] / (final["time_s"] / speed),
            "behind_s": final["behind_s"],
        }
    return paced


def main() -> dict:
    missing = AVR_MISSING or SIMAVR_MISSING
    if missing:
        raise SystemExit(f"bench_firmware: {missing}")
    exe = build_simboard(build_dir())
    results: dict = {
        "references": {
            "flash": NANO_FLASH,
            "ram": NANO_RAM,
            "control_period_cycles": CONTROL_PERIOD,
            "top_speed_pulses_per_s": TOP_PULSES,
        }
    }
    for motor in MOTORS:
        fw = firmware(motor)
        clean = _under_load(exe, motor, 0)
        damaged = _under_load(exe, motor, 50)
        garbage = _through_garbage(exe, motor)
        scattered = _damaged_bus_worst(exe, motor, SCHEDULES)
        idle = _highest_encoder_rate(exe, motor, bus=False)
        busy = _highest_encoder_rate(exe, motor, bus=True)
        used = fw.static_ram + damaged["stack_bytes"]
        results[motor] = {
            "flash": fw.flash,
            "static_ram": fw.static_ram,
            "ram_used": used,
            "ram_free": 1 - used / NANO_RAM,
            "clean_bus": clean,
            "damaged_bus": damaged,
            "damaged_bus_scattered_worst": scattered,
            "costly_garbage": garbage,
            "encoder_max_pulses_per_s": {"idle": idle, "busy": busy, "busy_vs_top_speed": busy / TOP_PULSES},
        }
        r = results[motor]
        print(
            f"{motor}: flash {fw.flash} B ({fw.flash / NANO_FLASH:.1%}), RAM {fw.static_ram} + {damaged['stack_bytes']}"
            f" = {used} B ({r['ram_free']:.0%} free); interrupt load {clean['isr_load']:.1%}"
            f" ({damaged['isr_load']:.1%} damaged bus); control period"
            f" {clean['control_period_cycles']['mean'] / F_CPU * 1e3:.3f} ms mean,"
            f" late by at most {clean['control_step_late_max']:.1%} ({damaged['control_step_late_max']:.1%}"
            f" damaged, {scattered:.1%} damaged over {SCHEDULES} scattered schedules,"
            f" {garbage['control_step_late_max']:.1%} costly garbage, {garbage['parsed']}/{garbage['sent']}"
            f" commands parsed); flood {clean['flood_parsed']}/{FLOOD_FRAMES};"
            f" encoder up to {idle:.0f} / {busy:.0f} pulses/s idle / busy ({busy / TOP_PULSES:.1f}x top speed)"
        )
        for name, v in clean["isr"].items():
            print(f"  {name}: {v['per_s']:.0f}/s x {v['cycles_each']:.1f} cycles = {v['load']:.2%}")
        if clean["steps"]:
            s = clean["steps"]
            spread = f"{s['interval_min']} - {s['interval_max']}"
            print(f"  steps: interval {s['interval_mean']:.3f} cycles ({spread}), std {s['interval_std']:.1f}")
    results["simulated_s_per_wall_s"] = _simulation_speed(exe)
    print(f"simulation: {results['simulated_s_per_wall_s']:.1f} simulated s per wall s")
    results["pacing"] = _pacing(exe)
    for name, v in results["pacing"].items():
        print(
            f"pacing at {name}: wall time {v['wall_vs_asked']:.3f}x the asked, behind by at most {v['behind_s']:.3f} s"
        )
    return results


if __name__ == "__main__":
    print(f"-> {save('firmware', main())}")
