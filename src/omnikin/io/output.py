"""One policy for every file and folder omnikin writes.

* **Never an input.** An output that is one of the command's inputs, or lies inside an
  input folder (a bag), is refused, ``--force`` or not.
* **Never a surprise.** An existing file the user did not ask to replace is refused unless
  ``force``; a report folder omnikin wrote itself (it carries :data:`REPORT_MARKER`) is
  replaced as a whole, so the same command runs twice; a data folder omnikin wrote (a ROS 2
  bag; it carries :data:`DATA_MARKER`) is replaced as a whole only with ``force``; any other
  existing folder is refused, ``force`` or not (omnikin never deletes a folder it did not
  write). An existing character device or pipe (``/dev/null``, a named pipe) is written in
  place: there is no file to lose.
* **Never half written.** Files are written to a temporary file in the same folder and
  renamed over the target (:func:`atomic_write`); a report folder is built beside the
  target and swapped in when complete (:func:`report_folder`), so an interrupted run leaves
  the previous output as it was and a folder never mixes files of two runs; a data folder is
  written beside the target by its writer and swapped in the same way (:func:`data_folder`).
* **Failures name the path.** An operating-system error while writing (disk full, read-only
  folder, no permission) is an :class:`omnikin.errors.OutputError` naming the path, in one
  line.
* ``-`` (:data:`STDOUT`) names standard output: it then carries the data only; messages go
  to standard error (the caller's job: :func:`is_stdout`).

Every refusal is an :class:`omnikin.errors.OutputExistsError` with a one-line message
naming the path and the way out.

* **One output, one path.** The outputs of one command are checked together
  (:func:`check_outputs`): no two on the same path or one inside another, at most one on
  standard output.
* **Never the current folder.** A folder output is never the current folder or one holding
  it (it is replaced as a whole); a file output never names a folder (``out/``, ``.``).

The command line declares each command's outputs and calls :func:`check_outputs` on them
before the command runs (``omnikin.cli.common.add_output`` and ``check_command_outputs``); the
writers check again right before writing, so a library caller gets the same protection.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import stat
import tempfile
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any, NamedTuple

from ..errors import InputError, OutputError, OutputExistsError

STDOUT = "-"
"""The output name meaning standard output."""

REPORT_MARKER = ".omnikin-report"
"""File in every report folder omnikin writes: such a folder may be replaced as a whole."""

DATA_MARKER = ".omnikin-data"
"""File in every data folder omnikin writes (a ROS 2 bag): with ``force`` such a folder is
replaced as a whole."""

FOLDER_KINDS = ("report", "data")


def is_stdout(path) -> bool:
    return str(path) == STDOUT


def _resolved(path) -> Path:
    return Path(os.path.abspath(os.path.realpath(os.fspath(path))))


def _inside(child: Path, parent: Path) -> bool:
    return child == parent or parent in child.parents


def check_output(path, *, inputs: Iterable = (), force: bool = False, folder: bool | str = False) -> Path | None:
    """Check that ``path`` may be written; return it as a :class:`Path` (None for stdout).

    ``inputs``: the paths the command reads (files or folders; None entries and ``-`` are
    skipped). ``folder``: False for a file; ``"report"`` (or True) for a report folder,
    ``"data"`` for a data folder such as a ROS 2 bag (see the module docstring).
    Raises :class:`OutputExistsError`, :class:`InputError` for a missing parent folder, or
    :class:`OutputError` for a folder omnikin may not write in.
    """
    kind = "report" if folder is True else folder
    if kind and kind not in FOLDER_KINDS:
        raise ValueError(f"folder must be False, True or one of {FOLDER_KINDS}, got {folder!r}")
    if is_stdout(path):
        if kind:
            raise InputError("'-' (standard output) cannot receive a folder; name a folder")
        return None
    text = os.fspath(path)
    if text == "":
        raise InputError("empty output path; name a file (or '-' for standard output)")
    if not kind and _names_folder(text):
        raise InputError(f"{text}: names a folder (it ends with {os.sep!r} or is '.' or '..'); name a file")
    out = Path(text)
    target = _resolved(out)
    cwd = _cwd()
    if kind and cwd is not None and _inside(cwd, target):
        raise OutputExistsError(
            f"{out}: is the current folder or contains it; omnikin replaces a {kind} folder as a whole: "
            "name another folder, or run omnikin from outside it"
        )
    for item in inputs:
        if item is None or is_stdout(item):
            continue
        src = _resolved(item)
        if _inside(target, src) or (kind and _inside(src, target)):
            raise OutputExistsError(
                f"{out}: is (or is inside, or contains) the input {item}; write the output somewhere else"
            )
    parent = target.parent
    if not parent.is_dir():
        raise InputError(f"{out}: cannot write: folder {parent} does not exist")
    if not kind and _in_place(out):
        return out
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{out}: cannot write: folder {parent} is not writable")
    if kind == "report":
        if out.exists() and not out.is_dir():
            raise OutputExistsError(f"{out}: exists and is not a folder")
        if out.is_dir() and any(out.iterdir()) and not (out / REPORT_MARKER).is_file():
            raise OutputExistsError(
                f"{out}: a non-empty folder omnikin did not write; choose a new folder "
                "(omnikin replaces only report folders it wrote itself)"
            )
        return out
    if kind == "data":
        if out.exists() or out.is_symlink():
            if not (out.is_dir() and not out.is_symlink() and (out / DATA_MARKER).is_file()):
                raise OutputExistsError(
                    f"{out}: exists already and omnikin did not write it; choose a new name "
                    "(omnikin never replaces a file or folder it did not write)"
                )
            if not force:
                raise OutputExistsError(
                    f"{out}: exists already; pass --force to replace it (a folder omnikin wrote, replaced as a whole)"
                )
        return out
    if out.is_dir():
        raise OutputExistsError(f"{out}: is a folder; name a file")
    if out.exists() and not force:
        raise OutputExistsError(f"{out}: exists; pass --force to replace it")
    if out.exists() and not stat.S_ISREG(out.stat().st_mode):
        raise OutputExistsError(f"{out}: exists and is not a regular file; name a file")
    return out


def _names_folder(text: str) -> bool:
    """True for a path that can only name a folder: it ends with a separator (``out/``) or its
    last part is ``.`` or ``..``."""
    seps = (os.sep, os.altsep) if os.altsep else (os.sep,)
    return text.endswith(seps) or os.path.basename(text) in (".", "..")


def _cwd() -> Path | None:
    """The current folder, resolved (None if it was removed)."""
    try:
        return _resolved(os.getcwd())
    except OSError:
        return None


class Output(NamedTuple):
    """One output of a command for :func:`check_outputs`: ``label`` names it in messages (the
    option, ``--log``), ``path`` (None: not written; ``-``: standard output), ``folder`` as for
    :func:`check_output`."""

    label: str
    path: Any
    folder: bool | str = False


def check_outputs(
    outputs: Iterable[Output], *, inputs: Iterable = (), force: bool = False, stdout: str | None = None
) -> list[Path | None]:
    """Check every output of one command together, before any work; return their paths as
    :func:`check_output` does (None for ``-``), in order.

    Beyond :func:`check_output` of each (never an input, an existing one only with ``force``,
    ...): at most one thing goes to standard output (``stdout`` labels another use of it, such
    as ``--json``), and no two outputs are the same path or lie inside one another (a tick log
    written into the bag folder it sits beside, a file named as the bag). Raises
    :class:`InputError` (or the errors of :func:`check_output`) naming the outputs by label.
    """
    given = [o if isinstance(o, Output) else Output(*o) for o in outputs]
    given = [o for o in given if o.path is not None]
    inputs = list(inputs)
    to_stdout = [f"{o.label} -" for o in given if is_stdout(o.path) and not o.folder] + ([stdout] if stdout else [])
    if len(to_stdout) > 1:
        raise InputError(
            f"{' and '.join(to_stdout)} would both write to standard output; name a file for "
            f"{'one of them' if len(to_stdout) == 2 else 'all but one'}"
        )
    files = [(o, _resolved(o.path)) for o in given if not is_stdout(o.path) and os.fspath(o.path) != ""]
    for k, (a, pa) in enumerate(files):
        for b, pb in files[k + 1 :]:
            if pa == pb:
                raise InputError(
                    f"{a.label} {a.path} and {b.label} {b.path} are the same path; give each output its own name"
                )
            if _inside(pa, pb) or _inside(pb, pa):
                inner, outer = (a, b) if _inside(pa, pb) else (b, a)
                raise InputError(
                    f"{inner.label} {inner.path} lies inside {outer.label} {outer.path}; write it elsewhere"
                )
    return [check_output(o.path, inputs=inputs, force=force, folder=o.folder) for o in given]


def _in_place(path: Path) -> bool:
    """True for an existing character device or pipe (``/dev/null``): written in place."""
    try:
        mode = path.stat().st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


def _output_error(path, exc: OSError) -> OutputError:
    if isinstance(exc, OutputError):
        return exc
    return OutputError(f"{path}: cannot write: {exc.strerror or exc}")


@contextlib.contextmanager
def atomic_write(
    path, mode: str = "w", *, encoding: str | None = "utf-8", newline: str | None = None
) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success it is renamed over ``path``.

    On an exception (or an interrupt) the temporary file is removed and ``path`` is left as
    it was. ``mode`` is ``"w"`` (text) or ``"wb"`` (bytes). A character device or pipe
    (``/dev/null``) is written in place. An operating-system error while writing (disk
    full, no permission) becomes an :class:`OutputError` naming ``path``.
    """
    target = Path(os.fspath(path))
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write: mode must be 'w' or 'wb', got {mode!r}")

    def opened(fd_or_path) -> IO[Any]:
        return open(fd_or_path, "wb") if mode == "wb" else open(fd_or_path, "w", encoding=encoding, newline=newline)

    if _in_place(target):
        try:
            with opened(target) as handle:
                yield handle
        except OSError as exc:
            raise _output_error(path, exc) from None
        return
    tmp = None
    try:
        with _uninterrupted():  # a Ctrl-C here must not leave the temporary file behind
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent or ".")
        with opened(fd) as handle:
            yield handle
        with _uninterrupted():
            _keep_mode(target, tmp)
            os.replace(tmp, target)
            tmp = None
    except BaseException as exc:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        if isinstance(exc, OSError):
            raise _output_error(path, exc) from None
        raise


def write_text(path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8), or to standard output for ``-`` (UTF-8 too,
    whatever the encoding of standard output: the same bytes as the file would hold)."""
    if is_stdout(path):
        import sys

        stream = sys.stdout
        if stream is None:  # the process was started without one (>&-)
            raise OutputError("standard output: cannot write: it is closed")
        binary = getattr(stream, "buffer", None)
        stream.flush()
        if binary is None:  # a text-only stream (a test's capture): it takes text
            stream.write(text)
            stream.flush()
            return
        binary.write(text.encode("utf-8"))
        binary.flush()
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
    stage = None
    try:
        with _uninterrupted():
            stage = _stage(target)
        yield stage
        _finish(stage, target, REPORT_MARKER, "written by omnikin; the folder is replaced as a whole on the next run\n")
    except BaseException as exc:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        if isinstance(exc, OSError):
            raise _output_error(path, exc) from None
        raise


@contextlib.contextmanager
def data_folder(path) -> Iterator[Path]:
    """Write a data folder (a ROS 2 bag) whose writer creates the folder itself: yields a path
    that does not exist yet, in a staging folder beside ``path``, with the same name; on
    success the folder written there is marked (:data:`DATA_MARKER`) and swapped in for
    ``path`` (a data folder omnikin wrote there before is removed as a whole). On an
    exception nothing is left behind and ``path`` stays as it was. Call :func:`check_output`
    with ``folder="data"`` first.
    """
    target = Path(os.fspath(path))
    holder = None
    try:
        with _uninterrupted():
            holder = _stage(target)
        yield holder / target.name
        _finish(
            holder / target.name,
            target,
            DATA_MARKER,
            "written by omnikin; with --force the folder is replaced as a whole\n",
        )
    except BaseException as exc:
        if isinstance(exc, OSError):
            raise _output_error(path, exc) from None
        raise
    finally:
        if holder is not None:
            shutil.rmtree(holder, ignore_errors=True)


def _stage(target: Path) -> Path:
    """A new empty folder beside ``target`` (same file system, so that renames are atomic)."""
    parent = target.parent if str(target.parent) else Path(".")
    try:
        return Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent))
    except OSError as exc:
        raise _output_error(target, exc) from None


def _finish(built: Path, target: Path, marker: str, note: str) -> None:
    """Mark the folder ``built`` and swap it in for ``target`` (an older one removed as a whole);
    Ctrl-C waits until the swap is complete."""
    with _uninterrupted():
        _swap(built, target, marker, note)


def _swap(built: Path, target: Path, marker: str, note: str) -> None:
    (built / marker).write_text(note, encoding="utf-8")
    os.chmod(built, 0o777 & ~_umask())
    parent = target.parent if str(target.parent) else Path(".")
    old = None
    if target.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=parent))
        try:
            os.replace(target, old / "previous")
        except BaseException:  # the folder cannot move (busy, no permission): leave nothing behind
            old.rmdir()
            raise
    try:
        os.replace(built, target)
    except BaseException:
        if old is not None:  # put the previous folder back
            os.replace(old / "previous", target)
            old.rmdir()
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


_DEFERRED = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
"""Signals :func:`_uninterrupted` defers."""


@contextlib.contextmanager
def _uninterrupted() -> Iterator[None]:
    """Defer Ctrl-C (SIGINT), SIGTERM and SIGHUP over a few file-system steps that must not be cut in
    the middle (creating a temporary and recording its name, swapping folders); the signals
    received are delivered right after, in order, each to the handler that was there before (a
    Python handler is called: Ctrl-C raises :class:`KeyboardInterrupt`, which ends the delivery;
    with the default action the process ends as it would have). Outside the main thread (where
    handlers cannot be set) it does nothing.

    Neither a deferred signal nor one that arrives while the handlers are swapped is lost or
    changes its meaning: a signal whose handler is not Python's (set by C code: it could not be
    put back) or ignored is left alone; the handlers are recorded before they are swapped, so
    that an exception raised by a pending signal while swapping leaves nothing swapped for good;
    and a deferring handler still installed once the block is over (an exception while the
    handlers are put back) passes its signal on to the previous handler instead of holding it.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []
    previous: dict[int, Any] = {}
    deferring = True

    def defer(num, frame):
        if deferring:
            received.append(num)
        else:  # the block is over but this handler is not replaced yet
            _deliver(num, previous[num], frame)

    try:
        for sig in _DEFERRED:
            handler = signal.getsignal(sig)
            if handler is None or handler == signal.SIG_IGN:
                continue
            previous[sig] = handler  # before the swap: an exception inside it is undone below
            signal.signal(sig, defer)
        yield
    finally:
        try:
            _restore(previous)
        finally:
            deferring = False
            for num in dict.fromkeys(received):  # each signal once, in the order they came
                _deliver(num, previous[num], None)


def _restore(previous: dict[int, Any]) -> None:
    """Put the handlers ``previous`` back, all of them even if a signal pending meanwhile raises
    (``signal.signal`` runs the handlers of pending signals before it swaps); then raise the
    first such exception."""
    error: BaseException | None = None
    for sig, handler in previous.items():
        while True:
            try:
                signal.signal(sig, handler)
                break
            except BaseException as exc:  # noqa: BLE001 (a signal's handler raised: after the rest)
                error = error or exc
    if error is not None:
        raise error


def _deliver(num: int, handler, frame) -> None:
    """Act on signal ``num`` as ``handler`` (the one :func:`_uninterrupted` deferred it from) would
    have: call a Python handler; for the default action, put it back and raise the signal."""
    if callable(handler):
        handler(num, frame)
    elif handler == signal.SIG_DFL:
        signal.signal(num, signal.SIG_DFL)
        signal.raise_signal(num)


def _umask() -> int:
    """The process umask (read by setting and restoring it)."""
    umask = os.umask(0)
    os.umask(umask)
    return umask
