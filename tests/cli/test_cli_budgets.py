"""Sizes the user controls are sized before the work: a hostile size is refused at once, in one
line naming the limit and the option, instead of a MemoryError traceback or an hour of swapping."""

from __future__ import annotations

import argparse
import math
import os
import re
from pathlib import Path

import pytest
import yaml

from omnikin.cli.budget import Budget, format_bytes, parse_duration, parse_size, require
from omnikin.cli.main import main
from omnikin.errors import ResourceLimitError
from support.cli import run_cli as cli

# The work a refusal must come before: each is replaced by a stand-in that fails the test if called.
WORK = (
    ("omnikin.simulation.kinematic", "simulate_kinematic"),
    ("omnikin.physics.run", "simulate_physics"),
    ("omnikin.io.bags", "record_run"),
    ("omnikin.api.umbmark", "umbmark_study"),  # the one study of both engines
)
BAG_READERS = (("omnikin.io.bags", "bag_odometry"), ("omnikin.io.bags", "export_poses"))
SAFETY_SECONDS = 120  # ends a hang (a pipe waited for, an endless device read); not a pace


def _never(module: str, name: str, ran: list):
    def stand_in(*args, **kwargs):
        ran.append(f"{module}.{name}")
        raise AssertionError(f"{module}.{name} ran before the refusal")

    return stand_in


def _hung(signum, frame):
    raise AssertionError(f"no answer within {SAFETY_SECONDS} s: the command hangs")


def refused_at_once(capsys, argv, *fragments, never=()):
    """Refused at once means before the work, whatever the pace of the machine: the simulation,
    the bag recorder and the UMBmark study (and the bag readers named in ``never``) fail the test
    if they start; a safety alarm turns a hang into a failure."""
    import importlib
    import signal

    ran: list[str] = []  # main() reports what it catches, so the stand-ins also say they ran here
    with pytest.MonkeyPatch.context() as mp:
        for module, name in WORK + tuple(never):
            mp.setattr(importlib.import_module(module), name, _never(module, name, ran))
        previous = signal.signal(signal.SIGALRM, _hung)
        signal.alarm(SAFETY_SECONDS)
        try:
            rc, out, err = cli(capsys, *argv)
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, previous)
    assert ran == [], f"the work started before the refusal: {ran}"
    assert rc == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: ") and len(lines[0]) < 400, err
    for f in fragments:
        assert f in lines[0], (f, err)
    return lines[0]


# --- the helpers -----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, value",
    [
        ("2G", 2 * 1024**3),
        ("1.5K", 1536),
        ("512M", 512 * 1024**2),
        ("100", 100),
        ("3GiB", 3 * 1024**3),
        ("1e3", 1000),
        ("4k", 4096),
        ("2g", 2 * 1024**3),
        ("1TiB", 1024**4),
        ("7B", 7),
    ],
)
def test_sizes(text, value):
    assert parse_size(text) == value


@pytest.mark.parametrize(
    "text, value", [("90", 90.0), ("10m", 600.0), ("10min", 600.0), ("2h", 7200.0), ("1.5s", 1.5), ("1d", 86400.0)]
)
def test_durations(text, value):
    assert parse_duration(text) == value


@pytest.mark.parametrize(
    "text, why",
    [
        (" 2G", "not a size"),
        ("2G\n", "not a size"),
        ("2G ", "not a size"),
        ("2 G", "not a size"),
        ("2\u3000G", "not a size"),
        ("\u00a02G", "not a size"),
        ("\u0661G", "not a size"),
        ("1_000", "not a size"),
        ("2Gb", "unknown unit 'Gb'"),
        ("2bb", "unknown unit 'bb'"),
        ("4kb", "unknown unit 'kb'"),
        ("2GB", "unknown unit 'GB'"),
        ("2Gi", "unknown unit 'Gi'"),
    ],
)
def test_a_size_is_a_plain_number_and_a_unit_of_the_table(text, why):
    """A size is a plain number (the grammar of every number omnikin reads) followed at once by a
    unit of one strict table: ' 2G', '2G\\n' and Unicode blanks are not 2 GiB, nor '2Gb'
    (gigabits elsewhere), nor '2bb' 2 bytes."""
    with pytest.raises(argparse.ArgumentTypeError, match=re.escape(why)) as info:
        parse_size(text)
    assert "powers of 1024" in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize(
    "text, why",
    [
        (" 90", "not a duration"),
        ("90\n", "not a duration"),
        ("1.5 s", "not a duration"),
        ("2H", "unknown unit 'H'"),
        ("3hours", "unknown unit 'hours'"),
    ],
)
def test_a_duration_is_a_plain_number_and_a_unit_of_the_table(text, why):
    with pytest.raises(argparse.ArgumentTypeError, match=re.escape(why)):
        parse_duration(text)


def test_the_help_names_the_units_of_sizes_and_durations(capsys):
    assert main(["simulate", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "K, M, G or T, powers of 1024 (also KiB, MiB, GiB, TiB)" in text
    assert "s, m (or min), h or d" in text


def test_a_blank_before_a_limit_is_a_usage_error_naming_the_option(capsys, tmp_path):
    refused_at_once(
        capsys, ["umbmark", "diff-drive", "--max-memory", " 2G", "-o", tmp_path / "r"], "argument --max-memory", "' 2G'"
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("text", ["", "G", "1Q", "-5M", "nan", "inf", "0", "1e400"])
def test_bad_sizes_are_refused(text):
    with pytest.raises(Exception, match="size"):
        parse_size(text)


def test_require_names_the_limit_and_the_way_out():
    with pytest.raises(
        ResourceLimitError,
        match=r"^job: about 3G of memory for 7 things, more than --max-memory "
        r"2G; do less, or raise --max-memory$",
    ) as info:
        require(Budget(), "job", memory=3 * 1024**3, size="7 things", hint="do less")
    assert info.value.needed == 3 * 1024**3 and info.value.limit == 2 * 1024**3 and info.value.unit == "bytes"
    with pytest.raises(ResourceLimitError, match="more than --max-time 90 s"):
        require(Budget(seconds=90), "job", seconds=91, hint="do less")
    require(Budget(seconds=90), "job", memory=1024, seconds=89, hint="do less")  # within: no error
    assert format_bytes(math.inf) == "inf"


# --- simulate ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "extra", [["--rate", "1e4", "--path", "line 1000"], ["--path", "line 1e5"], ["--path", "spin 5e6"]]
)
def test_hostile_simulation_sizes_are_refused_at_once(capsys, tmp_path, extra):
    pytest.importorskip("rosbags")
    bag = tmp_path / "x.bag"
    refused_at_once(capsys, ["simulate", "tomasi-omni3", *extra, "--bag", bag], "simulate", "--max-memory", "samples")
    assert not bag.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "path, why",
    [
        ("line 1e12", "length must be from 0 to 100000"),
        ("spin 1e15", "angle must lie in [-5729577.951, 5729577.951] deg, got 1e+15"),
    ],
)
def test_absurd_path_lengths_are_refused_by_the_plan(capsys, tmp_path, path, why):
    pytest.importorskip("rosbags")
    bag = tmp_path / "x.bag"
    refused_at_once(capsys, ["simulate", "tomasi-omni3", "--path", path, "--bag", bag], "--path", why)
    assert list(tmp_path.iterdir()) == []


def test_simulation_beyond_the_time_limit_is_refused(capsys, tmp_path):
    """640,000 samples of four messages each: far more than 1 s of writing on any machine."""
    pytest.importorskip("rosbags")
    refused_at_once(
        capsys,
        ["simulate", "tomasi-omni3", "--rate", "1e4", "--max-time", "1s", "--bag", tmp_path / "x.bag"],
        "--max-time 1 s",
        "lower --rate",
    )


def test_bad_limit_is_a_usage_error(capsys, tmp_path):
    refused_at_once(
        capsys,
        ["simulate", "tomasi-omni3", "--max-memory", "lots", "--bag", tmp_path / "x.bag"],
        "--max-memory",
        "'lots'",
    )


# --- bags --------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def joint_bag(tmp_path_factory):
    pytest.importorskip("rosbags")
    path = tmp_path_factory.mktemp("js") / "run.bag"
    assert main(["simulate", "tomasi-omni3", "--path", "spin 90", "--rate", "50", "--bag", str(path)]) == 0
    return path


def copy_with_declared_count(bag: Path, dest: Path, topic: str, count: int) -> Path:
    """A copy of ``bag`` whose metadata declares ``count`` messages on ``topic`` (a hostile or broken
    metadata.yaml; the messages are the same)."""
    import shutil

    shutil.copytree(bag, dest)
    meta = yaml.safe_load((dest / "metadata.yaml").read_text())
    info = meta["rosbag2_bagfile_information"]
    for entry in info["topics_with_message_count"]:
        if entry["topic_metadata"]["name"] == topic:
            entry["message_count"] = count
    (dest / "metadata.yaml").write_text(yaml.safe_dump(meta))
    return dest


def test_bag_declaring_a_trillion_messages_is_refused_before_reading(capsys, joint_bag, tmp_path):
    bag = copy_with_declared_count(joint_bag, tmp_path / "huge.bag", "/joint_states", 10**12)
    refused_at_once(
        capsys,
        ["bag", "odometry", "tomasi-omni3", bag, "-o", tmp_path / "o.bag"],
        "1000000000000",
        "--max-memory",
        never=BAG_READERS,
    )
    assert not (tmp_path / "o.bag").exists()
    refused_at_once(
        capsys,
        [
            "bag",
            "export",
            copy_with_declared_count(joint_bag, tmp_path / "h2.bag", "/odom", 10**12),
            "--topic",
            "/odom",
            "--format",
            "tum",
        ],
        "--max-memory",
        never=BAG_READERS,
    )


def test_bag_understating_its_messages_is_stopped_while_reading(capsys, joint_bag, tmp_path):
    """The metadata says one message; the limit (8K / 400 bytes = 20 messages) is enforced on the
    messages actually read."""
    bag = copy_with_declared_count(joint_bag, tmp_path / "liar.bag", "/joint_states", 1)
    line = refused_at_once(
        capsys,
        ["bag", "odometry", "tomasi-omni3", bag, "-o", tmp_path / "o.bag", "--max-memory", "8K"],
        "more than 20 messages",
        "--max-memory 8K",
    )
    assert "Traceback" not in line
    assert not (tmp_path / "o.bag").exists() and sorted(p.name for p in tmp_path.iterdir()) == ["liar.bag"]


# --- trajectory files ----------------------------------------------------------------------------------------
def test_trajectory_file_too_large_for_the_budget_is_refused(capsys, tmp_path):
    est = tmp_path / "est.csv"
    est.write_text("t,x,y,theta\n" + "".join(f"{k},0,0,0\n" for k in range(2000)))
    refused_at_once(capsys, ["metrics", est, est, "--max-memory", "64K"], str(est), "--max-memory 64K")
    rc, _, err = cli(capsys, "metrics", est, est, "--json")
    assert rc == 0, err


# --- inputs without a size or end ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        ["metrics", "/dev/zero", "/dev/zero"],
        ["show", "/dev/zero"],
        ["simulate", "diff-drive", "--true-robot", "/dev/zero", "--bag", "x.bag"],
        ["bag", "export", "/dev/zero", "--topic", "/odom", "--format", "tum"],
    ],
)
def test_endless_devices_are_refused_not_read(capsys, tmp_path, monkeypatch, argv):
    """/dev/zero has no size to check and no end: read, it would fill the memory."""
    if argv[0] in ("simulate", "bag"):
        pytest.importorskip("rosbags")
    monkeypatch.chdir(tmp_path)
    refused_at_once(capsys, argv, "/dev/zero")


def test_bag_that_is_or_holds_a_pipe_is_refused_not_waited_for(capsys, joint_bag, tmp_path):
    """A named pipe nobody writes to would block the bag reader's open() forever."""
    import shutil

    fifo = tmp_path / "run.mcap"
    os.mkfifo(fifo)
    refused_at_once(capsys, ["bag", "export", fifo, "--topic", "/odom", "--format", "tum"], "pipe")
    bag = tmp_path / "copy.bag"
    shutil.copytree(joint_bag, bag)
    os.mkfifo(bag / "extra.mcap")
    refused_at_once(capsys, ["bag", "odometry", "tomasi-omni3", bag, "-o", tmp_path / "o.bag"], "extra.mcap", "pipe")
