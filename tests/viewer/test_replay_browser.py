"""The replay page in headless Chromium: Play moves the robot along the recorded run, typing a
time in the slider's field scrubs to it, the run selector changes run; the pose the page shows
is checked against the closed form of the recorded motion (a circle at a constant twist)."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from omnikin.io.robot_file import load_robot
from omnikin.viewer.replay import PoseSeries, Track
from omnikin.viewer.replay_page import ReplayViewer
from omnikin.viewer.replay_sources import ReplaySource
from support.browser import wait_for, wait_for_viser
from support.viewer_wire import served

V, W = 0.3, 0.4  # the recorded twist [m/s, rad/s]: a circle of radius 0.75 m


def circle(t) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    return np.column_stack([V / W * np.sin(W * t), V / W * (1 - np.cos(W * t)), W * t])


@pytest.fixture
def replay() -> Iterator[ReplayViewer]:
    """A replay page of two recorded runs of tomasi-omni3, sampled at 5 Hz: ``circle`` for 10 s,
    and ``line`` (1 m along +x in 2 s)."""
    t = np.arange(0.0, 10.01, 0.2)
    line_t = np.array([0.0, 2.0])
    line = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    tracks = [
        Track("circle", PoseSeries(t, circle(t)), PoseSeries(t, circle(t) * 0.95)),
        Track("line", PoseSeries(line_t, line), PoseSeries(line_t, line)),
    ]
    with served(
        ReplayViewer(ReplaySource("a test", load_robot("tomasi-omni3"), tracks, side=1.0), "127.0.0.1", 0)
    ) as viewer:
        yield viewer


SHOWN = """() => {
    const status = document.querySelector('#omnikin-replay').dataset;
    const readout = document.querySelector('#omnikin-readout').dataset;
    return {run: status.run, playing: status.playing, t: Number(readout.t), x: Number(readout.x),
            y: Number(readout.y), theta: Number(readout.theta)};
}"""
"""The replay's status and the readout's pose, read at one instant (the page updates them
while it plays)."""


def shown(page) -> dict:
    return page.evaluate(SHOWN)


def on_circle(state: dict) -> None:
    exact = circle([state["t"]])[0]
    assert state["x"] == pytest.approx(exact[0], abs=1e-9) and state["y"] == pytest.approx(exact[1], abs=1e-9)
    assert math.remainder(state["theta"] - exact[2], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_play_scrub_and_run_selector_move_the_robot_along_the_recorded_run(page, page_log, replay):
    page.goto(replay.url)
    wait_for_viser(page)
    wait_for(page, "document.querySelector('#omnikin-readout[data-t]') !== null")
    start = shown(page)
    assert start["run"] == "circle" and start["t"] == 0.0 and start["playing"] == "false"

    page.get_by_role("button", name="Play").click()
    wait_for(page, "Number(document.querySelector('#omnikin-readout').dataset.t) > 1.0", timeout=15)
    playing = shown(page)
    assert playing["playing"] == "true"
    on_circle(playing)  # the pose shown at the time shown is the recorded motion's
    page.get_by_role("button", name="Pause").click()
    wait_for(page, "document.querySelector('#omnikin-replay').dataset.playing === 'false'")

    field = page.get_by_role("textbox").nth(0)  # the time slider's number field comes first
    field.fill("7.5")
    field.press("Enter")
    wait_for(page, "Math.abs(Number(document.querySelector('#omnikin-readout').dataset.t) - 7.5) < 1e-9")
    scrubbed = shown(page)
    on_circle(scrubbed)

    page.get_by_role("combobox").nth(0).click()  # the run selector (then the speed)
    page.get_by_role("option", name="line").click()
    wait_for(page, "document.querySelector('#omnikin-replay').dataset.run === 'line'")
    line = shown(page)
    assert (line["t"], line["x"], line["y"]) == (0.0, 0.0, 0.0)
    assert page_log.external == [] and page_log.page_errors == []
