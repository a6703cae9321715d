"""Opening input files so that a hostile path cannot hang the reader or fill the memory.

* :func:`read_text` reads a small text file whole (robot files, ROS parameter files): it
  must be a *regular* file (a FIFO would block the open, ``/dev/zero`` never ends, a
  directory is no file) of at most ``max_bytes``; the size is checked before anything is
  read, so a 2 GB file costs nothing. NUL bytes mark a binary file.
* :func:`read_lines` reads a data file line by line (tick logs, measurement files,
  trajectories): a regular file or a pipe (``<(zcat log.csv.gz)`` gives ``/dev/fd/63``);
  devices, sockets and directories are refused. A FIFO is opened without blocking and read
  once its writer has sent data or closed it; a named pipe nobody writes to is an error after
  :data:`PIPE_WAIT_S` instead of a hang.

Both decode UTF-8 (a byte-order mark is dropped) and raise the caller's error class with
a one-line message that names the file.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from pathlib import Path

MAX_CONFIG_BYTES = 1 << 18
"""Largest robot or parameter file read [bytes], 256 KiB: the largest preset is under 2 KB and a
robot of two thousand wheels written one per line still fits, while PyYAML's pure-Python reader
parses about 0.3 MiB/s, so no file can keep it busy for more than about a second."""

MAX_LINE_BYTES = 1 << 20
"""Longest line of a data file [bytes]: a tick log of 20 000 wheels has lines of about 240 KB; a
file without line breaks cannot make the reader hold more than this."""


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a pipe (FIFO)"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


PIPE_WAIT_S = 30.0
"""How long a pipe may stay silent before its first data or end [s]: a named pipe nobody writes to
is an error after this, not a hang."""


def _wait_for_writer(fd: int, source: str, error: type[Exception]) -> None:
    """Wait until a pipe has data or its writer closed it (at most :data:`PIPE_WAIT_S`)."""
    import select

    if not hasattr(select, "poll"):
        return
    poller = select.poll()
    poller.register(fd, select.POLLIN | select.POLLHUP)
    if not poller.poll(PIPE_WAIT_S * 1000):
        raise error(f"{source}: a pipe nobody wrote to within {PIPE_WAIT_S:g} s")


def _open_fd(path, error: type[Exception], what: str, *, allow_pipe: bool) -> tuple[int, os.stat_result]:
    """A file descriptor of ``path`` opened for reading, after checking what kind of file it is."""
    if not isinstance(path, (str, bytes, os.PathLike)):  # else os.open's TypeError
        from ..common.messages import shorten

        raise error(f"{shorten(path)}: not a path to {what} (give a str or os.PathLike)")
    source = str(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise error(f"{source}: no such file") from None
    except IsADirectoryError:
        raise error(f"{source}: is a directory, not {what}") from None
    except OSError as exc:
        raise error(f"{source}: cannot open: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        regular = stat.S_ISREG(info.st_mode)
        if not (regular or (allow_pipe and stat.S_ISFIFO(info.st_mode))):
            raise error(f"{source}: is {_kind(info.st_mode)}, not {what}")
        if not regular:
            _wait_for_writer(fd, source, error)
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)  # opened non-blocking only so that a FIFO cannot hang the open
    except BaseException:
        os.close(fd)
        raise
    return fd, info


def read_text(
    path: str | Path, error: type[Exception], *, what: str = "a text file", max_bytes: int = MAX_CONFIG_BYTES
) -> str:
    """The whole text of a small regular UTF-8 file (module docstring); ``what`` names the
    expected kind in messages (``"a robot file"``)."""
    source = str(path)
    fd, info = _open_fd(path, error, what, allow_pipe=False)
    limit = f"{what} may hold at most {max_bytes} bytes"
    with open(fd, "rb", closefd=True) as handle:
        if info.st_size > max_bytes:
            raise error(f"{source}: {info.st_size} bytes is too large: {limit}")
        try:
            data = handle.read(max_bytes + 1)
        except OSError as exc:
            raise error(f"{source}: cannot read: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise error(f"{source}: too large (grew while read): {limit}")
    nul = data.find(b"\0")
    if nul >= 0:
        raise error(f"{source}: binary data (NUL byte at offset {nul}), not {what}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{source}: not a UTF-8 text file (byte {exc.start}: {exc.reason})") from None


def read_lines(
    path: str | Path, error: type[Exception], *, what: str = "a text file", max_line_bytes: int = MAX_LINE_BYTES
) -> Iterator[tuple[int, str]]:
    """``(line_number, text)`` of each line of a UTF-8 regular file or pipe (module docstring),
    line endings kept; a line longer than ``max_line_bytes`` or not UTF-8 is an error naming it."""
    source = str(path)
    fd, _ = _open_fd(path, error, what, allow_pipe=True)
    with open(fd, "rb", closefd=True) as handle:
        number = 0
        while True:
            try:
                raw = handle.readline(max_line_bytes + 1)
            except OSError as exc:
                raise error(f"{source}: cannot read: {exc.strerror or exc}") from None
            if not raw:
                return
            number += 1
            if len(raw) > max_line_bytes:
                raise error(f"{source}: line {number}: longer than {max_line_bytes} bytes")
            try:
                text = raw.decode("utf-8-sig" if number == 1 else "utf-8")
            except UnicodeDecodeError as exc:
                raise error(
                    f"{source}: line {number}: not UTF-8 text (byte {exc.start + 1} of the line: {exc.reason})"
                ) from None
            yield number, text
