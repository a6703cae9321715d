"""A termination signal (``timeout``, ``kill``, systemd: SIGTERM) ends a command the way Ctrl-C
does: every cleanup runs, nothing half written is left, exit status 143 and one line that is not
an error. A server (view, sim, ros) the user stops ends normally: status 0.

``timeout 2.6 omnikin umbmark -o k`` once left ``.k.xxxx.tmp/`` with a 0-byte PNG and
``timeout 3 omnikin simulate --rate 2000 --bag big.bag`` 137 MB in ``.big.bag.xxxx.tmp/``.
Each test runs the real entry point in a subprocess, waits until the output is being written
(its temporary file or staging folder exists), sends a real SIGTERM and checks the folder.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import pytest

from support import servers
from support.paths import omnikin_env
from support.ros_domain import fresh_domain


def start(tmp_path, *argv):
    return subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", *[str(a) for a in argv]],
        cwd=tmp_path,
        env=omnikin_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def run_module(folder, name: str, source: str) -> subprocess.CompletedProcess:
    """``source`` written to ``folder/name.py`` and run as ``python -m name`` there (the way
    CPython's unhandled-interrupt handling applies), its output captured."""
    (folder / f"{name}.py").write_text(source, encoding="utf-8")
    return subprocess.run(
        [sys.executable, "-m", name], cwd=folder, env=omnikin_env(), capture_output=True, text=True, timeout=300
    )


def terminate_while_writing(proc, folder, prefix: str, timeout: float = 300.0) -> None:
    """Send SIGTERM as soon as an entry of ``folder`` starting with ``prefix`` (a temporary file
    or a staging folder) appears; fail if the command ends first."""
    deadline = time.monotonic() + timeout
    while not any(p.name.startswith(prefix) for p in folder.iterdir()):
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the command ended before writing: {proc.returncode} {err}")
        assert time.monotonic() < deadline, "no temporary output appeared"
        time.sleep(0.002)
    proc.send_signal(signal.SIGTERM)


def ended_by_sigterm(proc) -> None:
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 128 + signal.SIGTERM == 143, err
    assert err.splitlines()[-1] == "omnikin: terminated (SIGTERM)", err
    assert "Traceback" not in err


def test_sigterm_while_writing_a_report_folder_leaves_nothing(tmp_path):
    proc = start(tmp_path, "umbmark", "diff-drive", "--runs", "1", "-o", "k")
    terminate_while_writing(proc, tmp_path, ".k.")
    ended_by_sigterm(proc)
    assert list(tmp_path.iterdir()) == []


def test_sigterm_keeps_the_previous_report_as_it_was(tmp_path):
    """A report omnikin wrote before stays whole: the new one was still being staged."""
    first = start(tmp_path, "umbmark", "diff-drive", "--runs", "1", "--no-calibrate", "-o", "k")
    assert first.wait(timeout=300) == 0, first.communicate()
    before = {p.name: p.read_bytes() for p in (tmp_path / "k").iterdir()}
    proc = start(tmp_path, "umbmark", "diff-drive", "--runs", "1", "-o", "k")
    terminate_while_writing(proc, tmp_path, ".k.")
    ended_by_sigterm(proc)
    assert [p.name for p in tmp_path.iterdir()] == ["k"]
    assert {p.name: p.read_bytes() for p in (tmp_path / "k").iterdir()} == before


def test_sigterm_while_writing_a_bag_leaves_nothing(tmp_path):
    pytest.importorskip("rosbags")
    proc = start(tmp_path, "simulate", "tomasi-omni3", "--rate", "2000", "--bag", "big.bag")
    terminate_while_writing(proc, tmp_path, ".big.bag.")
    time.sleep(0.3)  # well into the writing
    ended_by_sigterm(proc)
    assert list(tmp_path.iterdir()) == []


def test_sigterm_while_writing_a_file_leaves_nothing(tmp_path):
    """The drawing is rendered into its temporary file (the 0-byte PNG of the report); 120
    wheels make the rendering last long enough to be caught in the middle."""
    pytest.importorskip("matplotlib")
    wheels = "".join(
        f"  - {{name: w{i}, type: omni, distance: 0.3, angle_deg: {3 * i}, radius: 0.05}}\n" for i in range(120)
    )
    robot = tmp_path / "many.yaml"
    robot.write_text(f"omnikin: 1\nname: many\nwheels:\n{wheels}")
    proc = start(tmp_path, "show", robot, "--plot", "layout.png")
    terminate_while_writing(proc, tmp_path, ".layout.png.")
    ended_by_sigterm(proc)
    assert list(tmp_path.iterdir()) == [robot]


def test_a_second_sigterm_does_not_cut_the_cleanup(tmp_path):
    """systemd and impatient users send SIGTERM twice: the cleanup the first one started finishes."""
    pytest.importorskip("rosbags")
    proc = start(tmp_path, "simulate", "tomasi-omni3", "--rate", "2000", "--bag", "big.bag")
    terminate_while_writing(proc, tmp_path, ".big.bag.")
    for _ in range(20):
        if proc.poll() is not None:
            break
        proc.send_signal(signal.SIGTERM)
        time.sleep(0.005)
    ended_by_sigterm(proc)
    assert list(tmp_path.iterdir()) == []


def test_a_termination_a_library_turns_into_its_own_error_is_still_a_termination(monkeypatch, capsys):
    """SIGTERM arriving inside a library's C code may come back as that library's own error
    (matplotlib: 'initialization failed'): the command still ends as terminated (143), not
    with the library's message."""
    import omnikin.cli.main as cli
    import omnikin.cli.presets as presets

    def library_call(args):
        try:
            signal.raise_signal(signal.SIGTERM)  # the handler raises Terminated here ...
        except BaseException:
            raise RuntimeError("initialization failed") from None  # ... which the library rewraps
        return 0

    monkeypatch.setattr(presets, "run", library_call)
    assert cli.main(["presets"]) == 143
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["omnikin: terminated (SIGTERM)"]
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN  # later ones ignored to the end
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


RUNNER = """
import sys

import omnikin.cli.main as cli
import omnikin.cli.presets as presets


def interrupted_in_source_text(args):
    # Ctrl-C inside code compiled from a string, as rosbags' serializers are on a bag's first messages
    exec("import signal\\nsignal.raise_signal(signal.SIGINT)", {})
    return 0


presets.run = interrupted_in_source_text
sys.exit(cli.main(["presets"]))
"""


def test_ctrl_c_inside_code_run_from_a_string_still_exits_130(tmp_path):
    """CPython notes a KeyboardInterrupt that leaves ``exec`` of a string as unhandled even when
    omnikin handles it, and under ``python -m`` then killed the process by SIGINT after it had
    printed 'omnikin: interrupted' (``simulate --bag`` interrupted while rosbags compiled its
    serializers: status -2 about once in six runs on a busy machine). The run here is the real
    ``main`` under ``python -m`` with a real SIGINT raised inside such code."""
    proc = run_module(tmp_path, "interrupted_runner", RUNNER)
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr == "omnikin: interrupted\n"


# --- servers: stopping them is their normal end ---------------------------------------------------------
STOPS = [signal.SIGINT, signal.SIGTERM]


@pytest.mark.parametrize("sig", STOPS, ids=lambda s: signal.Signals(s).name)
def test_stopping_the_viewer_is_a_normal_end(tmp_path, sig):
    pytest.importorskip("viser", reason="omnikin view needs the extra 'viewer'")
    proc = servers.start(servers.omnikin("view", "tomasi-omni3", "--port", "0"), tmp_path)
    try:
        servers.page_address(proc)
    finally:
        status, _, err = servers.stop(proc, sig)
    servers.stopped_normally("view", status, err, sig)


@pytest.mark.parametrize("sig", STOPS, ids=lambda s: signal.Signals(s).name)
def test_stopping_the_ros_node_is_a_normal_end(tmp_path, sig):
    pytest.importorskip("rclpy", reason="omnikin ros needs the extra 'ros'")
    domain = fresh_domain()
    env = omnikin_env(ROS_DOMAIN_ID=str(domain), ROS_LOG_DIR=str(tmp_path / "ros_log"))
    proc = servers.start(servers.omnikin("ros", "tomasi-omni3"), tmp_path, env)
    try:
        servers.wait_node(proc, domain)
    finally:
        status, _, err = servers.stop(proc, sig)
    servers.stopped_normally("ros", status, err, sig)


def test_stopping_the_window_writes_its_report_and_is_a_normal_end(tmp_path):
    pytest.importorskip("mujoco", reason="omnikin sim needs the extra 'physics'")
    if servers.DISPLAY_MISSING:
        pytest.skip(servers.DISPLAY_MISSING)
    with servers.virtual_display() as display:
        proc = servers.start(
            servers.omnikin("sim", "tomasi-omni3", "--report", "run.json"), tmp_path, omnikin_env(DISPLAY=display)
        )
        try:
            servers.wait_window(display, proc)
        finally:
            status, _, err = servers.stop(proc, signal.SIGINT)
    servers.stopped_normally("sim", status, err, signal.SIGINT)
    assert json.loads((tmp_path / "run.json").read_text())["end"] == "stopped"


# --- a stop that something swallows ----------------------------------------------------------------------
# Python runs a signal's handler wherever the main thread is, a finaliser (__del__, a weakref
# callback, a generator the garbage collector closes) included, and the exception it raises
# cannot leave a finaliser; a library may also swallow every exception. The command must still
# stop: with the stop it lost sent again, or at the latest with the next one.
SWALLOWED = """
import os, signal, sys, time

import omnikin.cli.main as cli
import omnikin.cli.presets as presets


class Finaliser:
    def __del__(self):
        os.kill(os.getpid(), signal.{sig})  # the stop lands while a finaliser runs


def swallowing_library():
    try:
        os.kill(os.getpid(), signal.{sig})
    except BaseException:
        pass


def work(args):
    {where}
    {again}
    for _ in range(400):  # 20 s of work, far longer than a stop takes to act
        time.sleep(0.05)
    print("finished", file=sys.stderr)
    return 0


presets.run = work
sys.exit(cli.main(["presets"]))
"""


def run_swallowed(tmp_path, sig: str, where: str, again: str = "") -> subprocess.CompletedProcess:
    return run_module(tmp_path, "swallowed_runner", SWALLOWED.format(sig=sig, where=where, again=again))


@pytest.mark.parametrize(
    ("sig", "status", "line"),
    [("SIGTERM", 143, "omnikin: terminated (SIGTERM)"), ("SIGINT", 130, "omnikin: interrupted")],
)
def test_a_stop_that_lands_in_a_finaliser_still_stops_the_command_quietly(tmp_path, sig, status, line):
    proc = run_swallowed(tmp_path, sig, "Finaliser()")
    assert proc.returncode == status, proc.stderr
    assert proc.stderr == line + "\n"  # no 'Exception ignored in ...' traceback, no 'finished'


def test_a_sigterm_after_one_a_library_swallowed_stops_the_command(tmp_path):
    """The first SIGTERM is lost inside a library; the one sent after it is not ignored."""
    proc = run_swallowed(tmp_path, "SIGTERM", "swallowing_library()", "os.kill(os.getpid(), signal.SIGTERM)")
    assert proc.returncode == 143, proc.stderr
    assert proc.stderr == "omnikin: terminated (SIGTERM)\n"


# --- stopped twice ------------------------------------------------------------------------------------
# The second Ctrl-C of an impatient user comes while the first one's command ends: while omnikin
# says so, or while Python exits (which takes a moment with NumPy and the API loaded). It must not
# turn 'omnikin: interrupted' (130) into a traceback or a death by SIGINT.
TWICE = """
import atexit, os, signal, sys

import omnikin.cli.main as cli
import omnikin.cli.presets as presets
from omnikin.cli import process


def stopped(args):
    os.kill(os.getpid(), signal.{sig})
    return 0


def again():
    os.kill(os.getpid(), signal.{again})


if "{when}" == "saying":
    said = process._ended

    def saying(message, status):
        again()
        return said(message, status)

    process._ended = saying
else:
    atexit.register(again)
presets.run = stopped
sys.argv = ["omnikin", "presets"]
sys.exit(cli.main())
"""


@pytest.mark.parametrize("when", ["saying", "exiting"])
@pytest.mark.parametrize(
    ("sig", "again", "status", "line"),
    [
        ("SIGINT", "SIGINT", 130, "omnikin: interrupted"),
        ("SIGTERM", "SIGINT", 143, "omnikin: terminated (SIGTERM)"),
        ("SIGINT", "SIGTERM", 130, "omnikin: interrupted"),
    ],
)
def test_a_second_stop_while_the_command_ends_changes_nothing(tmp_path, sig, again, status, line, when):
    proc = run_module(tmp_path, "twice_runner", TWICE.format(sig=sig, again=again, when=when))
    assert proc.returncode == status, proc.stderr
    assert proc.stderr == line + "\n"
