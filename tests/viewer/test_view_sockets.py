"""Every socket a real ``omnikin view`` process listens on refuses what another web site, a
re-pointed DNS name or a script without a page can send; the page of the printed address still
drives the robot.

The sockets are enumerated from the operating system (psutil: every TCP socket in LISTEN of the
process and its children), not from what the viewer prints: a server it starts and does not
mention (such as viser's own, which on a loopback port would take a WebSocket from anyone) is
attacked too.
"""

from __future__ import annotations

import http.client
import os
import socket
import stat
from pathlib import Path

import psutil
import pytest
from websockets.exceptions import InvalidHandshake, InvalidStatus
from websockets.sync.client import connect

from support.browser import hold_key, wait_for
from support.viewer_wire import SUBPROTOCOL, listening_sockets, start_viewer, stop_viewer

PATHS = ("/", "/omnikin/keys")
"""viser's scene socket (the page connects to its own origin) and the key channel."""


def reach(ip: str) -> str:
    """The address to connect to for a socket listening on ``ip``."""
    return {"0.0.0.0": "127.0.0.1", "::": "::1"}.get(ip, ip)


def netloc(ip: str, port: int) -> str:
    return f"[{ip}]:{port}" if ":" in ip else f"{ip}:{port}"


def websocket_attempt(ip: str, port: int, path: str, *, host: str | None = None, origin: str | None) -> str:
    """Open a WebSocket to ``ip:port`` at ``path`` with the given ``Host`` (default: the
    address) and ``Origin`` (None: none sent), offering viser's subprotocol; 'open' when the
    server took it, else how it was refused."""
    sock = socket.create_connection((ip, port), timeout=10)
    try:
        ws = connect(
            f"ws://{host or netloc(ip, port)}{path}",
            sock=sock,
            origin=origin,  # type: ignore[arg-type]
            subprotocols=[SUBPROTOCOL],  # type: ignore[list-item]
            open_timeout=10,
        )
    except InvalidStatus as e:
        return f"refused {e.response.status_code}"
    except (InvalidHandshake, OSError, TimeoutError) as e:
        return f"failed {type(e).__name__}"
    finally:
        sock.close()
    ws.close()
    return "open"


def page_status(ip: str, port: int, host: str) -> int:
    conn = http.client.HTTPConnection(ip, port, timeout=10)
    try:
        conn.request("GET", "/", headers={"Host": host})
        return conn.getresponse().status
    finally:
        conn.close()


@pytest.fixture
def viewer():
    proc, url = start_viewer("tomasi-omni3")
    try:
        yield proc, url
    finally:
        err = stop_viewer(proc)
        assert "Traceback" not in err, err[-2000:]


def test_every_listening_socket_refuses_other_sites_rebinding_and_scripts_without_a_page(viewer):
    proc, url = viewer
    sockets = listening_sockets(proc.pid)
    printed = int(url.rstrip("/").rsplit(":", 1)[1])
    assert printed in {port for _, port in sockets}
    for ip, port in sockets:
        ip = reach(ip)
        own = netloc(ip, port)
        for path in PATHS:
            # another web site open in the user's browser (cross-site WebSocket hijacking)
            assert websocket_attempt(ip, port, path, origin="http://evil.example") == "refused 403", (ip, port, path)
            assert websocket_attempt(ip, port, path, origin="null") == "refused 403"
            # a site that re-pointed its name at this computer: Host and Origin agree, name foreign
            rebound = f"evil.example:{port}"
            assert websocket_attempt(ip, port, path, host=rebound, origin=f"http://{rebound}") == "refused 403"
            # a local program with no page at all (no Origin)
            assert websocket_attempt(ip, port, path, origin=None) == "refused 403"
            # ... and the page itself, asked for by the re-pointed name
        assert page_status(ip, port, f"evil.example:{port}") == 403
        # the same requests from the page's own origin are taken: the refusals above are the policy
        assert page_status(ip, port, own) == 200
        assert websocket_attempt(ip, port, "/", origin=f"http://{own}") == "open"
    assert len(sockets) == 1, f"the viewer listens on more than its front: {sockets}"


def test_viser_s_server_is_a_unix_socket_in_a_folder_only_this_user_can_open(viewer):
    proc, _ = viewer
    paths = {c.laddr for c in psutil.Process(proc.pid).net_connections(kind="unix") if c.laddr}
    inner = [Path(p) for p in paths if Path(p).name == "viser.sock"]
    assert len(inner) == 1, paths
    folder = inner[0].parent
    info = folder.stat()
    assert stat.S_IMODE(info.st_mode) == 0o700 and info.st_uid == os.getuid()
    assert stat.S_IMODE(inner[0].stat().st_mode) & 0o077 == 0
    stop_viewer(proc)
    assert not folder.exists()  # nothing left behind


def test_the_page_of_the_printed_address_still_drives_the_robot(viewer, page, page_log):
    _, url = viewer
    page.goto(url)
    page.wait_for_selector("#omnikin-readout[data-x]", timeout=30000)
    wait_for(page, "document.documentElement.dataset.omnikinKeys === 'connected'")
    hold_key(page, "w", 1.0)  # forward (the distance is test_view_page's business; a loaded page is late)
    wait_for(page, "Number(document.querySelector('#omnikin-readout').dataset.x) > 0.001", timeout=60)
    assert page_log.page_errors == [] and page_log.external == []


def test_the_page_says_plainly_when_the_viewer_has_stopped(viewer, page):
    proc, url = viewer
    page.goto(url)
    page.wait_for_selector("#omnikin-readout[data-x]", timeout=30000)
    wait_for(page, "document.documentElement.dataset.omnikinKeys === 'connected'")
    assert page.locator("#omnikin-gone").count() == 0  # no banner while the viewer runs
    stop_viewer(proc)
    banner = page.wait_for_selector("#omnikin-gone", timeout=20000)
    assert banner is not None
    assert "omnikin viewer has stopped" in banner.inner_text()
