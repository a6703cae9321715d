"""Standard output and error as the caller gives them: closed (``>&-``), or in an encoding without
the characters to print (``PYTHONIOENCODING=ascii``, a C locale). One line and a status, never an
internal error. Real subprocesses, real file descriptors."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from support.paths import ROOT, omnikin_env

ROBOT = (
    "omnikin: 1\nname: café\ndescription: un robot à trois roues — ça roule\nwheels:\n"
    "  - {name: a, type: omni, distance: 0.2, angle_deg: 90, radius: 0.05, encoder: {ticks_per_rev: 1000}}\n"
    "  - {name: b, type: omni, distance: 0.2, angle_deg: 210, radius: 0.05, encoder: {ticks_per_rev: 1000}}\n"
    "  - {name: c, type: omni, distance: 0.2, angle_deg: 330, radius: 0.05, encoder: {ticks_per_rev: 1000}}\n"
)
"""Robot names and descriptions may hold any printable character (the robot-file rules)."""


def shell(command: str, tmp_path, **env: str) -> subprocess.CompletedProcess:
    """``command`` in sh, with ``omnikin`` the entry point of this checkout (redirections like ``>&-`` work)."""
    program = f"'{sys.executable}' -m omnikin.cli.main"
    return subprocess.run(
        ["sh", "-c", command.replace("omnikin", program, 1)],
        cwd=tmp_path,
        env=omnikin_env(**env),
        capture_output=True,
        timeout=300,
    )


@pytest.fixture
def uni(tmp_path):
    path = tmp_path / "uni.yaml"
    path.write_text(ROBOT, encoding="utf-8")
    return path


def test_closed_standard_output_is_one_line_and_status_1(tmp_path):
    """'show --json >&-' was 'internal error: AttributeError: NoneType has no attribute flush'."""
    proc = shell("omnikin show tomasi-omni3 --json >&-", tmp_path)
    assert proc.returncode == 1
    assert proc.stderr.decode() == "omnikin: error: standard output: cannot write: it is closed\n"


def test_closed_standard_output_still_writes_the_file_asked_for(tmp_path):
    log = ROOT / "examples" / "tick_log.csv"
    proc = shell(f"omnikin odometry tomasi-omni3 '{log}' -o out.csv >&-", tmp_path)
    assert proc.returncode == 1 and b"standard output: cannot write" in proc.stderr
    assert (tmp_path / "out.csv").read_text().startswith("t,x,y,theta\n")


def test_closed_standard_error_keeps_the_status(tmp_path):
    proc = shell("omnikin ik tomasi-omni3 1 2 >/dev/null 2>&-", tmp_path)
    assert proc.returncode == 2
    proc = shell("omnikin show tomasi-omni3 --json 2>&-", tmp_path)
    assert proc.returncode == 0 and json.loads(proc.stdout)["name"] == "tomasi-omni3"


def test_an_ascii_terminal_gets_escapes_not_an_internal_error(tmp_path, uni):
    """PYTHONIOENCODING=ascii omnikin show uni.yaml was 'internal error: UnicodeEncodeError'."""
    proc = shell("omnikin show uni.yaml", tmp_path, PYTHONIOENCODING="ascii")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.decode("ascii").startswith("caf\\xe9: un robot \\xe0 trois roues \\u2014 \\xe7a roule\n")
    proc = shell("omnikin ik uni.yaml 1 2 3 --steer-hint-deg 5", tmp_path, PYTHONIOENCODING="ascii")
    assert proc.returncode == 2 and proc.stderr.decode("ascii").count("\n") == 1
    assert "'caf\\xe9'" in proc.stderr.decode("ascii")


def test_json_and_data_are_exact_whatever_the_encoding(tmp_path, uni):
    proc = shell("omnikin show uni.yaml --json", tmp_path, PYTHONIOENCODING="ascii")
    assert proc.returncode == 0 and json.loads(proc.stdout)["name"] == "café"
    runs = ROOT / "examples" / "calibration_runs.csv"
    proc = shell(f"omnikin calibrate tomasi-omni3 '{runs}' -o -", tmp_path, PYTHONIOENCODING="ascii")
    assert proc.returncode == 0, proc.stderr
    assert b"name: tomasi-omni3" in proc.stdout
    proc = shell("omnikin simulate uni.yaml --path 'spin 10' --log -", tmp_path, PYTHONIOENCODING="ascii")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.decode("utf-8").startswith("# encoder tick log of café written by: omnikin simulate uni.yaml")
