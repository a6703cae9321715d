"""Helpers for driving a real browser page in the viewer tests: the Chromium command line, the
request guard, waiting on the page, keys, page-side time and reading colours off a screenshot.

The fixtures that use them (``browser``, ``page``, ``page_log``) are in ``browser_fixtures.py``,
which also explains the flags and the pitfalls.
"""

from __future__ import annotations

import io
import ipaddress
import shutil
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit

import numpy as np

if TYPE_CHECKING:
    from playwright.sync_api import ConsoleMessage, Error, Page, Route, ViewportSize, WebSocket

LOOPBACK_RULES = "MAP * ~NOTFOUND , EXCLUDE 127.0.0.1 , EXCLUDE localhost , EXCLUDE [::1]"
"""Chromium's host-resolver rules: every host but the loopback ones fails to resolve, IP
literals included, so nothing the page, its workers or Chromium itself open leaves the machine."""

CHROMIUM_FLAGS = (
    "--disable-gpu",  # no GPU here: WebGL2 runs on SwiftShader (ANGLE on Vulkan, in software)
    # allows WebGL's software fallback, which Chromium deprecated (137); headless Chromium 150 here
    # renders without it, but Playwright passes it anyway and keeping it guards other versions
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    f"--host-resolver-rules={LOOPBACK_RULES}",
)
"""Flags on top of Playwright's own (it adds --headless, --no-sandbox, a new empty
--user-data-dir per launch and some of the above; repeating them keeps this list complete)."""

VIEWPORT: ViewportSize = {"width": 1024, "height": 768}
"""The page size [CSS px]; screenshots are this size (device scale factor 1)."""


def find_chromium() -> str | None:
    """Debian's Chromium (``/usr/bin/chromium``, or ``chromium`` on ``PATH``), or ``None``."""
    if Path("/usr/bin/chromium").is_file():
        return "/usr/bin/chromium"
    return shutil.which("chromium")


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago (for a server under test)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def is_local(url: str) -> bool:
    """Whether the page may load ``url``: ``data:``, ``blob:`` and ``about:`` URLs, and URLs whose
    host is a loopback address (127.0.0.0/8, ::1) or ``localhost``."""
    parts = urlsplit(url)
    if parts.scheme in ("data", "blob", "about"):
        return True
    host = parts.hostname or ""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass
class PageLog:
    """What a page did that a test may want to rule out: requests to other machines (aborted by
    the guard), WebSockets to other machines (they fail on the resolver rules), console errors
    and uncaught page errors; and every WebSocket it opened (a viser client opens one)."""

    external: list[str] = field(default_factory=list)
    websockets: list[str] = field(default_factory=list)
    console_errors: list[str] = field(default_factory=list)
    page_errors: list[str] = field(default_factory=list)

    def guard(self, route: Route) -> None:
        """The ``context.route`` handler: loopback requests go on, the rest is aborted and logged.
        It sees the page's and its workers' HTTP requests, not WebSockets (see :meth:`watch`)."""
        url = route.request.url
        if is_local(url):
            route.continue_()
        else:
            self.external.append(url)
            route.abort("blockedbyclient")

    def watch(self, page: Page) -> None:
        """Log ``page``'s WebSockets (its workers' too: viser opens its socket in a Web Worker),
        console errors and uncaught exceptions."""

        def on_websocket(socket: WebSocket) -> None:
            self.websockets.append(socket.url)
            if not is_local(socket.url):
                self.external.append(socket.url)

        def on_console(message: ConsoleMessage) -> None:
            if message.type == "error":
                self.console_errors.append(message.text)

        def on_page_error(error: Error) -> None:
            self.page_errors.append(str(error))

        page.on("websocket", on_websocket)
        page.on("console", on_console)
        page.on("pageerror", on_page_error)


def wait_for(page: Page, js_expr: str, timeout: float = 10.0) -> Any:
    """Wait until the JavaScript expression ``js_expr`` is truthy on ``page`` (evaluated every
    animation frame) and return its value; ``timeout`` [s]. On timeout an ``AssertionError``
    names the expression."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    try:
        return page.wait_for_function(js_expr, timeout=timeout * 1000).json_value()
    except PlaywrightTimeout:
        raise AssertionError(f"the page never satisfied {js_expr!r} within {timeout} s") from None


def wait_until(condition: Callable[[], Any], what: str, timeout: float = 30.0) -> None:
    """Wait until ``condition()`` (a check in this process: a viewer's state, what a listener
    recorded) is truthy, looking every 50 ms; ``timeout`` [s] guards against a hang, never a pace.
    On timeout an ``AssertionError`` says ``what`` was awaited."""
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"no {what} within {timeout} s")
        time.sleep(0.05)


VISER_CONNECTED = "document.querySelector('svg.tabler-icon-cloud-check') !== null"
"""True while a viser client's WebSocket is connected: the green cloud icon in its control panel
(the label next to it reads 'Connected' unless the server set a label of its own)."""


def wait_for_viser(page: Page, timeout: float = 20.0) -> None:
    """Wait until the viser client on ``page`` is connected to its server; ``timeout`` [s]. The
    scene may not be drawn yet: wait for a colour (:func:`wait_for_colour`) for that."""
    wait_for(page, VISER_CONNECTED, timeout)


def page_seconds(page: Page) -> float:
    """The page's clock, ``performance.now()`` [s] since the page's time origin: the clock of
    event ``timeStamp`` values, unaffected by the test process's scheduling."""
    return page.evaluate("performance.now()") / 1000.0


KEY_RECORDER = """() => {
  window.__keyEvents = [];
  for (const type of ['keydown', 'keyup'])
    window.addEventListener(type, (e) => window.__keyEvents.push(
      {type: e.type, key: e.key, code: e.code, repeat: e.repeat, t: e.timeStamp / 1000,
       handled: performance.now() / 1000}), true);
}"""


def record_keys(page: Page) -> None:
    """Start logging ``page``'s keydown/keyup events (window, capture phase, so a handler that
    stops propagation does not hide them); read them with :func:`recorded_keys`."""
    page.evaluate(KEY_RECORDER)


def recorded_keys(page: Page) -> list[dict]:
    """The key events logged since :func:`record_keys`: dicts with ``type``, ``key``, ``code``,
    ``repeat``, ``t`` (the event's ``timeStamp`` [s], on :func:`page_seconds`' clock: when the
    key went down or up) and ``handled`` [s, same clock]: when the page's handlers ran, which is
    later while the page's thread is busy (drawing a frame in software takes tens of ms)."""
    return page.evaluate("window.__keyEvents")


def hold_key(page: Page, key: str, seconds: float, repeat_every: float | None = None) -> None:
    """Hold ``key`` (a Playwright key name: 'w', 'ArrowUp', 'Shift') down on ``page`` for about
    ``seconds`` [s], then release it. Playwright does not auto-repeat: without ``repeat_every``
    the page sees one keydown and one keyup; with it [s], a keydown with ``repeat`` true follows
    every ``repeat_every`` as a real keyboard's auto-repeat does. Exact durations are on the page's
    clock (the events' time stamps), not this function's: the hold is timed from the moment the
    browser has taken the keydown (Playwright returns once it has), so however late a loaded
    machine delivers that first event, the page sees the key down for at least ``seconds``."""
    page.keyboard.down(key)
    start = time.monotonic()
    if repeat_every is not None:
        for k in range(1, int(seconds / repeat_every) + 1):  # on a fixed schedule: no drift
            if k * repeat_every >= seconds:
                break
            time.sleep(max(0.0, start + k * repeat_every - time.monotonic()))
            page.keyboard.down(key)  # Playwright marks a down of a key already down as a repeat
    time.sleep(max(0.0, start + seconds - time.monotonic()))
    page.keyboard.up(key)


def screenshot_rgb(page: Page) -> np.ndarray:
    """The page's viewport as an ``(height, width, 3)`` float array of RGB in [0, 1] (PNG decoded
    by matplotlib)."""
    from matplotlib.image import imread

    return imread(io.BytesIO(page.screenshot(type="png")), format="png")[..., :3]


def colour_mask(image: np.ndarray, rgb: tuple[int, int, int], tolerance: float = 0.15) -> np.ndarray:
    """Pixels of ``image`` (RGB in [0, 1]) showing a lit surface of colour ``rgb`` (0..255, a
    saturated colour). Shading scales a surface's colour and adds grey (ambient, specular light),
    which leaves its chroma direction ``c - min(c)`` / ``max(c - min(c))`` unchanged: a pixel
    matches when its direction is within ``tolerance`` of the colour's in every channel and its
    chroma ``max - min`` is at least half the colour's (greys and pale tints do not match)."""
    target = np.asarray(rgb, dtype=float) / 255.0
    target_chroma = target.max() - target.min()
    if target_chroma < 0.5:
        raise ValueError(f"colour {rgb} is not saturated enough to find by its hue")
    chroma = image.max(axis=-1) - image.min(axis=-1)
    direction = (image - image.min(axis=-1, keepdims=True)) / np.maximum(chroma, 1e-9)[..., None]
    target_direction = (target - target.min()) / target_chroma
    close = np.all(np.abs(direction - target_direction) <= tolerance, axis=-1)
    return close & (chroma >= 0.5 * target_chroma)


def wait_for_colour(page: Page, rgb: tuple[int, int, int], min_pixels: int = 100, timeout: float = 20.0) -> np.ndarray:
    """Take screenshots of ``page`` until at least ``min_pixels`` pixels show colour ``rgb``
    (:func:`colour_mask`) and return that mask; ``timeout`` [s]. This is the signal that a scene
    has been drawn: viser draws on demand, some frames after its client connects."""
    end = time.monotonic() + timeout
    while True:
        mask = colour_mask(screenshot_rgb(page), rgb)
        if mask.sum() >= min_pixels:
            return mask
        if time.monotonic() > end:
            raise AssertionError(f"after {timeout} s only {mask.sum()} pixels of the page show colour {rgb}")
        time.sleep(0.2)
