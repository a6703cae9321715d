"""Every command in the README runs as written (in a fresh folder, with the repository's examples).

The README's bash blocks are run line by line, in order, in one temporary folder that has
``examples/`` beside it as in the repository, and a copy of ``firmware/`` without its build
folder (``make -C firmware`` builds from scratch there); the two set-up commands (``pip install
...``) are what CI itself runs and are not repeated. The servers run until stopped, as a user runs
them: each must come up and serve (``omnikin view``: its page answers on the address it printed, on
a free port instead of the default 8080, so that no test depends on a fixed port; ``omnikin sim``:
its window is up on a virtual display of its own; ``omnikin ros``: its node runs), then stop
normally on Ctrl-C (SIGINT: status 0, no error). The Python block runs as a script; the
robot-file block loads.
"""

from __future__ import annotations

import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile

import pytest

from support import servers
from support.firmware_build import AVR_MISSING
from support.paths import ROOT, omnikin_env
from support.ros_domain import fresh_domain
from support.simboard import SIMAVR_MISSING

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
    return omnikin_env(ROS_DOMAIN_ID=str(fresh_domain()), ROS_LOG_DIR=tempfile.mkdtemp())


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


SERVERS = ("ros", "view", "sim")
"""omnikin commands that serve until the user stops them."""


@pytest.mark.slow
def test_every_readme_command_runs_as_written(workdir):
    env = _env()
    for cmd in _commands():
        if cmd.split()[:1] == ["omnikin"] and cmd.split()[1] in SERVERS:
            _serve_and_stop(cmd, workdir, env)
            continue
        # the timeout only guards against a hang: a busy machine may take minutes for the example sweep
        res = subprocess.run(_argv(cmd), cwd=workdir, env=env, capture_output=True, text=True, timeout=900)
        assert res.returncode == 0, f"{cmd}: exit {res.returncode}: {res.stderr[-800:]}"
        assert "Traceback" not in res.stderr


def _serve_and_stop(cmd: str, workdir, env) -> None:
    """Start the server ``cmd``, check it is up and serving, stop it with Ctrl-C (SIGINT) and
    check that this is its normal end."""
    command = cmd.split()[1]
    argv = _argv(cmd)
    if command == "ros":
        pytest.importorskip("rclpy", reason="the ROS 2 wheels (extra ros) are not installed")
    if command == "view" and "--port" not in argv:
        argv += ["--port", "0"]
    if command == "sim":
        if servers.DISPLAY_MISSING:
            pytest.skip(f"{cmd}: {servers.DISPLAY_MISSING}; .ci/run installs it")
        with servers.virtual_display() as display:
            proc = servers.start(argv, workdir, dict(env, DISPLAY=display))
            try:
                servers.wait_window(display, proc)
            finally:
                status, _, err = servers.stop(proc, signal.SIGINT)
    else:
        proc = servers.start(argv, workdir, env)
        try:
            if command == "view":
                servers.page_address(proc)
            else:  # its node on the graph
                servers.wait_node(proc, int(env["ROS_DOMAIN_ID"]))
        finally:
            status, _, err = servers.stop(proc, signal.SIGINT)
    servers.stopped_normally(command, status, err, signal.SIGINT)


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
