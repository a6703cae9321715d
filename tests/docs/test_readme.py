"""Every command in the README runs as written (in a fresh folder, with the repository's examples).

The README's bash blocks are run line by line, in order, in one temporary folder that has
``examples/`` beside it as in the repository, and a copy of ``firmware/`` without its build
folder (``make -C firmware`` builds from scratch there); the two set-up commands (``pip install
...``) are what CI itself runs and are not repeated. ``omnikin ros`` runs until stopped: it must come
up and stop cleanly on SIGINT. The Python block runs as a script; the robot-file block loads.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import pytest

from conftest import ROOT, omnikin_env
from firmware_build import AVR_MISSING
from simboard import SIMAVR_MISSING

README = (ROOT / "README.md").read_text(encoding="utf-8")


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, flags=re.S)


def _commands() -> list[str]:
    out = []
    for block in _blocks("bash"):
        for line in block.splitlines():
            cmd = line.split(" #")[0].strip()
            if cmd and "pip install" not in cmd:
                out.append(cmd)
    return out


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    work = tmp_path_factory.mktemp("readme")
    (work / "examples").symlink_to(ROOT / "examples")
    shutil.copytree(ROOT / "firmware", work / "firmware", ignore=shutil.ignore_patterns("build"))
    return work


def _env():
    return omnikin_env(ROS_DOMAIN_ID=str(100 + os.getpid() % 100), ROS_LOG_DIR=tempfile.mkdtemp())


def _argv(cmd: str) -> list[str]:
    argv = shlex.split(cmd)
    if argv[0] == "make" or argv[0].startswith("firmware/build/"):  # the firmware and its simulated board
        missing = AVR_MISSING or SIMAVR_MISSING
        if missing:
            pytest.skip(f"{cmd}: {missing}")
        return argv
    assert argv[0] == "omnikin", f"README command does not start with omnikin, make or firmware/build/: {cmd}"
    return [sys.executable, "-m", "omnikin.cli.main", *argv[1:]]


def test_readme_has_exactly_two_setup_commands():
    setup = [c for b in _blocks("bash") for c in b.splitlines() if "pip install" in c]
    assert setup == [
        'python3 -m pip install -e ".[viz]" && omnikin umbmark',
        'python3 -m pip install -e ".[test]" && python3 -m pytest',
    ]


@pytest.mark.slow
def test_every_readme_command_runs_as_written(workdir):
    env = _env()
    for cmd in _commands():
        if cmd.startswith("omnikin ros"):
            pytest.importorskip("rclpy", reason="the ROS 2 wheels (extra ros) are not installed")
            proc = subprocess.Popen(
                _argv(cmd), cwd=workdir, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
            )
            time.sleep(8.0)
            assert proc.poll() is None, f"{cmd}: exited early: {proc.communicate()[1][-500:]}"
            proc.send_signal(signal.SIGINT)
            _, err = proc.communicate(timeout=30)
            assert proc.returncode == 0, f"{cmd}: exit {proc.returncode}: {err[-500:]}"
            continue
        argv = _argv(cmd)
        if cmd.startswith("omnikin sim"):  # a window: on a virtual screen of its own
            if shutil.which("xvfb-run") is None:
                pytest.skip("xvfb-run (Debian package xvfb) is not installed; .ci/run installs it")
            argv = ["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", *argv]
        res = subprocess.run(argv, cwd=workdir, env=env, capture_output=True, text=True, timeout=300)
        assert res.returncode == 0, f"{cmd}: exit {res.returncode}: {res.stderr[-800:]}"
        assert "Traceback" not in res.stderr


def test_readme_python_block_runs(workdir):
    (code,) = _blocks("python")
    res = subprocess.run(
        [sys.executable, "-c", code], cwd=workdir, env=_env(), capture_output=True, text=True, timeout=120
    )
    assert res.returncode == 0, res.stderr[-800:]


def test_readme_robot_file_loads(workdir):
    from omnikin import load_robot

    (text,) = _blocks("yaml")
    path = workdir / "my-omni3.yaml"
    path.write_text(text, encoding="utf-8")
    robot = load_robot(str(path))
    assert len(robot.wheels) == 3 and robot.mobility.campion_type == (3, 0)
