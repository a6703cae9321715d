"""Shared helpers of the benchmarks: best-of-k timing, machine description, reports."""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def best_time(fn, repeat: int = 5, number: int = 1) -> float:
    """Best wall time [s] of ``number`` calls of ``fn`` over ``repeat`` rounds, per call."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def machine() -> dict:
    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "platform": platform.platform(),
    }


def save(name: str, data: dict) -> Path:
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"machine": machine(), **data}, indent=2) + "\n")
    return path


def tomasi_log(n: int, rate: float = 100.0, seed: int = 0):
    """A tick log of tomasi-omni3 driving a slowly varying twist: ``(t, ticks)``."""
    from omnikin import load_robot

    robot = load_robot("tomasi-omni3")
    t = np.arange(n) / rate
    twist = np.column_stack([0.3 * np.sin(0.1 * t), 0.2 * np.cos(0.07 * t), 0.5 * np.sin(0.05 * t)])
    speeds = twist @ robot.ik_matrix.T
    angles = np.cumsum(speeds, axis=0) / rate
    ticks = np.round(angles / (2 * np.pi / 600)).astype(np.int64)
    return robot, t, ticks
