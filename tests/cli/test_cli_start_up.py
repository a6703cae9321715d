"""Starting ``omnikin``: the entry point imports little, and a user who stops omnikin while it
loads its commands gets the one line of any stopped command, never a traceback.

The command modules (and the Python API behind them: SciPy, the physics description, the
studies) are imported while the command line handles Ctrl-C and SIGTERM; what the entry point
imports before that is the window in which a stop could only end Python with a traceback, so it
is kept to ``import omnikin``.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from support.paths import omnikin_env

HEAVY = ("scipy", "matplotlib", "mujoco", "rosbags", "dask", "viser", "rclpy", "omnikin.api", "omnikin.evaluation")


def python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=omnikin_env())


def test_entry_point_imports_neither_the_api_nor_heavy_libraries():
    proc = python(
        "import sys, omnikin.cli.main\n"
        f"print(sorted(h for h in {HEAVY!r} if any(m == h or m.startswith(h + '.') for m in sys.modules)))"
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


def test_every_command_is_still_listed_by_help():
    proc = subprocess.run(
        [sys.executable, "-m", "omnikin.cli.main", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        env=omnikin_env(),
    )
    assert proc.returncode == 0, proc.stderr
    listed = proc.stdout.split("positional arguments:")[1].split("options:")[0]
    for command in ("presets", "show", "ik", "fk", "odometry", "umbmark", "calibrate", "bag", "simulate", "metrics"):
        assert f"\n    {command}" in listed, command
    for command in ("ros", "sim", "view", "sweep", "mjcf", "urdf"):
        assert f"\n    {command}" in listed, command


# A finder that sends the signal to its own process the moment a command module starts to be
# imported: the stop arrives while omnikin loads its commands, at a known place.
STOP_WHILE_LOADING = """
import os, signal, sys

class Stop:
    def find_spec(self, name, path=None, target=None):
        if name == "omnikin.cli.umbmark":
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.{sig})
        return None

from omnikin.cli.main import main
sys.meta_path.insert(0, Stop())
sys.exit(main(["presets"]))
"""


@pytest.mark.parametrize(
    ("sig", "status", "line"),
    [("SIGINT", 130, "omnikin: interrupted"), ("SIGTERM", 143, "omnikin: terminated (SIGTERM)")],
)
def test_stopped_while_loading_its_commands_omnikin_says_so_in_one_line(sig, status, line):
    proc = python(STOP_WHILE_LOADING.format(sig=sig))
    assert proc.returncode == status, proc.stderr
    assert proc.stderr.strip() == line
    assert proc.stdout == ""
