"""The one output policy (omnikin.io.output): never an input, never a surprise, never half written."""

from __future__ import annotations

import os

import pytest

from omnikin.errors import InputError, OutputExistsError
from omnikin.io.output import REPORT_MARKER, atomic_write, check_output, report_folder


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
    with pytest.raises(OutputExistsError, match="input"):       # same file by another spelling
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
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]      # no temporary left
    with atomic_write(out) as handle:
        handle.write("new")
    assert out.read_text() == "new"


def test_report_folder_is_replaced_as_a_whole_and_foreign_folders_refused(tmp_path):
    out = tmp_path / "report"
    check_output(out, folder=True)
    with report_folder(out) as stage:
        (stage / "first.txt").write_text("1")
    assert (out / REPORT_MARKER).is_file() and (out / "first.txt").is_file()
    check_output(out, folder=True)                                         # ours: may be replaced
    with report_folder(out) as stage:
        (stage / "second.txt").write_text("2")
    assert sorted(p.name for p in out.iterdir()) == sorted([REPORT_MARKER, "second.txt"])   # no mix
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
