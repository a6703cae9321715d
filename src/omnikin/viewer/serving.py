"""The two servers behind a viewer page: viser's, on a Unix socket that only this user can open,
and the front server on the user's address (:mod:`omnikin.viewer.front`), started and stopped
together.

**viser's server listens on no network port.** viser 1.x has no option for where it listens:
its server thread binds with ``websockets.asyncio.server.serve(handler, host, port, **options)``
(``WebsockServer._background_worker``). :func:`start_viser` replaces that one call, for viser's
own handler and only while ``viser.ViserServer()`` starts, with ``unix_serve(handler,
sock=...)`` on a socket it bound beforehand in a fresh directory of mode 0700 (the socket
itself 0600): a web page cannot reach a Unix socket, another user cannot open the directory,
and no TCP port is ever bound, not even for an instant. The seam is checked before viser starts
(:func:`check_viser_seam`: the call must be there) and after (the socket must be the one viser
serves); either failing is one line naming the viser version, with nothing left listening. The
front server relays each page's WebSocket to that socket (``unix_connect``).

viser prints a banner with its own address when it starts and a line when it stops; both are
silenced (:func:`quiet`): the address to open is the front's (:attr:`PageServers.url`),
printed by the command.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import shutil
import socket
import tempfile
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import viser
import websockets.asyncio.server as ws_server
from viser.infra import _infra

from ..errors import InputError
from .front import FrontServer
from .inputs import PageInputs

CONTROL_PERIOD = 0.02
"""Wall time [s] between two updates of a page's scene (50 Hz)."""
SLOW_PERIOD = 0.2
"""Wall time [s] between two updates of the trails, the table and the plots."""
MAX_SOCKET_PATH = 100
"""Longest Unix socket path [bytes] used (Linux allows 107, macOS 103)."""

_SEAM_LOCK = threading.Lock()  # one viser server starts at a time (the seam is process-wide)


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Standard output silenced (viser's banner and its stop line)."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


def free_port() -> int:
    """A TCP port free on loopback now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def quiet_library_logs() -> None:
    """The WebSocket library's own log (viser's server uses it; a page's malformed message,
    relayed, makes it log a traceback) goes nowhere: nothing a peer sends prints on the user's
    terminal (the front server counts its own, :attr:`FrontServer.problems`)."""
    library = logging.getLogger("websockets")
    library.propagate = False
    if not any(isinstance(h, logging.NullHandler) for h in library.handlers):
        library.addHandler(logging.NullHandler())


def _unsupported(what: str) -> InputError:
    return InputError(f"viser {viser.__version__} is not supported by omnikin view ({what}): install viser 1.1")


def check_viser_seam() -> None:
    """Raise :class:`InputError` in one line unless viser's server thread binds through
    ``websockets.asyncio.server.serve`` (module docstring), before anything listens."""
    if not hasattr(socket, "AF_UNIX"):
        raise InputError("omnikin view needs Unix sockets (Linux or macOS)")
    worker = getattr(getattr(_infra, "WebsockServer", None), "_background_worker", None)
    code = getattr(worker, "__code__", None)
    inner = [c for c in (code.co_consts if code else ()) if getattr(c, "co_name", "") == "start_server"]
    names = inner[0].co_names if inner else ()
    if not any(names[i : i + 4] == ("websockets", "asyncio", "server", "serve") for i in range(len(names))):
        raise _unsupported("its server does not bind through websockets.asyncio.server.serve")


def _bind_private_socket() -> tuple[socket.socket, Path]:
    """A listening Unix socket ``viser.sock`` in a new directory of mode 0700 (and the directory)."""
    base = tempfile.gettempdir()
    if len(os.fsencode(base)) > MAX_SOCKET_PATH - 30:
        base = "/tmp"  # a long TMPDIR would not fit a socket's path
    folder = Path(tempfile.mkdtemp(prefix="omnikin-view-", dir=base))  # mode 0700 (mkdtemp)
    path = folder / "viser.sock"
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        old = os.umask(0o177)
        try:
            sock.bind(str(path))  # 0600
        finally:
            os.umask(old)
        sock.listen(128)
    except OSError as e:
        sock.close()
        shutil.rmtree(folder, ignore_errors=True)
        raise InputError(f"cannot make the viewer's private socket in {folder} ({e.strerror})") from None
    return sock, folder


def start_viser(label: str = "omnikin") -> tuple[viser.ViserServer, Path]:
    """A viser server serving the Unix socket of a private directory (module docstring); the
    server and the directory (its socket: ``viser.sock``)."""
    check_viser_seam()
    sock, folder = _bind_private_socket()
    original = ws_server.serve
    served: list[bool] = []

    def serve(handler, *args, **options):
        if getattr(handler, "__qualname__", "") != "WebsockServer._background_worker.<locals>.ws_handler":
            return original(handler, *args, **options)  # anyone else's server: untouched
        served.append(True)
        return original(handler, unix=True, sock=sock, **options)  # websockets' unix_serve, on our socket

    try:
        with _SEAM_LOCK:
            ws_server.serve = serve  # type: ignore[assignment,misc]
            try:
                with quiet():
                    server = viser.ViserServer(host="127.0.0.1", port=0, label=label, verbose=False)
            finally:
                ws_server.serve = original  # type: ignore[misc]
        if not served:
            with quiet():
                server.stop()
            raise _unsupported("its server did not take the private socket")
    except BaseException:
        sock.close()
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return server, folder


class PageServers:
    """viser on a private Unix socket and the front server on ``host:port`` (0: a free port),
    key messages to ``on_key``, every other message of a page screened by :class:`PageInputs`;
    raises :class:`~omnikin.errors.InputError` in one line when the address cannot be served
    (nothing left running)."""

    def __init__(self, host: str, port: int, on_key: Callable[[dict], None]):
        quiet_library_logs()
        self.viser, self._folder = start_viser()
        try:
            self.inputs = PageInputs(self.viser)
            self.front = FrontServer(host, port, str(self._folder / "viser.sock"), on_key=on_key, inputs=self.inputs)
            self.front.start()
        except BaseException:
            self._stop_viser()
            raise

    @property
    def url(self) -> str:
        return self.front.url

    @property
    def socket_path(self) -> Path:
        """viser's Unix socket (in a directory of mode 0700)."""
        return self._folder / "viser.sock"

    def _stop_viser(self) -> None:
        with quiet():
            self.viser.stop()
        shutil.rmtree(self._folder, ignore_errors=True)

    def stop(self) -> None:
        self.front.stop()
        self._stop_viser()
