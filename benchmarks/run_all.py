"""Run every benchmark and save the figures in benchmarks/results/*.json.

    python3 benchmarks/run_all.py

Benchmarks are not part of the test run; their figures go into docs/performance.md.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_accuracy  # noqa: E402
import bench_batch  # noqa: E402
import bench_runtime  # noqa: E402
import bench_simulation  # noqa: E402
import bench_streaming  # noqa: E402
import bench_umbmark  # noqa: E402
from _common import machine, save  # noqa: E402

if __name__ == "__main__":
    print("machine:", machine())
    modules = [bench_streaming, bench_batch, bench_accuracy, bench_simulation, bench_umbmark, bench_runtime]
    try:
        import bench_physics  # needs the extra 'physics' (MuJoCo)

        modules.append(bench_physics)
    except ImportError as e:
        print(f"physics skipped: {e} (pip install -e '.[physics]')")
    try:
        import bench_sweep  # needs the extra 'sweep'

        modules.append(bench_sweep)
    except ImportError as e:
        print(f"sweep skipped: {e} (pip install -e '.[sweep]')")
    try:
        import bench_viewer  # needs the extra 'viewer' and Debian's Chromium

        modules.append(bench_viewer)
    except ImportError as e:
        print(f"viewer skipped: {e} (pip install -e '.[viewer]')")
    for module in modules:
        name = module.__name__.replace("bench_", "")
        path = save(name, module.main())
        print(f"-> {path}\n")
