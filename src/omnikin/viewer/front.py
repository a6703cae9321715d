"""The viewer's front server: one address for the page, the 3D scene and the keyboard.

viser serves its page and its scene over one port but passes no key events to Python (its
client handles keys for its own shortcuts only), and it cannot serve a script of ours. The
front server therefore stands on the user's address (``--host``, ``--port``) in front of a
viser server that listens on a Unix socket only this user can open
(:func:`omnikin.viewer.serving.start_viser`): the front is the only socket a browser can reach.

- ``GET /`` (and ``/index.html``): viser's own client page (bundled in the viser wheel, no
  internet needed) with ``<script src="/omnikin/teleop.js">`` added to its head;
- ``GET /omnikin/teleop.js``: the key script (:file:`teleop.js`): held keys as press and
  release messages over a WebSocket;
- WebSocket ``/omnikin/keys``: those messages, each handed to ``on_key`` as a dict with the
  socket's identity as ``source`` (:func:`parse_key_message` checks them; anything else is counted
  in :attr:`FrontServer.rejected`);
- any other WebSocket: relayed both ways, message by message, to the viser server (the
  client connects to the page's own origin, so it lands here). Each message of the page is
  first checked by ``inputs`` (:class:`omnikin.viewer.inputs.PageInputs`, the one boundary of
  the page's values): a refused one is not relayed, and the page is told instead, at most once
  a second (:class:`omnikin.viewer.inputs.NoticeLimiter`: a notice says how many it covers; the
  held ones are told when the second has passed, even if nothing more comes).

Time (the key messages' rate, the notices' interval) is ``clock``'s, the monotonic clock unless
a test gives its own.

Nothing a peer sends prints a traceback: the WebSocket library's log (a request that is not a
GET, a broken handshake, a peer gone mid-message) and any error left in the server's tasks are
counted in :attr:`FrontServer.problems` (the last one in :attr:`FrontServer.last_problem`),
never printed; the connection concerned is closed.

Every request must name this computer in its ``Host`` header (an IP address, ``localhost`` or
one of its host names, :func:`trusted_host`): a web site whose name was re-pointed at this
computer (DNS rebinding) gets neither the page nor a WebSocket. Every WebSocket must come from a
page of this server (its ``Origin`` header names the same host and port as its ``Host`` header):
another web site open in the user's browser cannot drive the robot (cross-site WebSocket
hijacking). A page's message may be at most :data:`MAX_INCOMING` bytes; a peer that does not
answer the closing handshake is dropped after :data:`CLOSE_TIMEOUT`.
"""

from __future__ import annotations

import asyncio
import gzip
import http
import ipaddress
import json
import logging
import os
import socket
import threading
import time
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from urllib.parse import urlsplit

from websockets.asyncio.client import unix_connect
from websockets.asyncio.server import ServerConnection, serve
from websockets.datastructures import Headers
from websockets.exceptions import ConnectionClosed
from websockets.http11 import Request, Response

from ..common.messages import shorten
from ..errors import InputError
from ..runtime.teleop import MOVES
from .inputs import NoticeLimiter, PageInputs

KEYS_PATH = "/omnikin/keys"
SCRIPT_PATH = "/omnikin/teleop.js"
KEY_MESSAGE_TYPES = ("press", "release", "release_all", "alive")
KEY_ACTIONS = (
    *MOVES,
    "stop",
    "steer_left",
    "steer_right",
    "camera_free",
    "camera_top",
    "camera_follow",
    "camera_run",
)
"""The actions :file:`teleop.js` sends (W S A D Q E, space, ] [, 1 2 3 4)."""
NOTICE_POLL = 0.25
"""Longest sleep [s] between two looks at a page's held refusals (:class:`NoticeLimiter`)."""
MAX_KEY_MESSAGE = 256
"""Longest key message [bytes]; a longer one closes its socket."""
KEY_RATE, KEY_BURST = 100.0, 50
"""Key messages a socket may send [1/s] after a burst of that many: a page sends one per key
change and an ``alive`` every 0.1 s; the rest is dropped and counted in ``rejected``."""
MAX_INCOMING = 1 << 20
"""Largest message [bytes] a page may send (viser's client sends camera moves and GUI values,
the key script a few bytes): a larger one closes its socket before it is buffered further."""
CLOSE_TIMEOUT = 1.0
"""Longest wait [s] for a peer's closing handshake; a silent peer does not hold up the exit."""
MAX_CONNECTIONS = 64
"""WebSockets served at once (pages' scene relays and key channels); more are closed (1013)."""
START_TIMEOUT = 10.0
"""Longest wait [s] for the server to listen."""


def parse_key_message(text) -> dict | None:
    """The key message ``text`` as ``{"type": ..., "action": ...}``, or None when it is not one
    (not JSON, not an object, an unknown type or action)."""
    if not isinstance(text, str):
        return None
    try:
        message = json.loads(text)
    except ValueError:
        return None
    if not isinstance(message, dict) or message.get("type") not in KEY_MESSAGE_TYPES:
        return None
    kind = message["type"]
    if kind in ("press", "release"):
        action = message.get("action")
        if action not in KEY_ACTIONS:
            return None
        return {"type": kind, "action": action}
    return {"type": kind}


def viser_page() -> bytes:
    """viser's client page with the key script added to its head."""
    import viser

    path = Path(viser.__file__).resolve().parent / "client" / "build" / "index.html"
    try:
        page = path.read_text(encoding="utf-8")
    except OSError as e:
        raise InputError(f"viser's client page is missing ({path}: {e.strerror}): reinstall viser") from None
    head = page.find("</head>")
    if head < 0:
        raise InputError(f"viser's client page {path} has no </head>: this viser is not supported")
    tag = f'<script src="{SCRIPT_PATH}"></script>'
    return (page[:head] + tag + page[head:]).encode("utf-8")


def own_names(served: str = "") -> frozenset[str]:
    """The names this computer answers to: ``localhost``, its host names (with ``.local``, its
    mDNS name) and the name it was told to serve on (``served``, when not an address)."""
    names = {"localhost"}
    for name in (socket.gethostname(), socket.getfqdn(), served):
        name = (name or "").lower().rstrip(".")
        if not name or name == "localhost" or _is_address(name):
            continue
        names.add(name)
        names.add(f"{name.split('.')[0]}.local")
    return frozenset(names)


def _is_address(name: str) -> bool:
    try:
        ipaddress.ip_address(name.strip("[]"))
    except ValueError:
        return False
    return True


def trusted_host(host: str | None, names: frozenset[str]) -> bool:
    """True when a request's ``Host`` header names this computer: an IP address literal (a web
    site cannot make a browser send one for its own name) or one of ``names``. Any other name
    may be a site whose DNS was re-pointed at this computer (DNS rebinding): it gets nothing."""
    if not host:
        return False
    name = urlsplit(f"http://{host}").hostname
    if name is None:
        return False
    return _is_address(name) or name.lower() in names


def header(request: Request, name: str) -> str | None:
    """The request's one header ``name``; None when it is missing or given more than once."""
    values = request.headers.get_all(name)
    return values[0] if len(values) == 1 else None


def same_origin(request: Request) -> bool:
    """True when the request's ``Origin`` names the host and port it was sent to (``Host``)."""
    origin, host = header(request, "Origin"), header(request, "Host")
    if not origin or not host:
        return False
    parts = urlsplit(origin)
    return parts.scheme in ("http", "https") and parts.netloc.lower() == host.lower()


class _Counted(logging.Handler):
    """Counts what the WebSocket library logs for one server, printing nothing."""

    def __init__(self, front: FrontServer):
        super().__init__(logging.WARNING)
        self.front = front

    def emit(self, record: logging.LogRecord) -> None:
        self.front.problems += 1
        self.front.last_problem = record.getMessage()[:200]


def _reason(error: BaseException) -> str:
    """What went wrong when listening, in a few words (``address already in use``)."""
    if isinstance(error, OSError):
        if error.errno and error.errno > 0:
            return os.strerror(error.errno).lower()
        if error.strerror:
            return error.strerror.lower()
    return str(error)[:100]


def _response(status: http.HTTPStatus, body: bytes, content_type: str, gzipped: bool = False) -> Response:
    headers = Headers()
    headers["Content-Type"] = content_type
    headers["Content-Length"] = str(len(body))
    headers["Cache-Control"] = "no-store"
    if gzipped:
        headers["Content-Encoding"] = "gzip"
    return Response(status.value, status.phrase, headers, body)


class FrontServer:
    """Serves the page and the keys on ``host:port`` and relays the scene to the viser server on
    the Unix socket ``inner`` (module docstring), every message of a page checked by ``inputs``.
    ``on_key`` is called in the server's thread."""

    def __init__(
        self,
        host: str,
        port: int,
        inner: str,
        on_key: Callable[[dict], None],
        inputs: PageInputs,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.host = host
        self.clock = clock
        self.port = port
        self.inner = inner
        self.on_key = on_key
        self.inputs = inputs
        self.rejected = 0
        self.key_messages = 0
        self.connections = 0  # WebSockets open now
        self.problems = 0  # what the WebSocket library logged, or a task left as an error (module docstring)
        self.last_problem = ""
        self._names = own_names(host)
        self._log = logging.Logger("omnikin.viewer.front")  # not the root's: nothing reaches the terminal
        self._log.addHandler(_Counted(self))
        page = viser_page()
        self._page = page
        self._page_gzip = gzip.compress(page)
        self._script = resources.files("omnikin.viewer").joinpath("teleop.js").read_bytes()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None

    @property
    def url(self) -> str:
        """The page's address as a browser on this computer opens it (a wildcard host as
        127.0.0.1 or [::1], an IPv6 address in brackets)."""
        host = self.host
        shown = "127.0.0.1" if host in ("", "0.0.0.0") else ("[::1]" if host == "::" else host)
        if ":" in shown and not shown.startswith("["):
            shown = f"[{shown}]"
        return f"http://{shown}:{self.port}/"

    # --- HTTP ----------------------------------------------------------------------------------
    def _process_request(self, connection: ServerConnection, request: Request) -> Response | None:
        path = urlsplit(request.path).path
        if not trusted_host(header(request, "Host"), self._names):
            self.rejected += 1
            return _response(http.HTTPStatus.FORBIDDEN, b"unknown host name\n", "text/plain")
        if (header(request, "Upgrade") or "").lower() == "websocket":
            if not same_origin(request):
                return _response(http.HTTPStatus.FORBIDDEN, b"cross-origin WebSocket refused\n", "text/plain")
            return None
        if path in ("/", "/index.html"):
            if "gzip" in (header(request, "Accept-Encoding") or ""):
                return _response(http.HTTPStatus.OK, self._page_gzip, "text/html; charset=utf-8", gzipped=True)
            return _response(http.HTTPStatus.OK, self._page, "text/html; charset=utf-8")
        if path == SCRIPT_PATH:
            return _response(http.HTTPStatus.OK, self._script, "application/javascript; charset=utf-8")
        return _response(http.HTTPStatus.NOT_FOUND, b"not found\n", "text/plain")

    # --- WebSockets ----------------------------------------------------------------------------
    async def _handle(self, connection: ServerConnection) -> None:
        if self.connections >= MAX_CONNECTIONS:
            self.rejected += 1
            await connection.close(code=1013, reason="too many connections")
            return
        self.connections += 1
        try:
            request = connection.request
            if request is not None and urlsplit(request.path).path == KEYS_PATH:
                await self._keys(connection)
            else:
                await self._relay(connection)
        finally:
            self.connections -= 1

    async def _keys(self, connection: ServerConnection) -> None:
        tokens, refilled = float(KEY_BURST), self.clock()
        try:
            async for text in connection:
                now = self.clock()
                tokens, refilled = min(float(KEY_BURST), tokens + (now - refilled) * KEY_RATE), now
                if tokens < 1.0:
                    self.rejected += 1  # faster than any page types: dropped
                    continue
                tokens -= 1.0
                if len(text) > MAX_KEY_MESSAGE:
                    self.rejected += 1
                    await connection.close(code=1009, reason="key message too long")
                    break
                message = parse_key_message(text)
                if message is None:
                    self.rejected += 1
                    continue
                self.key_messages += 1
                message["source"] = id(connection)  # whose keys: each page's are held and released apart
                self.on_key(message)
        except ConnectionClosed:
            pass
        finally:
            self.on_key({"type": "release_all", "source": id(connection)})  # a closed page holds no key

    async def _relay(self, connection: ServerConnection) -> None:
        protocols = [connection.subprotocol] if connection.subprotocol else None
        try:
            async with unix_connect(
                self.inner,
                uri="ws://localhost/",
                subprotocols=protocols,
                max_size=None,  # viser's own scene messages (this computer's) may be large
                compression=None,
                close_timeout=CLOSE_TIMEOUT,
                logger=self._log,
            ) as inner:
                notices = NoticeLimiter(clock=self.clock)  # this page's
                held: list[asyncio.Task] = []

                async def tell_held() -> None:
                    """Tell the refusals held back once the interval has passed."""
                    try:
                        while notices.held:
                            await asyncio.sleep(min(max(notices.wait(), 0.01), NOTICE_POLL))
                            told = notices.due()
                            if told:
                                await connection.send(self.inputs.notice(notices.last, told))
                    except ConnectionClosed:
                        pass

                async def pump(source, sink, check: bool) -> None:
                    try:
                        async for message in source:
                            reason = self.inputs.check(message) if check else None
                            if reason is None:
                                await sink.send(message)
                                continue
                            # refused (counted by inputs): the page is told, viser sees nothing
                            told = notices.refuse(reason)
                            if told:
                                await connection.send(self.inputs.notice(reason, told))
                            elif not held or held[-1].done():
                                held.append(asyncio.create_task(tell_held()))
                    except ConnectionClosed:
                        pass  # either side went away: the other is closed below

                tasks = [
                    asyncio.create_task(pump(connection, inner, check=True)),
                    asyncio.create_task(pump(inner, connection, check=False)),
                ]
                _, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
                for task in [*pending, *held]:
                    task.cancel()
                await asyncio.gather(*pending, *held, return_exceptions=True)
        except (ConnectionClosed, OSError):
            pass

    @staticmethod
    def _select_subprotocol(connection: ServerConnection, offered):
        return next((p for p in offered if p.startswith("viser-v")), None)

    # --- life ----------------------------------------------------------------------------------
    def start(self) -> None:
        """Listen in a thread of its own; returns when listening (the port taken when ``port``
        was 0) or raises :class:`InputError` naming the address when it cannot."""
        self._thread = threading.Thread(target=self._run, name="omnikin-view-front", daemon=True)
        self._thread.start()
        if not self._ready.wait(START_TIMEOUT):
            raise InputError(
                f"the viewer did not start listening on {self.host}:{self.port} within {START_TIMEOUT:g} s"
            )
        if self._error is not None:
            error = self._error
            raise InputError(
                f"cannot listen on {shorten(self.host)}:{self.port} ({_reason(error)}): choose another --port or --host"
            ) from None

    def _on_loop_error(self, loop, context: dict) -> None:
        self.problems += 1
        self.last_problem = str(context.get("exception") or context.get("message", ""))[:200]

    def _run(self) -> None:
        loop = asyncio.new_event_loop()
        loop.set_exception_handler(self._on_loop_error)
        self._loop = loop
        try:
            loop.run_until_complete(self._serve())
        except BaseException as e:  # noqa: BLE001 (reported by start())
            self._error = e
            self._ready.set()
        finally:
            loop.close()

    async def _serve(self) -> None:
        self._stop = asyncio.Event()
        async with serve(
            self._handle,
            self.host,
            self.port,
            process_request=self._process_request,
            select_subprotocol=self._select_subprotocol,
            max_size=MAX_INCOMING,
            compression=None,
            close_timeout=CLOSE_TIMEOUT,
            logger=self._log,
        ) as server:
            self.port = server.sockets[0].getsockname()[1] if server.sockets else self.port
            self._ready.set()
            await self._stop.wait()

    def stop(self) -> None:
        """Stop listening and close every connection."""
        if self._loop is not None and self._stop is not None and not self._loop.is_closed():
            try:
                self._loop.call_soon_threadsafe(self._stop.set)
            except RuntimeError:
                pass
        if self._thread is not None:
            self._thread.join(START_TIMEOUT)
