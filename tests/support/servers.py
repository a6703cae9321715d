"""omnikin's long-running commands (``view``, ``sim``, ``ros``) as a user runs them: started in a
process of their own, checked to be up and serving, then stopped with a real signal.

Every wait here is a safety timeout on something that must happen (a line, a page, a window), never
a pace: a busy machine only makes them take longer.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

from support.paths import omnikin_env

UP_TIMEOUT = 300.0
"""Safety timeout for a server to come up [s] (a model built, a page served, on a busy machine)."""

ADDRESS = re.compile(r"^omnikin view: .* at (http://\S+)\s")
"""The line ``omnikin view`` prints when its page is served (the address a user opens)."""


def start(argv: list[str], cwd: Path, env: dict | None = None) -> subprocess.Popen:
    """Run ``argv`` in ``cwd`` (text pipes; Ctrl-C delivered as in a terminal: SIGINT at its
    default even where the test process ignores it, as a shell's background job does)."""
    return subprocess.Popen(
        argv,
        cwd=cwd,
        env=env if env is not None else omnikin_env(),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def omnikin(*args: str) -> list[str]:
    """The command line of ``omnikin ARGS`` with this interpreter and this checkout."""
    return [sys.executable, "-m", "omnikin.cli.main", *args]


def page_address(proc: subprocess.Popen) -> str:
    """Wait for ``omnikin view``'s address line and check the page answers there; the address."""
    assert proc.stdout is not None
    line = proc.stdout.readline()  # blocks until the line or the end of the process
    match = ADDRESS.match(line)
    if match is None:
        proc.kill()
        out, err = proc.communicate(timeout=30)
        raise AssertionError(f"no address line from omnikin view: {line!r}{out!r}\n{err[-800:]}")
    url = match.group(1)
    with urllib.request.urlopen(url, timeout=UP_TIMEOUT) as page:
        assert page.status == 200, f"{url}: HTTP {page.status}"
        assert b"<html" in page.read().lower(), f"{url}: not a page"
    return url


@contextlib.contextmanager
def virtual_display() -> Iterator[str]:
    """A fresh Xvfb display on a free number (Xvfb picks it: -displayfd); its name (``:N``)."""
    read, write = os.pipe()
    xvfb = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    try:
        with os.fdopen(read) as f:
            number = f.readline().strip()
        assert number.isdigit(), "Xvfb did not report its display"
        name = f":{number}"
        _wait_for_connections(name, xvfb)
        yield name
    finally:
        xvfb.terminate()
        xvfb.wait(30)


def _wait_for_connections(display: str, xvfb: subprocess.Popen) -> None:
    """Wait until ``display`` takes a client (a screen grab over its socket): a loaded machine can
    leave a window's first connection refused between Xvfb naming its display and serving it."""
    from PIL import ImageGrab

    deadline = time.monotonic() + UP_TIMEOUT
    while True:
        try:
            ImageGrab.grab(xdisplay=display)
            return
        except OSError as error:
            if xvfb.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"Xvfb display {display} takes no client: {error}") from None
            time.sleep(0.1)


DISPLAY_MISSING = next(
    (
        f"{tool} is not installed (apt-get install xvfb xdotool)"
        for tool in ("Xvfb", "xdotool")
        if not shutil.which(tool)
    ),
    None,
)
"""Why a window cannot be tested here (one line), or None."""


def wait_window(display: str, proc: subprocess.Popen) -> None:
    """Wait until ``omnikin sim``'s MuJoCo window is mapped on ``display`` and shows the scene (the
    screen, black before, holds the many colours of a rendered frame: floor, sky, robot, text)."""
    from PIL import ImageGrab

    deadline = time.monotonic() + UP_TIMEOUT
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"omnikin sim ended before its window opened: {proc.communicate()[1][-800:]}")
        found = subprocess.run(
            ["xdotool", "search", "--onlyvisible", "--name", "MuJoCo"],
            env=dict(os.environ, DISPLAY=display),
            capture_output=True,
            text=True,
        ).stdout.split()
        if found and len(ImageGrab.grab(xdisplay=display).getcolors(maxcolors=1 << 20) or ()) > 100:
            return
        time.sleep(0.2)
    raise AssertionError(f"no MuJoCo window showing the scene on {display} within {UP_TIMEOUT:g} s")


def stop(proc: subprocess.Popen, sig: int = signal.SIGINT) -> tuple[int, str, str]:
    """Send ``sig`` (SIGINT: Ctrl-C); wait for the end; (exit status, stdout rest, stderr)."""
    proc.send_signal(sig)
    try:
        out, err = proc.communicate(timeout=UP_TIMEOUT)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        raise AssertionError(f"still running {UP_TIMEOUT:g} s after {signal.Signals(sig).name}: {err[-800:]}") from None
    return proc.returncode, out, err


def stopped_normally(command: str, status: int, err: str, sig: int) -> None:
    """The end of a server the user stopped: status 0, no error, no traceback, and the one line
    ``omnikin COMMAND: stopped (HOW)`` last (``omnikin ros``: its node stops the wheels and ends
    without a line, after its ROS log)."""
    how = "Ctrl-C" if sig == signal.SIGINT else signal.Signals(sig).name
    assert status == 0, f"omnikin {command} stopped with {signal.Signals(sig).name}: exit {status}: {err[-800:]}"
    assert "Traceback" not in err and "error:" not in err, err[-800:]
    if command != "ros":
        assert err.strip().splitlines()[-1:] == [f"omnikin {command}: stopped ({how})"], err[-800:]


def wait_node(proc: subprocess.Popen, domain: int, name: str = "omnikin_base") -> None:
    """Wait until the ROS 2 node ``name`` of ``proc`` is on the graph of ``domain`` (seen from an
    rclpy context of the test's own, without signal handlers)."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain, signal_handler_options=SignalHandlerOptions.NO)
    probe = rclpy.create_node("omnikin_test_probe", context=context)
    try:
        deadline = time.monotonic() + UP_TIMEOUT
        while name not in probe.get_node_names():
            if proc.poll() is not None:
                raise AssertionError(f"omnikin ros ended before its node came up: {proc.communicate()[1][-800:]}")
            assert time.monotonic() < deadline, f"no node {name} on ROS domain {domain} within {UP_TIMEOUT:g} s"
            time.sleep(0.2)
    finally:
        probe.destroy_node()
        rclpy.shutdown(context=context)
