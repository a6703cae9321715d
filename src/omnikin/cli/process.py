"""The process around a command: signals, standard streams, warnings, one-line errors and
exit statuses (:func:`run`, which :func:`omnikin.cli.main.main` calls with the parser).

Errors end with one line ``omnikin: error: ...`` on stderr, never a traceback: exit status 2
for bad input or usage, 1 when something fails while running (an output cannot be written, a
hardware link fails, an unexpected error), 141 when a reader closes the pipe. Stopping is not
an error: a command that serves until the user stops it (:data:`SERVERS`: view, sim, ros) ends
on Ctrl-C, SIGTERM or SIGHUP with ``omnikin view: stopped (SIGTERM)`` and status 0; any other
command stopped before it finished says ``omnikin: interrupted`` (130, Ctrl-C) or ``omnikin:
terminated (SIGTERM)`` (143; 129 on SIGHUP), so that a script knows the work is not done.
Ctrl-C and a termination signal end a command the same way: every temporary file and staging
folder is removed, a previous output stays as it was.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import signal
import sys
import threading
import warnings
from collections.abc import Callable, Iterator

from ..common.messages import one_line
from ..errors import InfeasibleTwistError, InputError, OmnikinError, OutputError, Terminated, UsageError
from .common import running
from .parser import CommandParser

MESSAGE_LIMIT = 800
"""Longest error or warning line printed [characters]."""

WRITE_ERRORS = {
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EFBIG,
    errno.EIO,
    errno.EROFS,
    errno.EACCES,
    errno.EPERM,
    errno.EBADF,
    errno.EPIPE,
}
"""Operating-system errors that mean an output could not be written."""


# --- stopping a command -----------------------------------------------------------------------------------
def stop_name(exc: BaseException) -> str:
    """How the user stopped a command: ``Ctrl-C`` (:class:`KeyboardInterrupt`) or the signal's
    name (:class:`Terminated`: ``SIGTERM``, ``SIGHUP``)."""
    return signal.Signals(exc.signum).name if isinstance(exc, Terminated) else "Ctrl-C"


STOPPED: list[str] = []
"""How the running command was stopped inside :func:`until_stopped` (empty: it was not)."""


@contextlib.contextmanager
def until_stopped() -> Iterator[None]:
    """Run the block of a command that serves until the user stops it (a page, a window, a node:
    :data:`omnikin.cli.process.SERVERS`): Ctrl-C, SIGTERM or SIGHUP inside it end the block as a
    normal end, and the command goes on after it (writes its report); :func:`run` then prints
    ``omnikin COMMAND: stopped (SIGTERM)`` on standard error and the exit status is 0. Without
    this block a server stopped by the user ends the same way, with nothing done after."""
    try:
        yield
    except (KeyboardInterrupt, Terminated) as exc:
        STOPPED.append(stop_name(exc))


def run(argv: list[str] | None, build_parser: Callable[[], CommandParser]) -> int:
    """Parse ``argv`` (default ``sys.argv[1:]``) with the parser ``build_parser`` makes and run
    the command it names (its ``func``); returns the exit status.

    Every failure ends here as one line on stderr (:func:`_fail`), whatever raised it: usage
    and input errors (2), failures while running (1; writing an output: the one place an
    :class:`OutputError` becomes a status), a closed pipe (141, quiet),
    floating-point trouble in omnikin's own computations (2: an input out of range; NumPy's
    warnings are errors inside a command), anything unexpected (1, ``internal error``; set
    ``OMNIKIN_TRACEBACK=1`` to see where). Other libraries' warnings print as one line.
    Standard output and error may be closed or in an encoding without every character
    (:func:`_standard_streams`). Ctrl-C, SIGTERM and SIGHUP (:class:`Terminated`) are not
    failures: a server (:data:`SERVERS`) ends with status 0 (:func:`_stopped`), any other
    command with 130 or 128 + the signal (:func:`_ended`).
    """
    process = argv is None  # the process's own command line (the console script, python -m)
    argv = [str(a) for a in (sys.argv[1:] if argv is None else argv)]
    STOPPED.clear()
    with _standard_streams(), _termination_unwinds() as stops:
        stops.process = process
        try:
            status = _main(argv, stops, build_parser)
        finally:
            stops.over = True  # the status is settled: a stop now changes nothing
    forget_handled_interrupt()  # a Ctrl-C handled above must not still end the process by SIGINT
    return status


def _main(argv: list[str], stops: _Stops, build_parser: Callable[[], CommandParser]) -> int:
    # the command's name: parsed, or before that the first argument naming a server (a server
    # stopped while omnikin still starts is stopped all the same)
    command: list[str] = [argv[0]] if argv and argv[0] in SERVERS else []
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            warnings.filterwarnings("error", category=RuntimeWarning, module=r"omnikin(\.|$)")
            try:
                status = _run(argv, command, build_parser)
            except Exception:
                if stops.fired:  # a library turned the termination into an error of its own (matplotlib's
                    raise Terminated(stops.fired[0]) from None  # C code: 'initialization failed'): it is one
                raise
            if STOPPED and command and command[0] in SERVERS:  # stopped inside until_stopped()
                stops.end_quietly()
                _stopped(command[0], STOPPED[0])
            sys.stdout.flush()  # a full disk or a closed pipe shows here, not at exit
            return status
    except (KeyboardInterrupt, Terminated) as exc:
        stops.end_quietly()
        if command and command[0] in SERVERS:  # the user stops a server: its normal end
            return _stopped(command[0], stop_name(exc))
        if isinstance(exc, Terminated):
            return _ended(f"terminated ({stop_name(exc)})", 128 + exc.signum)
        return _ended(f"interrupted; {exc}" if str(exc) else "interrupted", 130)
    except UsageError as exc:
        return _fail(f"{exc.command + ': ' if exc.command else ''}{exc} (see {exc.help_hint})", 2)
    except OutputError as exc:  # the one place for write failures: the message names the path
        return _fail(exc, 1)
    except InfeasibleTwistError as exc:  # without the library's way out (a Python argument)
        return _fail(exc.detail, 2)
    except InputError as exc:
        return _fail(exc, 2)
    except OmnikinError as exc:  # LinkError: failures while running
        return _fail(exc, 1)
    except ImportError as exc:  # an optional extra is missing (the message names it)
        return _fail(exc, 2)
    except BrokenPipeError:  # the reader of standard output went away: stop quietly
        _quiet_stdout()
        return 141
    except (RuntimeWarning, FloatingPointError) as exc:
        return _fail(f"numerical failure ({exc}): an input is probably beyond the range omnikin computes with", 2)
    except MemoryError:
        return _fail("out of memory; lower the sizes of the job (see --max-memory of the command)", 1)
    except OSError as exc:  # not raised by omnikin's readers and writers: standard output
        _quiet_stdout()
        where = f"{exc.filename}" if exc.filename else "standard output"
        return _fail(
            f"{where}: cannot write: {exc.strerror or exc}"
            if exc.errno in WRITE_ERRORS
            else f"{where}: {exc.strerror or exc}",
            1,
        )
    except Exception as exc:  # noqa: BLE001 (the promise: no traceback reaches a user)
        if os.environ.get("OMNIKIN_TRACEBACK"):
            import traceback

            traceback.print_exc()
        return _fail(
            f"internal error: {type(exc).__name__}: {exc} (a bug in omnikin: please report it with the "
            f"command line; OMNIKIN_TRACEBACK=1 shows where)",
            1,
        )


def _run(argv: list[str], command: list[str], build_parser: Callable[[], CommandParser]) -> int:
    """Parse and run; the command's name is appended to ``command`` once known. Every command
    runs in :func:`~omnikin.cli.common.running` (its outputs checked together first)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help and --version print, then argparse exits
        return exc.code if isinstance(exc.code, int) else 0
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    command[:] = [args.command]
    with running(args):  # every output of the command checked together before any work
        return args.func(args)


def _fail(message, status: int) -> int:
    """Print ``omnikin: error: MESSAGE`` as one bounded line on stderr; return ``status``."""
    return _say(f"omnikin: error: {one_line(message, MESSAGE_LIMIT)}", status)


def _ended(message, status: int) -> int:
    """A command the user interrupted or terminated before it finished: ``omnikin: MESSAGE`` (not
    an error: the user asked for it; the status, 130 or 128 + the signal, tells a script that
    the work is not done); return ``status``."""
    return _say(f"omnikin: {one_line(message, MESSAGE_LIMIT)}", status)


def _stopped(command: str, how: str) -> int:
    """A server the user stopped (:data:`SERVERS`): ``omnikin COMMAND: stopped (HOW)``, status 0."""
    return _say(f"omnikin {command}: stopped ({how})", 0)


def _say(line: str, status: int) -> int:
    try:
        print(line, file=sys.stderr)
        sys.stderr.flush()
    except (OSError, ValueError):  # stderr itself is gone: nothing more to say
        pass
    return status


SERVERS = frozenset({"view", "sim", "ros"})
"""Commands that run until the user stops them (a page, a window, a ROS node): Ctrl-C, SIGTERM
or SIGHUP is their normal end, status 0 (:func:`_stopped`)."""


TERMINATION_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
"""Signals that end a command like Ctrl-C does (:class:`Terminated`): ``timeout``, ``kill``,
systemd, a closed terminal."""


class _Stops:
    """The stops a running command received (:func:`_termination_unwinds`)."""

    def __init__(self) -> None:
        self.fired: list[int] = []
        """The termination signals that raised :class:`Terminated`, in order."""
        self.over = False
        """The command's status is settled (set by :func:`run`): a stop now changes nothing."""
        self.reporting = False
        """A stop lost in a finaliser is being reported (:func:`_termination_unwinds`)."""
        self.process = False
        """The command line is the process's own (:func:`run` without ``argv``)."""
        self.ending = False
        """The command was stopped and the process is ending (:meth:`end_quietly`)."""

    def end_quietly(self) -> None:
        """The command was stopped (Ctrl-C, a termination signal) and its process is ending: a
        further stop would only cut that short (a second Ctrl-C while Python exits would kill it
        by SIGINT after 'omnikin: interrupted' was printed: status -2 to its parent, not 130), so
        Ctrl-C and the termination signals are ignored to the end of the process. Only for the
        process's own command line (:attr:`process`) and in the main thread: a program calling
        :func:`omnikin.cli.main.main` with arguments keeps its handlers."""
        self.ending = True
        if not self.process or threading.current_thread() is not threading.main_thread():
            return
        for sig in (signal.SIGINT, *TERMINATION_SIGNALS):
            if signal.getsignal(sig) is None:  # set outside Python: left alone
                continue
            while True:
                try:
                    signal.signal(sig, signal.SIG_IGN)
                    break
                except (KeyboardInterrupt, Terminated):  # one pending meanwhile: ending all the same
                    continue


@contextlib.contextmanager
def _termination_unwinds() -> Iterator[_Stops]:
    """Turn a termination signal into :class:`Terminated` while a command runs. Once one unwinds
    the command, later ones are ignored to the end of the process (the cleanup it started must
    finish, and the process is ending); one that comes while none is unwinding raises again.
    Without a signal the previous handlers come back after. A signal the caller ignores
    (``nohup``) stays ignored, and a handler not set from Python (:func:`signal.getsignal` gives
    None) is left alone. Only in the main thread. Yields the :class:`_Stops` received, so that
    an error a library raised in place of the termination (it arrived inside its C code) is
    still reported as the termination.

    A stop is *unwinding* while a :class:`Terminated` is being handled (an ``except``,
    ``finally`` or ``__exit__`` on its way up, or code they call: :func:`_unwinding`); a server
    that ended on one (:data:`STOPPED`) writes its report on. A stop
    that lands in a finaliser (``__del__``, a weakref callback, a generator closed by the
    garbage collector: Python runs signal handlers there too) cannot leave it: Python reports it
    as "Exception ignored in ..." with a traceback and goes on. Such a stop, a Ctrl-C too, is
    reported quietly and sent again from outside the finaliser (:func:`_send_again`); a
    library that swallows every exception (``except BaseException: pass``) loses the first
    stop, and the next one stops the command (a first stop remembered for good would leave the
    command running to its end, deaf to every later SIGTERM)."""
    stops = _Stops()
    if threading.current_thread() is not threading.main_thread():
        yield stops
        return

    def unwind(signum, frame):
        if stops.reporting:  # inside the report of a lost stop: it acts once that is over
            _send_again(signum, stops)
            return
        if stops.over or stops.ending or (stops.fired and (STOPPED or _unwinding())):
            return  # the stop that came first unwinds the command, or a server ended on it
        stops.fired.append(signum)
        raise Terminated(signum)

    def lost(unraisable) -> None:  # sys.unraisablehook while the command runs
        exc = unraisable.exc_value
        if not isinstance(exc, (KeyboardInterrupt, Terminated)):
            previous_hook(unraisable)
            return
        stops.reporting = True
        try:
            _send_again(exc.signum if isinstance(exc, Terminated) else signal.SIGINT, stops)
        finally:
            stops.reporting = False

    previous = {}
    for sig in TERMINATION_SIGNALS:
        handler = signal.getsignal(sig)
        if handler is not signal.SIG_IGN and handler is not None:  # None: set outside Python, left alone
            previous[sig] = handler
            signal.signal(sig, unwind)
    previous_hook = sys.unraisablehook
    sys.unraisablehook = lost
    try:
        yield stops
    finally:
        stops.over = True
        for sig, handler in previous.items():
            signal.signal(sig, signal.SIG_IGN if stops.fired or (stops.ending and stops.process) else handler)
        sys.unraisablehook = previous_hook


def _unwinding() -> bool:
    """Whether a :class:`Terminated` is being handled where the signal's handler runs: the
    exception handled (:func:`sys.exc_info`, which sees the ``except``, ``finally`` and
    ``__exit__`` blocks of every caller) or one it was raised while handling."""
    exc = sys.exc_info()[1]
    for _ in range(1000):  # a cycle of contexts cannot hold the handler
        if exc is None:
            return False
        if isinstance(exc, Terminated):
            return True
        exc = exc.__context__
    return False


def _send_again(signum: int, stops: _Stops) -> None:
    """Send signal ``signum`` to this process again in a moment, from another thread (its handler
    then runs in the main thread wherever that is, outside the finaliser or report it was lost
    in), unless the command has ended or is ending on another stop by then."""

    def send() -> None:
        if not (stops.over or stops.ending):
            os.kill(os.getpid(), signum)

    timer = threading.Timer(0.01, send)
    timer.daemon = True
    timer.start()


class _ClosedStream(io.TextIOBase):
    """Stands for standard output when the process has none (started with ``>&-``): writing to it
    is an ``OSError`` (EBADF), which :func:`run` reports as one line with status 1."""

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        raise OSError(errno.EBADF, "it is closed")

    def isatty(self) -> bool:
        return False


@contextlib.contextmanager
def _standard_streams() -> Iterator[None]:
    """Standard output and error, usable whatever the process was given: a missing one (closed
    by the caller) is replaced (standard output by :class:`_ClosedStream`, standard error by
    the null device: nothing more can be said), and characters the stream's encoding lacks
    (``PYTHONIOENCODING=ascii``, a C locale) are written as backslash escapes instead of
    failing. Data written to ``-`` is UTF-8 whatever the encoding
    (:func:`omnikin.io.output.write_text`). Restored after the command."""
    saved = sys.stdout, sys.stderr
    errors = {}
    devnull = None
    if sys.stdout is None:
        sys.stdout = _ClosedStream()
    if sys.stderr is None:
        devnull = sys.stderr = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115 (closed below)
    for stream in (sys.stdout, sys.stderr):
        if isinstance(stream, io.TextIOWrapper) and stream.errors != "backslashreplace":
            errors[stream] = stream.errors
            with contextlib.suppress(OSError, ValueError):
                stream.reconfigure(errors="backslashreplace")
    try:
        yield
    finally:
        for stream, old in errors.items():
            with contextlib.suppress(OSError, ValueError):
                stream.reconfigure(errors=old)
        if devnull is not None:
            devnull.close()
        sys.stdout, sys.stderr = saved


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings of other libraries as one line (``warnings.showwarning`` during a command)."""
    try:
        print(f"omnikin: warning: {one_line(message, MESSAGE_LIMIT)}", file=sys.stderr)
    except (OSError, ValueError):
        pass


def _quiet_stdout() -> None:
    """After standard output failed (closed pipe, full disk), point it at /dev/null so that the
    interpreter's final flush does not print a second error."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # not a real file (a test's capture)
        return
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)
    except OSError:
        pass


def forget_handled_interrupt() -> None:
    """Make sure that a Ctrl-C the command handled does not end the process by SIGINT after all.

    CPython ends a process whose :class:`KeyboardInterrupt` nobody handled by killing it with
    SIGINT (bpo-1054041: so that a shell sees death by Ctrl-C), and it notes such an interrupt in a
    flag that is also set when a KeyboardInterrupt leaves code run from source text
    (``exec``/``eval`` of a string, C ``PyRun_String``), even if a caller handles it later. Under
    ``python -m omnikin`` (``Py_RunMain``) the flag is read after the interpreter finalized and
    the process dies by SIGINT whatever status it exited with: a Ctrl-C that came while rosbags
    compiled its generated serializers (``exec`` of a string) once turned ``omnikin: interrupted``
    (130) into death by SIGINT. Every evaluation of source text resets the flag when it starts:
    an empty one clears it. Call when the command's exit status is settled."""
    exec("", {})  # noqa: S102 (an empty program: nothing runs)
