"""The two servers behind a viewer page: viser's, on loopback only, and the front server on the
user's address (:mod:`omnikin.viewer.front`), started and stopped together.

viser prints a banner with its own (loopback) address when it starts and a line when it stops;
both are silenced (:func:`quiet`): the address to open is the front's (:attr:`PageServers.url`),
printed by the command.
"""

from __future__ import annotations

import contextlib
import io
import logging
import socket
from collections.abc import Callable, Iterator

import viser

from .front import FrontServer

CONTROL_PERIOD = 0.02
"""Wall time [s] between two updates of a page's scene (50 Hz)."""
SLOW_PERIOD = 0.2
"""Wall time [s] between two updates of the trails, the table and the plots."""


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
    """The WebSocket library's own log (viser's server on loopback uses it; a page's malformed
    message, relayed, makes it log a traceback) goes nowhere: nothing a peer sends prints on the
    user's terminal (the front server counts its own, :attr:`FrontServer.problems`)."""
    library = logging.getLogger("websockets")
    library.propagate = False
    if not any(isinstance(h, logging.NullHandler) for h in library.handlers):
        library.addHandler(logging.NullHandler())


class PageServers:
    """viser on ``127.0.0.1`` and the front server on ``host:port`` (0: a free port), key messages
    to ``on_key``; raises :class:`~omnikin.errors.InputError` in one line when the address
    cannot be served (nothing left running)."""

    def __init__(self, host: str, port: int, on_key: Callable[[dict], None]):
        quiet_library_logs()
        with quiet():
            self.viser = viser.ViserServer(host="127.0.0.1", port=free_port(), label="omnikin", verbose=False)
        try:
            self.front = FrontServer(host, port, self.viser.get_port(), on_key=on_key)
            self.front.start()
        except BaseException:
            with quiet():
                self.viser.stop()
            raise

    @property
    def url(self) -> str:
        return self.front.url

    def stop(self) -> None:
        self.front.stop()
        with quiet():
            self.viser.stop()
