"""Run every benchmark and save the figures in benchmarks/results/*.json.

    python3 benchmarks/run_all.py

Benchmarks are not part of the test run; their figures go into docs/performance.md. Those that
need an extra or system packages are skipped, with the reason, where these are missing.
"""

import importlib

import bench_accuracy
import bench_batch
import bench_runtime
import bench_sensors
import bench_simulation
import bench_streaming
import bench_umbmark
from _common import machine, save

OPTIONAL = {
    "control": "pip install -e '.[test]' (toppra and Clarabel, the reference solvers; OSQP, extra control)",
    "physics": "pip install -e '.[physics]' (MuJoCo)",
    "tracking": "pip install -e '.[physics,control]' (MuJoCo, OSQP)",
    "sweep": "pip install -e '.[sweep]' (Dask)",
    "viewer": "pip install -e '.[viewer]' and Debian's chromium",
    "firmware": "pip install -e '.[serial]' and the AVR packages of .ci/run",
}
"""Benchmarks that need more than the core, and what they need."""


def _firmware_missing() -> str | None:
    from support.firmware_build import AVR_MISSING
    from support.simboard import SIMAVR_MISSING

    return AVR_MISSING or SIMAVR_MISSING


if __name__ == "__main__":
    print("machine:", machine())
    modules = [
        bench_streaming,
        bench_batch,
        bench_accuracy,
        bench_simulation,
        bench_umbmark,
        bench_runtime,
        bench_sensors,
    ]
    for name, needs in OPTIONAL.items():
        try:
            module = importlib.import_module(f"bench_{name}")
            missing = _firmware_missing() if name == "firmware" else None
        except ImportError as e:
            missing = f"{e} ({needs})"
        if missing:
            print(f"{name} skipped: {missing}")
        else:
            modules.append(module)
    for module in modules:
        name = module.__name__.replace("bench_", "")
        path = save(name, module.main())
        print(f"-> {path}\n")
