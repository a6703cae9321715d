"""The browser harness on a bare viser server: WebGL draws the scene in headless Chromium, the
guard keeps and logs every request to another machine, and the waiting, key and clock helpers
do what the viewer tests rely on."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest

from support.browser import (
    VIEWPORT,
    VISER_CONNECTED,
    colour_mask,
    free_port,
    hold_key,
    page_seconds,
    record_keys,
    recorded_keys,
    screenshot_rgb,
    wait_for,
    wait_for_colour,
    wait_for_viser,
)

MAGENTA = (255, 0, 255)
"""The box's colour: nothing else on viser's page (white, blue buttons, a green icon, an orange
notice, the red/green/blue axes gizmo) has this hue."""

CYAN = (0, 255, 255)
"""A colour nothing in the scene has, to show the colour test tells colours apart."""


@pytest.fixture
def viser_box() -> Iterator[str]:
    """A real viser server on a free loopback port showing a unit magenta box at the origin, lit
    by the default lights only; its page's URL."""
    import viser

    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    server.scene.configure_environment_map(hdri=None)  # its software set-up costs 3-9 s per page
    server.scene.add_box("/box", color=MAGENTA, dimensions=(1.0, 1.0, 1.0), position=(0.0, 0.0, 0.0))
    try:
        yield f"http://127.0.0.1:{port}/"
    finally:
        server.stop()


def test_webgl_draws_the_viser_box_in_its_colour_at_the_centre(page, viser_box):
    page.goto(viser_box)
    wait_for_viser(page)
    wait_for_colour(page, MAGENTA, min_pixels=500)
    image = screenshot_rgb(page)
    assert image.shape == (VIEWPORT["height"], VIEWPORT["width"], 3)
    box = colour_mask(image, MAGENTA)
    rows, cols = np.nonzero(box)
    # viser's default camera looks at the origin: the box is drawn around the viewport's centre
    assert abs(rows.mean() - VIEWPORT["height"] / 2) < 0.1 * VIEWPORT["height"]
    assert abs(cols.mean() - VIEWPORT["width"] / 2) < 0.1 * VIEWPORT["width"]
    assert box.sum() > 2000  # about 5400 at 1024 x 768
    assert colour_mask(image, CYAN).sum() < 20


def test_viser_page_makes_no_external_request_and_no_error(page, page_log, viser_box):
    page.goto(viser_box)
    wait_for_viser(page)
    wait_for_colour(page, MAGENTA)
    assert page_log.websockets == [viser_box.replace("http://", "ws://")]
    assert page_log.external == []
    assert page_log.console_errors == []
    assert page_log.page_errors == []


def test_guard_stops_and_logs_requests_and_websockets_to_other_machines(page, page_log, viser_box):
    page.goto(viser_box)
    wait_for_viser(page)
    outside = {
        "http://example.com/page",  # a name
        "http://93.184.216.34/fetch",  # an address (something on this network answers it)
        "ws://93.184.216.34/socket",
        "http://93.184.216.34/from-worker",
        "ws://93.184.216.34/worker-socket",
    }
    fetched = page.evaluate(
        """async () => {
          new WebSocket('ws://93.184.216.34/socket');
          const code = "fetch('http://93.184.216.34/from-worker').catch(() => {});"
            + "new WebSocket('ws://93.184.216.34/worker-socket');";
          new Worker(URL.createObjectURL(new Blob([code], {type: 'text/javascript'})));
          const results = [];
          for (const url of ['http://example.com/page', 'http://93.184.216.34/fetch'])
            results.push(await fetch(url).then(() => 'loaded', () => 'failed'));
          return results;
        }"""
    )
    assert fetched == ["failed", "failed"]
    end = time.monotonic() + 10
    while set(page_log.external) != outside and time.monotonic() < end:
        page.wait_for_timeout(100)  # lets Playwright deliver the page's events
    assert set(page_log.external) == outside
    # the page's own loopback socket is untouched
    assert page_log.websockets[0] == viser_box.replace("http://", "ws://")
    assert page.evaluate(VISER_CONNECTED)


def test_wait_for_returns_the_value_and_names_the_expression_it_timed_out_on(page, viser_box, monkeypatch):
    page.goto(viser_box)
    assert wait_for(page, "document.title.length + 1") == len(page.title()) + 1
    asked: list = []  # the wait handed to the browser, in its milliseconds (not the machine's pace)
    real = page.wait_for_function
    monkeypatch.setattr(page, "wait_for_function", lambda e, timeout: asked.append(timeout) or real(e, timeout=timeout))
    with pytest.raises(AssertionError, match=r"never satisfied 'window.neverSet === 1' within 0.5 s"):
        wait_for(page, "window.neverSet === 1", timeout=0.5)
    assert asked == [500.0]


def test_a_held_key_is_one_keydown_and_one_keyup_its_duration_apart_on_the_page_clock(page, viser_box):
    page.goto(viser_box)
    record_keys(page)
    before = page_seconds(page)
    hold_key(page, "x", 0.5)
    after = page_seconds(page)
    events = recorded_keys(page)
    assert [(e["type"], e["key"], e["repeat"]) for e in events] == [("keydown", "x", False), ("keyup", "x", False)]
    down, up = events
    assert before <= down["t"] <= up["t"] <= after
    # held at least the 0.5 s the test slept between the two; at most the page's time around them
    assert 0.5 - 0.01 <= up["t"] - down["t"] <= after - before


def test_a_held_key_with_auto_repeat_sends_repeated_keydowns(page, viser_box):
    page.goto(viser_box)
    record_keys(page)
    hold_key(page, "x", 0.6, repeat_every=0.1)
    events = recorded_keys(page)
    downs = [e for e in events if e["type"] == "keydown"]
    assert downs[0]["repeat"] is False
    assert all(e["repeat"] for e in downs[1:])
    # one repeat at each 0.1 s mark before the release at 0.6 s, each sent however late: 5
    assert len(downs) - 1 == 5
    assert [e["type"] for e in events][-1] == "keyup"


def test_holding_w_moves_viser_camera_towards_the_box(page, viser_box):
    page.goto(viser_box)
    wait_for_viser(page)
    far = wait_for_colour(page, MAGENTA).sum()
    hold_key(page, "w", 0.5)  # viser: forward at 2 units/s, from about 5 units away
    end = time.monotonic() + 10
    near = far
    while near < 1.2 * far and time.monotonic() < end:
        near = colour_mask(screenshot_rgb(page), MAGENTA).sum()
    assert near >= 1.2 * far
