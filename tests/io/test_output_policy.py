"""The one output policy (omnikin.io.output): never an input, never a surprise, never half written."""

from __future__ import annotations

import contextlib
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from omnikin.errors import InputError, OutputError, OutputExistsError
from omnikin.io.output import (
    DATA_MARKER,
    REPORT_MARKER,
    Output,
    atomic_write,
    check_output,
    check_outputs,
    data_folder,
    report_folder,
)
from support.paths import omnikin_env


def test_new_file_is_accepted_and_existing_one_needs_force(tmp_path):
    out = tmp_path / "traj.csv"
    assert check_output(out) == out
    out.write_text("old")
    with pytest.raises(OutputExistsError, match="exists; pass --force"):
        check_output(out)
    assert check_output(out, force=True) == out


def test_an_input_is_never_an_output_even_with_force(tmp_path):
    log = tmp_path / "log.csv"
    log.write_text("t,a\n")
    with pytest.raises(OutputExistsError, match="input"):
        check_output(log, inputs=[log], force=True)
    link = tmp_path / "alias.csv"
    link.symlink_to(log)
    with pytest.raises(OutputExistsError, match="input"):
        check_output(link, inputs=[log], force=True)
    with pytest.raises(OutputExistsError, match="input"):  # same file by another spelling
        check_output(tmp_path / "sub" / ".." / "log.csv", inputs=[log], force=True)


def test_an_output_inside_an_input_folder_is_refused(tmp_path):
    bag = tmp_path / "run.bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("x")
    with pytest.raises(OutputExistsError, match="inside"):
        check_output(bag / "metadata.yaml", inputs=[bag], force=True)


def test_stdout_and_missing_folder(tmp_path):
    assert check_output("-") is None
    with pytest.raises(InputError, match="does not exist"):
        check_output(tmp_path / "nope" / "out.csv")


def test_atomic_write_leaves_the_old_file_on_failure(tmp_path):
    out = tmp_path / "a.txt"
    out.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_write(out) as handle:
            handle.write("new")
            raise RuntimeError("interrupted")
    assert out.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]  # no temporary left
    with atomic_write(out) as handle:
        handle.write("new")
    assert out.read_text() == "new"


def test_report_folder_is_replaced_as_a_whole_and_foreign_folders_refused(tmp_path):
    out = tmp_path / "report"
    check_output(out, folder=True)
    with report_folder(out) as stage:
        (stage / "first.txt").write_text("1")
    assert (out / REPORT_MARKER).is_file() and (out / "first.txt").is_file()
    check_output(out, folder=True)  # ours: may be replaced
    with report_folder(out) as stage:
        (stage / "second.txt").write_text("2")
    assert sorted(p.name for p in out.iterdir()) == sorted([REPORT_MARKER, "second.txt"])  # no mix
    with pytest.raises(RuntimeError):
        with report_folder(out) as stage:
            (stage / "third.txt").write_text("3")
            raise RuntimeError("interrupted")
    assert sorted(p.name for p in out.iterdir()) == sorted([REPORT_MARKER, "second.txt"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    for force in (False, True):
        with pytest.raises(OutputExistsError, match="did not write"):
            check_output(mine, folder=True, force=force)
    assert (mine / "thesis.tex").read_text() == "precious"


def test_new_files_get_the_usual_permissions(tmp_path):
    out = tmp_path / "p.txt"
    with atomic_write(out) as handle:
        handle.write("x")
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask


# --- data folders (ROS 2 bags): replaced only with force, and only if omnikin wrote them ---------------
def _write_data(out, name):
    """A writer that creates its folder itself (as rosbags does) inside omnikin.io.output.data_folder."""
    with data_folder(out) as target:
        assert not target.exists() and target.name == out.name and target.parent != out.parent
        target.mkdir()
        (target / name).write_text(name)


def test_data_folder_is_new_or_replaced_as_a_whole_with_force(tmp_path):
    out = tmp_path / "run.bag"
    assert check_output(out, folder="data") == out
    _write_data(out, "first.db3")
    assert sorted(p.name for p in out.iterdir()) == [DATA_MARKER, "first.db3"]
    with pytest.raises(OutputExistsError, match="pass --force"):
        check_output(out, folder="data")
    check_output(out, folder="data", force=True)
    _write_data(out, "second.db3")
    assert sorted(p.name for p in out.iterdir()) == [DATA_MARKER, "second.db3"]  # no mix of two runs
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.bag"]  # no staging left


def test_foreign_folders_and_files_are_never_data_outputs(tmp_path):
    foreign = tmp_path / "recorded.bag"
    foreign.mkdir()
    (foreign / "metadata.yaml").write_text("precious")
    empty = tmp_path / "empty"
    empty.mkdir()
    a_file = tmp_path / "notes.txt"
    a_file.write_text("precious")
    for path in (foreign, empty, a_file):
        for force in (False, True):
            with pytest.raises(OutputExistsError, match="did not write"):
                check_output(path, folder="data", force=force)
    assert (foreign / "metadata.yaml").read_text() == "precious" and a_file.read_text() == "precious"


def test_interrupted_data_folder_leaves_the_previous_one(tmp_path):
    out = tmp_path / "run.bag"
    _write_data(out, "first.db3")
    with pytest.raises(KeyboardInterrupt):
        with data_folder(out) as target:
            target.mkdir()
            (target / "half.db3").write_text("half")
            raise KeyboardInterrupt
    assert sorted(p.name for p in out.iterdir()) == [DATA_MARKER, "first.db3"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.bag"]


def test_a_data_folder_is_never_inside_an_input_folder(tmp_path):
    bag = tmp_path / "in.bag"
    bag.mkdir()
    with pytest.raises(OutputExistsError, match="input"):
        check_output(bag / "out.bag", inputs=[bag], folder="data", force=True)
    with pytest.raises(OutputExistsError, match="input"):  # nor one that contains an input
        check_output(tmp_path, inputs=[bag / "metadata.yaml"], folder="data", force=True)


# --- devices, failures ----------------------------------------------------------------------------------
def test_character_devices_are_written_in_place(tmp_path):
    """-o /dev/null needs no --force, and /dev/null stays a device (no rename over it)."""
    assert check_output("/dev/null") == Path("/dev/null")
    with atomic_write("/dev/null") as handle:
        handle.write("discarded")
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
def test_a_full_disk_is_an_output_error_naming_the_path():
    with pytest.raises(OutputError, match="^/dev/full: cannot write: No space left on device$"):
        with atomic_write("/dev/full") as handle:
            handle.write("x" * 100_000)


def test_missing_folder_is_named(tmp_path):
    with pytest.raises(InputError, match="cannot write: folder .*nope does not exist"):
        check_output(tmp_path / "nope" / "out.csv")
    with pytest.raises(InputError, match="does not exist"):
        check_output(tmp_path / "nope" / "out.bag", folder="data")


@contextlib.contextmanager
def _unwritable_folder(path: Path):
    """A folder nobody may write in, root included: mode 0555 for a normal user; for root
    (CI runs as root) the immutable attribute (``chattr +i``, e2fsprogs)."""
    path.mkdir()
    path.chmod(0o555)
    immutable = os.geteuid() == 0
    if immutable:
        subprocess.run(["chattr", "+i", str(path)], check=True, capture_output=True, timeout=30)
    try:
        yield path
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(path)], check=True, capture_output=True, timeout=30)
        path.chmod(0o755)


def test_read_only_folder_is_refused_before_writing(tmp_path):
    with _unwritable_folder(tmp_path / "ro") as ro:
        with pytest.raises(OutputError, match="not writable"):
            check_output(ro / "out.csv")
        with pytest.raises(OutputError, match="cannot write"):
            with atomic_write(ro / "out.csv") as handle:
                handle.write("x")
        assert list(ro.iterdir()) == []


def test_a_signal_during_a_critical_step_is_delivered_after_it(tmp_path):
    """Ctrl-C that arrives while a temporary file is created and recorded (or folders are
    swapped) waits for the step to end, then interrupts: nothing is left behind."""
    import signal

    from omnikin.io.output import _uninterrupted

    out = tmp_path / "a.txt"
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(out) as handle:
            with _uninterrupted():
                signal.raise_signal(signal.SIGINT)  # arrives inside the critical step ...
                handle.write("still running")  # ... which goes on to its end
            raise AssertionError("the deferred Ctrl-C should have been delivered here")
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


class _Stopped(Exception):
    """What the SIGTERM handler of these tests raises (as the command line's ``Terminated`` does)."""


@pytest.fixture
def own_handlers():
    """Python handlers for the three deferred signals (SIGINT: Ctrl-C's KeyboardInterrupt; SIGTERM:
    raises :class:`_Stopped`; SIGHUP: records), the process's own ones back after the test;
    yields the handlers and the list of SIGHUPs recorded."""
    import signal

    hups: list[int] = []

    def stopped(num, frame):
        raise _Stopped(num)

    def hung_up(num, frame):
        hups.append(num)

    mine = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: stopped, signal.SIGHUP: hung_up}
    saved = {sig: signal.signal(sig, handler) for sig, handler in mine.items()}
    try:
        yield mine, hups
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)


@pytest.mark.parametrize("moment", range(6))
@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_signal_while_the_handlers_are_swapped_acts_once_and_nothing_stays_swapped(
    own_handlers, monkeypatch, name, moment
):
    """The signal arrives just before the handlers are swapped in (moments 0-2) or back (3-5): it
    acts exactly once, as its own handler does (Ctrl-C: one KeyboardInterrupt), and every handler
    is its own again after the block. (A Ctrl-C raised while the handlers were put back once left
    SIGTERM and SIGHUP deferred for the rest of the process: a later ``kill`` did nothing.)"""
    import signal

    from omnikin.io import output

    mine, hups = own_handlers
    signum = getattr(signal, name)
    swap = signal.signal
    calls: list[int] = []

    def swap_late(sig, handler):  # the signal comes right before the swap number ``moment``
        if len(calls) == moment:
            calls.append(sig)
            signal.raise_signal(signum)  # Python runs the handler in place now: before the swap
        else:
            calls.append(sig)
        return swap(sig, handler)

    monkeypatch.setattr(signal, "signal", swap_late)
    raised = []
    try:
        with output._uninterrupted():
            pass
    except (KeyboardInterrupt, _Stopped) as exc:
        raised.append(type(exc))
    monkeypatch.undo()
    assert moment < len(calls), "the moment never came"
    assert raised == {"SIGINT": [KeyboardInterrupt], "SIGTERM": [_Stopped], "SIGHUP": []}[name]
    assert hups == ([signal.SIGHUP] if name == "SIGHUP" else [])
    assert {sig: signal.getsignal(sig) for sig in mine} == mine


def test_a_signal_not_handled_by_python_is_left_alone(own_handlers, monkeypatch):
    """A handler Python did not set (C code's: ``signal.getsignal`` says None) cannot be put back
    from Python: the block leaves that signal alone instead of restoring the default action
    after it (which turned the next Ctrl-C into death by SIGINT)."""
    import signal

    from omnikin.io import output

    getsignal = signal.getsignal
    monkeypatch.setattr(signal, "getsignal", lambda sig: None if sig == signal.SIGINT else getsignal(sig))
    swapped: list[int] = []
    swap = signal.signal
    monkeypatch.setattr(signal, "signal", lambda sig, handler: swapped.append(sig) or swap(sig, handler))
    with output._uninterrupted():
        pass
    monkeypatch.undo()
    assert signal.SIGINT not in swapped and signal.SIGTERM in swapped
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_signals_deferred_together_each_act_once_in_order(own_handlers):
    """SIGHUP then Ctrl-C inside the block: after it, the SIGHUP handler runs, then Ctrl-C
    interrupts; none is dropped for coming second."""
    import signal

    from omnikin.io import output

    _, hups = own_handlers
    with pytest.raises(KeyboardInterrupt):
        with output._uninterrupted():
            signal.raise_signal(signal.SIGHUP)
            signal.raise_signal(signal.SIGINT)
            signal.raise_signal(signal.SIGHUP)
            assert hups == []
    assert hups == [signal.SIGHUP]


# --- the outputs of one command, together -------------------------------------------------------------------
def test_two_outputs_on_one_path_are_refused_before_anything_is_written(tmp_path):
    """simulate --log x.csv --bag x.csv wrote a 13 MB bag and then failed: the outputs of a command
    are checked against each other, whatever their kinds and spellings."""
    log = tmp_path / "x.csv"
    cases = [
        [Output("--log", log), Output("--bag", log, "data")],
        [Output("--log", log), Output("--bag", tmp_path / "sub" / ".." / "x.csv", "data")],
        [Output("-o", log), Output("--plot", str(log))],
    ]
    for outputs in cases:
        with pytest.raises(InputError, match="are the same path"):
            check_outputs(outputs)
    assert list(tmp_path.iterdir()) == []


def test_an_output_inside_another_output_folder_is_refused(tmp_path):
    bag = tmp_path / "run.bag"
    for outputs in (
        [Output("--bag", bag, "data"), Output("--log", bag / "log.csv")],
        [Output("--log", bag / "deep" / "log.csv"), Output("--bag", bag, "data")],
        [Output("-o", tmp_path / "rep", "report"), Output("--bag", tmp_path / "rep" / "b.bag", "data")],
    ):
        with pytest.raises(InputError, match="lies inside"):
            check_outputs(outputs)


def test_at_most_one_thing_goes_to_standard_output():
    """--log - --json once wrote the CSV and the JSON document into one stream."""
    with pytest.raises(InputError, match="--log - and --json would both write to standard output"):
        check_outputs([Output("--log", "-")], stdout="--json")
    with pytest.raises(InputError, match="-o - and --log - would both"):
        check_outputs([Output("-o", "-"), Output("--log", "-")])
    assert check_outputs([Output("-o", "-"), Output("--plot", None)]) == [None]
    assert check_outputs([], stdout="--json") == []


def test_outputs_are_still_checked_one_by_one_against_the_inputs(tmp_path):
    log = tmp_path / "log.csv"
    log.write_text("t\n")
    with pytest.raises(OutputExistsError, match="input"):
        check_outputs([Output("-o", tmp_path / "new.csv"), Output("--log", log)], inputs=[log], force=True)
    with pytest.raises(OutputExistsError, match="exists; pass --force"):
        check_outputs([Output("--log", log)])


@pytest.mark.parametrize("name", ["newdir/", "newdir//", ".", "..", "sub/.", "sub/.."])
def test_a_file_output_never_names_a_folder(tmp_path, name, monkeypatch):
    """-o newdir/ wrote a regular file 'newdir'."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    with pytest.raises(InputError, match="names a folder"):
        check_output(name)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sub"]


def test_a_folder_output_may_end_with_a_separator(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert check_output("report/", folder="report") == Path("report")
    assert check_output("run.bag/", folder="data") == Path("run.bag")


@pytest.mark.parametrize("kind", ["report", "data"])
def test_the_current_folder_or_one_holding_it_is_never_a_folder_output(tmp_path, monkeypatch, kind):
    """'cd report && omnikin umbmark -o .' failed with 'Device or resource busy' and left an
    empty '..xxxx.old' folder in the report."""
    rep = tmp_path / "rep"
    rep.mkdir()
    (rep / (REPORT_MARKER if kind == "report" else DATA_MARKER)).write_text("")
    (rep / "inner").mkdir()
    monkeypatch.chdir(rep / "inner")
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    for name in ("..", "../", str(rep), "../../rep", "."):
        with pytest.raises(OutputExistsError, match="current folder"):
            check_output(name, folder=kind, force=True)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before


def test_a_folder_that_cannot_be_moved_aside_leaves_nothing_behind(tmp_path, monkeypatch):
    """The swap of a report into '.' (the current folder cannot be renamed) fails as an
    OutputError and leaves neither its staging folder nor an empty '.old' folder."""
    rep = tmp_path / "rep"
    rep.mkdir()
    (rep / REPORT_MARKER).write_text("")
    monkeypatch.chdir(rep)
    with pytest.raises(OutputError, match="cannot write"):
        with report_folder(".") as stage:  # the library call, without check_output
            (stage / "a.txt").write_text("a")
    assert sorted(p.name for p in rep.iterdir()) == [REPORT_MARKER]


def test_data_to_standard_output_is_utf8_whatever_its_encoding(tmp_path):
    """'-' carries the bytes a file would hold (UTF-8), even when standard output is ASCII."""
    script = "from omnikin.io.output import write_text; write_text('-', 'caf\\u00e9\\n')"
    env = dict(omnikin_env(), PYTHONIOENCODING="ascii")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "café\n".encode()


def test_data_to_a_closed_standard_output_is_an_output_error():
    script = (
        "from omnikin.io.output import write_text\n"
        "from omnikin.errors import OutputError\n"
        "try:\n    write_text('-', 'x')\nexcept OutputError as exc:\n    raise SystemExit(str(exc))\n"
    )
    proc = subprocess.run(
        ["sh", "-c", f"'{sys.executable}' -c \"$0\" >&-", script], capture_output=True, env=omnikin_env(), timeout=120
    )
    assert (proc.returncode, proc.stderr) == (1, b"standard output: cannot write: it is closed\n")
