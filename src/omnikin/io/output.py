"""One policy for every file and folder omnikin writes.

* **Never an input.** An output that is one of the command's inputs, or lies inside an
  input folder (a bag), is refused, ``--force`` or not.
* **Never a surprise.** An existing file the user did not ask to replace is refused unless
  ``force``; a report folder omnikin wrote itself (it carries :data:`REPORT_MARKER`) is
  replaced as a whole, so the same command runs twice; any other non-empty folder is
  refused, ``force`` or not (omnikin never deletes a folder it did not write).
* **Never half written.** Files are written to a temporary file in the same folder and
  renamed over the target (:func:`atomic_write`); a report folder is built beside the
  target and swapped in when complete (:func:`report_folder`), so an interrupted run leaves
  the previous output as it was and a folder never mixes files of two runs.
* ``-`` (:data:`STDOUT`) names standard output: it then carries the data only; messages go
  to standard error (the caller's job: :func:`is_stdout`).

Every refusal is an :class:`omnikin.errors.OutputExistsError` with a one-line message
naming the path and the way out.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from ..errors import InputError, OutputExistsError

STDOUT = "-"
"""The output name meaning standard output."""

REPORT_MARKER = ".omnikin-report"
"""File in every report folder omnikin writes: such a folder may be replaced as a whole."""


def is_stdout(path) -> bool:
    return str(path) == STDOUT


def _resolved(path) -> Path:
    return Path(os.path.abspath(os.path.realpath(os.fspath(path))))


def _inside(child: Path, parent: Path) -> bool:
    return child == parent or parent in child.parents


def check_output(path, *, inputs: Iterable = (), force: bool = False, folder: bool = False) -> Path | None:
    """Check that ``path`` may be written; return it as a :class:`Path` (None for stdout).

    ``inputs``: the paths the command reads (files or folders; None entries and ``-`` are
    skipped). ``folder``: the output is a folder (see the module docstring), else a file.
    Raises :class:`OutputExistsError` (or :class:`InputError` for a missing parent folder).
    """
    if is_stdout(path):
        if folder:
            raise InputError("'-' (standard output) cannot receive a folder; name a folder")
        return None
    out = Path(os.fspath(path))
    if str(out) == "":
        raise InputError("empty output path")
    target = _resolved(out)
    for item in inputs:
        if item is None or is_stdout(item):
            continue
        src = _resolved(item)
        if _inside(target, src) or (folder and _inside(src, target)):
            raise OutputExistsError(f"{out}: is (or is inside, or contains) the input {item}; "
                                    "write the output somewhere else")
    parent = target.parent
    if not parent.is_dir():
        raise InputError(f"{out}: folder {parent} does not exist")
    if folder:
        if out.exists() and not out.is_dir():
            raise OutputExistsError(f"{out}: exists and is not a folder")
        if out.is_dir() and any(out.iterdir()) and not (out / REPORT_MARKER).is_file():
            raise OutputExistsError(f"{out}: a non-empty folder omnikin did not write; choose a new folder "
                                    "(omnikin replaces only report folders it wrote itself)")
        return out
    if out.is_dir():
        raise OutputExistsError(f"{out}: is a folder; name a file")
    if out.exists() and not force:
        raise OutputExistsError(f"{out}: exists; pass --force to replace it")
    return out


@contextlib.contextmanager
def atomic_write(path, mode: str = "w", *, encoding: str | None = "utf-8",
                 newline: str | None = None) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success it is renamed over ``path``.

    On an exception (or an interrupt) the temporary file is removed and ``path`` is left as
    it was. ``mode`` is ``"w"`` (text) or ``"wb"`` (bytes).
    """
    target = Path(os.fspath(path))
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write: mode must be 'w' or 'wb', got {mode!r}")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent or ".")
    try:
        handle: IO[Any] = (os.fdopen(fd, "wb") if mode == "wb"
                           else os.fdopen(fd, "w", encoding=encoding, newline=newline))
        with handle:
            yield handle
        _keep_mode(target, tmp)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_text(path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8), or to standard output for ``-``."""
    if is_stdout(path):
        import sys

        sys.stdout.write(text)
        sys.stdout.flush()
        return
    with atomic_write(path) as handle:
        handle.write(text)


def _keep_mode(target: Path, tmp: str) -> None:
    """Give the new file the permissions a plain ``open(target, 'w')`` would have."""
    if target.exists():
        shutil.copymode(target, tmp)
        return
    os.chmod(tmp, 0o666 & ~_umask())


@contextlib.contextmanager
def report_folder(path) -> Iterator[Path]:
    """Build a report folder: yields an empty staging folder beside ``path``; on success it
    is marked (:data:`REPORT_MARKER`) and swapped in for ``path`` (an older report there is
    removed as a whole). On an exception the staging folder is removed and ``path`` is left
    as it was. Call :func:`check_output` with ``folder=True`` first.
    """
    target = Path(os.fspath(path))
    parent = target.parent if str(target.parent) else Path(".")
    stage = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent))
    try:
        yield stage
        (stage / REPORT_MARKER).write_text("written by omnikin; the folder is replaced as a whole on the next run\n",
                                           encoding="utf-8")
        os.chmod(stage, 0o777 & ~_umask())
        old = None
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=parent))
            os.replace(target, old / "report")
        os.replace(stage, target)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise


def _umask() -> int:
    """The process umask (read by setting and restoring it)."""
    umask = os.umask(0)
    os.umask(umask)
    return umask
