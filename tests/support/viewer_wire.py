"""The viewers under test: a real ``omnikin view`` process, a viewer of this process served from a
thread (:func:`served`), and a raw client of viser's protocol, for the tests that attack the
viewer as another program would (no browser).

viser's wire format (viser 1.1, read from ``viser/infra/_infra.py``, written here again
independently): a page sends each message as one binary WebSocket message, the msgpack of a dict
with a ``type``; the server sends frames of two little-endian uint64 (the msgpack's size, the
compressed size), the zstd-compressed msgpack ``{"messages": [...], ...}``, then raw buffers.
The WebSocket subprotocol names viser's version (``viser-v1.1.1``).
"""

from __future__ import annotations

import re
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Protocol, TypeVar

import msgspec
import numpy as np
import psutil
import viser
import viser.transforms as vtf
import zstandard
from websockets.sync.client import ClientConnection, connect

from support.paths import omnikin_env

SUBPROTOCOL = f"viser-v{viser.__version__}"
INPUT_CONTROLS = (
    "GuiSliderMessage",
    "GuiNumberMessage",
    "GuiButtonMessage",
    "GuiButtonGroupMessage",
    "GuiDropdownMessage",
    "GuiCheckboxMessage",
    "GuiTextMessage",
)
"""viser's messages that create a control a page can change."""


class Served(Protocol):
    def run(self, duration: float | None = None) -> str: ...

    def close(self) -> None: ...


V = TypeVar("V", bound=Served)


@contextmanager
def served(viewer: V) -> Iterator[V]:
    """Serve ``viewer`` (a ``LiveViewer`` or ``ReplayViewer`` of this process) from a thread of its
    own while the block runs; close it and wait for that thread (10 s at most) after."""
    thread = threading.Thread(target=viewer.run, daemon=True)
    thread.start()
    try:
        yield viewer
    finally:
        viewer.close()
        thread.join(timeout=10)


def start_viewer(*args: str) -> tuple[subprocess.Popen, str]:
    """``omnikin view ARGS --port 0 --duration 300`` in a new process; it and the page's URL."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "view", *args, "--port", "0", "--duration", "300"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=omnikin_env(),
    )
    line = proc.stdout.readline() if proc.stdout else ""
    found = re.search(r"http://\S+/", line)
    if not found:
        proc.kill()
        raise AssertionError(f"no address printed: {line!r} {proc.communicate()[1][-2000:]}")
    return proc, found.group(0)


def stop_viewer(proc: subprocess.Popen) -> str:
    """Stop the viewer (SIGTERM, a normal end) and return its standard error."""
    proc.terminate()
    try:
        _, err = proc.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    return err


def listening_sockets(pid: int) -> list[tuple[str, int]]:
    """Every TCP address ``pid`` and its children listen on."""
    process = psutil.Process(pid)
    found = set()
    for p in [process, *process.children(recursive=True)]:
        for c in p.net_connections(kind="inet"):
            if c.status == psutil.CONN_LISTEN:
                found.add((c.laddr.ip, c.laddr.port))
    return sorted(found)


def decode_frame(frame: bytes) -> list[dict]:
    """The messages of one frame the viser server sent."""
    size = int.from_bytes(frame[:8], "little")
    compressed = int.from_bytes(frame[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(frame[16 : 16 + compressed], max_output_size=size)
    return list(msgspec.msgpack.decode(inner)["messages"])


NOTICE_TITLE = re.compile(r"omnikin refused (an input|(\d+) inputs) from this page \((\d+) since the viewer started\)")


def notices(messages: list[dict]) -> list[tuple[int, int]]:
    """The notices of refused inputs among ``messages``: per notice ``(refusals it tells, refusals
    since the viewer started)``, read from its title."""
    told = []
    for m in messages:
        if m.get("type") == "NotificationShowMessage":
            found = NOTICE_TITLE.fullmatch(m["props"]["title"])
            assert found, m["props"]["title"]
            told.append((1 if found[2] is None else int(found[2]), int(found[3])))
    return told


class ViserClient:
    """A raw client of the page's scene socket, as a page of the front's own origin opens it; a
    thread of its own reads every frame as it comes (a page that stops reading is dropped by the
    server's keepalive, as it should be)."""

    def __init__(self, url: str):
        ws_url = url.replace("http://", "ws://")
        self.ws: ClientConnection = connect(
            ws_url, origin=url.rstrip("/"), subprotocols=[SUBPROTOCOL], max_size=None, open_timeout=20
        )
        self.received: list[dict] = []
        self.closed: BaseException | None = None
        self._reader = threading.Thread(target=self._read_all, daemon=True)
        self._reader.start()

    def _read_all(self) -> None:
        try:
            for frame in self.ws:
                if isinstance(frame, bytes):
                    self.received.extend(decode_frame(frame))
        except Exception as e:  # noqa: BLE001 (the socket closed, or a frame not in viser's format: said by read())
            self.closed = e

    def send(self, message: dict | bytes | str) -> None:
        self.ws.send(message if isinstance(message, (bytes, str)) else msgspec.msgpack.encode(message))

    def read(self, until, timeout: float = 20.0) -> list[dict]:
        """Wait until ``until(received)`` holds; every message received."""
        end = time.monotonic() + timeout
        while not until(list(self.received)):
            if self.closed is not None or not self._reader.is_alive():
                raise AssertionError(f"the socket stopped: {self.closed!r}, close code {self.ws.close_code}")
            if time.monotonic() > end:
                raise AssertionError(f"never satisfied within {timeout} s")
            time.sleep(0.02)
        return list(self.received)

    def of_type(self, *kinds: str) -> list[dict]:
        return [m for m in list(self.received) if m.get("type") in kinds]

    def controls(self) -> dict[str, dict]:
        """The page's input controls after the backlog: uuid -> creating message."""
        self.read(lambda got: any(m.get("type") == "ReplayDoneMessage" for m in got))
        return {m["uuid"]: m for m in self.of_type(*INPUT_CONTROLS)}

    def close(self) -> None:
        self.ws.close()
        self._reader.join(timeout=10)


def world_transform(scene: viser.SceneApi, name: str) -> vtf.SE3:
    """The pose in the world of scene node ``name``: the product of its own and its ancestors'
    transforms (viser's scene tree: ``/a/b`` is a child of ``/a``), from the server's scene state."""
    handles = scene._handle_from_node_name  # the server's scene state, by node name
    parts = name.strip("/").split("/")
    pose = vtf.SE3.identity()
    for k in range(1, len(parts) + 1):
        handle = handles.get("/" + "/".join(parts[:k]))
        if handle is not None:
            local = vtf.SE3.from_rotation_and_translation(vtf.SO3(np.asarray(handle.wxyz)), np.asarray(handle.position))
            pose = pose @ local
    return pose
