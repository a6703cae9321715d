"""The viewer's screenshots in docs/viewer.md, taken again as a user sees the page.

    python3 benchmarks/viewer_screenshots.py [FOLDER]

writes ``viewer-live.png`` and ``viewer-replay.png`` (1280 x 800) into ``FOLDER`` (default
``docs/img``), with Debian's headless Chromium (Playwright, the flags of ``tests/support/browser.py``):

- live: ``omnikin view tomasi-omni3 --engine physics``; W and Q held together for 4 s (an arc),
  then the follow camera (key 3): the green heading arrow of the truth, the narrower magenta one
  of the odometry on it, the two trails behind;
- replay: ``omnikin umbmark --runs 1 --side 2`` (tomasi-omni3 as built, seed 1) played with
  ``omnikin view --replay``: "before cw run 1" at 23.19 s, "after cw run 1" shown together,
  camera "run".

This machine has no GPU: Chromium draws WebGL in software, and viser says so in a notice of its
own ("Software WebGL rendering detected") that a user's browser with a GPU does not show. The
notice is closed before each shot. Not a benchmark: it measures nothing, and takes a minute or
two.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from support.browser import CHROMIUM_FLAGS, find_chromium

ROOT = Path(__file__).resolve().parents[1]

SIZE = {"width": 1280, "height": 800}
"""The screenshots' size [CSS px, device scale 1]."""
SOFTWARE_NOTICE = "Software WebGL rendering detected"
READOUT = "document.querySelector('#omnikin-readout').dataset"
"""The readout's numbers in the page's JavaScript."""


def omnikin(*args: str) -> list[str]:
    return [sys.executable, "-m", "omnikin.cli.main", *args]


def serve(*args: str, cwd: str | None = None) -> tuple[subprocess.Popen, str]:
    """``omnikin view ARGS`` on a free port, in folder ``cwd``: the process and the page's address."""
    proc = subprocess.Popen(
        omnikin("view", *args, "--port", "0", "--duration", "900"), stdout=subprocess.PIPE, text=True, cwd=cwd
    )
    found = re.search(r"http://\S+/", proc.stdout.readline() if proc.stdout else "")
    if found is None:
        proc.kill()
        raise SystemExit(f"omnikin view {' '.join(args)} printed no address")
    return proc, found.group(0)


def open_page(browser, url: str):
    """The page at ``url``, drawn, its keys connected and viser's software-WebGL notice closed."""
    page = browser.new_page(viewport=SIZE)
    page.goto(url)
    page.wait_for_selector("#omnikin-readout[data-x]", timeout=60000)
    page.wait_for_function("document.documentElement.dataset.omnikinKeys === 'connected'", timeout=60000)
    notice = page.locator(".mantine-Notification-root", has_text=SOFTWARE_NOTICE)
    try:
        notice.wait_for(timeout=20000)
    except Exception:  # noqa: BLE001 (no notice: a GPU draws this page)
        return page
    notice.locator("button").first.click()
    notice.wait_for(state="detached", timeout=20000)
    return page


def live(browser, folder: Path) -> None:
    proc, url = serve("tomasi-omni3", "--engine", "physics")
    try:
        page = open_page(browser, url)
        time.sleep(2.0)  # the scene's first frames
        page.keyboard.down("w")
        page.keyboard.down("q")
        page.wait_for_function(f"{READOUT}.omega > 0.4", timeout=60000)  # driving
        time.sleep(4.0)
        page.keyboard.up("q")
        page.keyboard.up("w")
        page.wait_for_function(f"Math.abs({READOUT}.vx) < 1e-3 && Math.abs({READOUT}.omega) < 1e-3", timeout=60000)
        page.keyboard.press("3")  # follow camera
        time.sleep(4.0)  # the camera's move and the frames after it
        page.screenshot(path=folder / "viewer-live.png")
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def replay(browser, folder: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        report = "umbmark-report"  # named so on the page, in the folder both commands run in
        done = subprocess.run(
            omnikin("umbmark", "--runs", "1", "--side", "2", "-o", report), capture_output=True, cwd=tmp
        )
        if done.returncode != 0:
            raise SystemExit(f"omnikin umbmark failed: {done.stderr.decode()[-2000:]}")
        proc, url = serve("--replay", report, cwd=tmp)
        try:
            page = open_page(browser, url)
            time.sleep(2.0)
            page.get_by_role("checkbox", name="after cw run 1").check()
            field = page.get_by_role("textbox").nth(0)  # the time slider's number field comes first
            field.fill("23.19")
            field.press("Enter")
            page.wait_for_function(f"Math.abs({READOUT}.t - 23.19) < 1e-9", timeout=60000)
            page.get_by_role("button", name="run", exact=True).click()
            time.sleep(4.0)
            page.screenshot(path=folder / "viewer-replay.png")
        finally:
            proc.terminate()
            proc.wait(timeout=30)


def main(folder: Path) -> None:
    from playwright.sync_api import sync_playwright

    executable = find_chromium()
    if executable is None:
        raise SystemExit("viewer_screenshots needs Debian's Chromium (apt-get install chromium)")
    folder.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=executable, args=list(CHROMIUM_FLAGS))
        try:
            live(browser, folder)
            replay(browser, folder)
        finally:
            browser.close()
    print(f"wrote {folder / 'viewer-live.png'} and {folder / 'viewer-replay.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "img")
