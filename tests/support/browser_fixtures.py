"""Browser fixtures for the viewer tests (loaded by the root conftest, so that no second
``conftest`` module shadows it): one headless Chromium per session, a fresh context and page per
test, every page guarded against leaving the machine. Helpers are in ``browser.py``.

What the next engineer needs to know (measured with Debian's Chromium 150, Playwright 1.65,
viser 1.1.1, on this 2-core machine without a GPU):

- Browser: Debian's ``/usr/bin/chromium`` (a shell wrapper; the ``[: ... unexpected operator``
  it prints from /etc/chromium.d is harmless) through ``chromium.launch(executable_path=...)``;
  Playwright cannot download browsers here. Playwright already adds --headless, --no-sandbox, a
  new empty --user-data-dir per launch and most quiet-network flags; ``CHROMIUM_FLAGS`` adds
  --disable-gpu, --disable-quic and the loopback-only resolver rules.
- WebGL2 works headless with --disable-gpu: ANGLE on SwiftShader's Vulkan, in software
  (``--enable-unsafe-swiftshader`` is kept though Chromium 150 headless does not need it).
  viser shows a "Software WebGL rendering detected" notice in the top-left corner.
- Readiness: connected = the control panel's green cloud icon
  (``browser.VISER_CONNECTED``, 0.6-0.9 s after ``goto``; the label text can be replaced by the
  server's). Drawn = the scene's colour in a screenshot (``wait_for_colour``): viser draws on
  demand (``frameloop="demand"``), so connected does not mean drawn. The default environment
  map (HDRI) takes 3-9 s of software set-up per page load, during which the page draws no frame
  and screenshots stall; ``scene.configure_environment_map(hdri=None)`` draws in ~0.5 s.
- Cost: Playwright's driver starts in 0.25 s, Chromium in 0.2 s; with a viser page open
  Chromium holds ~500 MiB (PSS) and the node driver ~120 MiB.
- No external request: ``context.route`` aborts and logs non-loopback HTTP from the page and its
  workers but never sees WebSockets; ``page.on("websocket")`` sees every WebSocket, also a
  worker's (viser opens its socket in a Web Worker). Do not use ``context.route_web_socket``: it
  sees only main-thread sockets and replaces them with a mock relayed through Playwright. The
  resolver rules make every other host, IP literals included, fail to resolve: needed, since
  this network answers some outside addresses (a WebSocket to 93.184.216.34 got an HTTP 404).
- Console: viser logs only warnings (THREE.Clock deprecated, "GPU stall due to ReadPixels");
  ``page_log.console_errors`` and ``page_errors`` stay empty on a clean page. Blocked requests
  and failed WebSockets add console errors of their own.
- Keys: ``page.keyboard.down`` does not auto-repeat (``hold_key(repeat_every=...)`` emulates it).
  viser's own camera moves on W/A/S/D/Q/E and the arrow keys (document keydown listeners, fresh
  presses only): teleop keys reach it too. Compare key timing on the page's clock
  (``page_seconds``, event ``timeStamp``), not the test's.
- The sync API's objects belong to the thread that made them (the test's): never touch a page
  from a viser callback thread; the sync API refuses to run inside a running asyncio loop.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

from support.browser import CHROMIUM_FLAGS, VIEWPORT, PageLog, find_chromium

if TYPE_CHECKING:
    from playwright.sync_api import Browser, Page


@pytest.fixture(scope="session")
def browser() -> Iterator[Browser]:
    """Headless Debian Chromium for the whole session (one launch serves every viewer test);
    the tests skip, with the reason, where Playwright or Chromium is missing."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("the viewer tests need Python's playwright: pip install -e '.[test]'")
    executable = find_chromium()
    if executable is None:
        pytest.skip("the viewer tests need Debian's Chromium (/usr/bin/chromium): apt-get install chromium")
    playwright = sync_playwright().start()
    try:
        chromium = playwright.chromium.launch(executable_path=executable, args=list(CHROMIUM_FLAGS), headless=True)
        try:
            yield chromium
        finally:
            chromium.close()
    finally:
        playwright.stop()


@pytest.fixture
def page_log() -> PageLog:
    """What this test's page requested from other machines, and its console and page errors."""
    return PageLog()


@pytest.fixture
def page(browser: Browser, page_log: PageLog) -> Iterator[Page]:
    """A page in a fresh browser context (no cookies or storage from other tests), ``VIEWPORT``
    sized, whose requests to other machines are aborted and logged in ``page_log``."""
    context = browser.new_context(viewport=VIEWPORT)
    try:
        context.route("**/*", page_log.guard)
        page = context.new_page()
        page_log.watch(page)
        yield page
    finally:
        context.close()
