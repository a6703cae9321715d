"""``omnikin view ROBOT --ros`` follows a running ``omnikin ros`` node and drives it: real nodes
(the node, simulating the robot as its file says, and the viewer's own) on a ROS domain of their
own, the page in headless Chromium.

The node's runtime ramps its command at its acceleration limit (0.5 m/s^2, its default) from
the first cmd_vel and back to zero from the zero the page sends at the release, so the robot
covers ``v T`` in all, ``T`` the time the page held the key.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time

import pytest

from browser import hold_key, record_keys, recorded_keys, wait_for
from omnikin_paths import omnikin_env
from ros_domain import fresh_domain

pytestmark = pytest.mark.ros
SPEED = 0.2
READOUT = "#omnikin-readout"


def readout(page) -> dict:
    return page.evaluate(f"(() => {{ const d = document.querySelector('{READOUT}').dataset; return {{...d}}; }})()")


@pytest.fixture
def ros_env(tmp_path):
    """A ROS domain of this test's own (:func:`ros_domain.fresh_domain`), discovery on this host,
    logs in the test's folder."""
    env = omnikin_env(
        ROS_DOMAIN_ID=str(fresh_domain()),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_LOG_DIR=str(tmp_path / "ros_log"),
        PYTHONUNBUFFERED="1",
    )
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.pop("ROS_STATIC_PEERS", None)
    return env


def test_the_ros_view_follows_a_node_and_its_keys_drive_it(ros_env, page, page_log, tmp_path):
    procs = []
    try:
        node = subprocess.Popen(
            [sys.executable, "-m", "omnikin.cli.main", "ros", "tomasi-omni3", "--errors", "none", "--noise", "none"],
            env=ros_env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        procs.append(node)
        view = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "omnikin.cli.main",
                "view",
                "tomasi-omni3",
                "--ros",
                "--port",
                "0",
                "--duration",
                "120",
            ],
            env=ros_env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        procs.append(view)
        line = view.stdout.readline()
        found = re.search(r"http://\S+/", line)
        assert found, f"no address printed: {line!r}"
        assert f"ROS_DOMAIN_ID {ros_env['ROS_DOMAIN_ID']}" in line
        page.goto(found.group(0))
        page.wait_for_selector(f"{READOUT}[data-x]", timeout=30000)
        wait_for(page, "document.documentElement.dataset.omnikinKeys === 'connected'")
        # the node's odometry is on the page once the graph has met: its time advances
        first = float(readout(page)["t"])
        wait_for(page, f"Number(document.querySelector('{READOUT}').dataset.t) > {first + 1.0}", timeout=15)
        time.sleep(2.0)  # discovery: the node's subscription to the viewer's cmd_vel
        before = readout(page)
        record_keys(page)
        hold_key(page, "w", 1.2)
        time.sleep(SPEED / 0.5 + 0.6)
        wait_for(page, f"Number(document.querySelector('{READOUT}').dataset.vx) === 0", timeout=10)
        after = readout(page)
        events = [e for e in recorded_keys(page) if e["key"] == "w" and not e["repeat"]]
        held = events[-1]["handled"] - events[0]["handled"]
        # the page shows the node's ground truth as the robot and its odometry beside it
        assert float(after["x"]) - float(before["x"]) == pytest.approx(SPEED * held, abs=SPEED * 0.15)
        assert float(after["odomX"]) - float(before["odomX"]) == pytest.approx(SPEED * held, abs=SPEED * 0.15)
        assert abs(float(after["y"]) - float(before["y"])) < 1e-6  # the robot as the file says (no errors)
        assert page_log.external == [] and page_log.page_errors == []
    finally:
        for proc in reversed(procs):
            proc.terminate()
            try:
                _, err = proc.communicate(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, 9) if proc is node else proc.kill()
                _, err = proc.communicate()
            assert "Traceback" not in (err or ""), (err or "")[-2000:]
