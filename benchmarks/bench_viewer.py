"""The viewer (extra ``viewer``): latency from a key press to the pose on the page.

``omnikin view tomasi-omni3`` (kinematic engine) is served on a free port and opened in Debian's
headless Chromium (Playwright, the flags of ``tests/support/browser.py``; software WebGL, no GPU). Then
``PRESSES`` times: the robot at rest, W is pressed and held, and the page records, on its own
clock, the key event's time stamp (when the key went down), when the page's handlers ran (the
teleop script sends then), and when the pose in the readout first changed (a MutationObserver on
the readout). Latency = pose changed - key down; the part inside the page (handlers run -
key down) is reported too. The reference measured in the same run is the page's frame interval
(``requestAnimationFrame`` while the robot moves): latency in frames says how much of it is the
page drawing. Target: median under 50 ms on this machine.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
import time

from _common import save
from support.browser import CHROMIUM_FLAGS, VIEWPORT, find_chromium

PRESSES = 20
HOLD = 0.25  # [s] each press
REST = 1.0  # [s] between presses: the robot stops (0.2 m/s at 0.5 m/s^2 takes 0.4 s)

OBSERVE = """() => {
  const readout = () => document.querySelector('#omnikin-readout');
  window.__keys = [];
  window.addEventListener('keydown', (e) => {
    if (e.repeat) return;
    window.__keys.push({down: e.timeStamp, handled: performance.now(), x0: readout().dataset.x, moved: null});
  }, true);
  new MutationObserver(() => {
    const last = window.__keys[window.__keys.length - 1];
    const el = readout();
    if (last && last.moved === null && el && el.dataset.x !== last.x0) last.moved = performance.now();
  }).observe(document.body, {subtree: true, childList: true, attributes: true});
}"""

FRAMES = """() => new Promise((done) => {
  const times = [];
  const frame = (t) => { times.push(t); if (times.length < 40) requestAnimationFrame(frame); else done(times); };
  requestAnimationFrame(frame);
})"""


def percentile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(q * (len(ordered) - 1))))]


def main() -> dict:
    from playwright.sync_api import sync_playwright

    executable = find_chromium()
    if executable is None:
        raise SystemExit("bench_viewer needs Debian's Chromium (apt-get install chromium)")
    cmd = [sys.executable, "-m", "omnikin.cli.main", "view", "tomasi-omni3", "--port", "0", "--duration", "600"]
    server = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        url = re.search(r"http://\S+/", server.stdout.readline()).group(0)  # type: ignore[union-attr]
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=executable, args=list(CHROMIUM_FLAGS))
            page = browser.new_page(viewport=VIEWPORT)
            page.goto(url)
            page.wait_for_selector("#omnikin-readout[data-x]", timeout=30000)
            page.wait_for_function("document.documentElement.dataset.omnikinKeys === 'connected'")
            time.sleep(2.0)  # the first frames and the scene's set-up
            page.evaluate(OBSERVE)
            frame_ms = []
            for k in range(PRESSES):
                page.keyboard.down("w")
                if k % 4 == 0:
                    times = page.evaluate(FRAMES)
                    frame_ms.append(statistics.median(b - a for a, b in zip(times, times[1:], strict=False)))
                time.sleep(HOLD)
                page.keyboard.up("w")
                time.sleep(REST)
            keys = page.evaluate("window.__keys")
            browser.close()
    finally:
        server.terminate()
        server.communicate(timeout=10)
    latency = [k["moved"] - k["down"] for k in keys if k["moved"] is not None]
    in_page = [k["handled"] - k["down"] for k in keys]
    frame = statistics.median(frame_ms)
    out = {
        "presses": len(keys),
        "seen": len(latency),
        "latency_ms": {"median": statistics.median(latency), "p95": percentile(latency, 0.95), "max": max(latency)},
        "handlers_after_key_ms": {"median": statistics.median(in_page), "max": max(in_page)},
        "frame_interval_ms": frame,
        "latency_in_frames": statistics.median(latency) / frame,
        "target_ms": 50.0,
    }
    print(f"key -> pose on the page, {len(latency)} of {len(keys)} presses (tomasi-omni3, kinematic, headless)")
    lat = out["latency_ms"]
    print(f"  latency       median {lat['median']:6.1f} ms   p95 {lat['p95']:6.1f} ms   max {lat['max']:6.1f} ms")
    print(f"  in the page   median {out['handlers_after_key_ms']['median']:6.1f} ms (key down -> handlers ran)")
    print(f"  frame         {frame:6.1f} ms (reference, same run): latency = {out['latency_in_frames']:.1f} frames")
    print(f"  target        median < 50 ms: {'met' if lat['median'] < 50 else 'NOT met'}")
    return out


if __name__ == "__main__":
    save("viewer", main())
