"""``omnikin track``: the summary of a figure-eight against the lemniscate's length, the TUM
outputs read back, the figure written, and one-line refusals (status 2) of bad paths, options and
outputs, before anything is driven or written."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from scipy.integrate import quad

from omnikin.io.trajectories import read_trajectory
from support.cli import run_cli, run_entry_point


def gerono_length(a: float) -> float:
    """Length of Gerono's lemniscate (a sin t, a sin 2t / 2): the integral of its speed."""
    return quad(lambda t: a * math.hypot(math.cos(t), math.cos(2 * t)), 0.0, 2 * math.pi, limit=200)[0]


def test_the_figure_eight_is_tracked_and_summarised(tmp_path, capsys):
    truth, reference, figure = tmp_path / "truth.tum", tmp_path / "ref.tum", tmp_path / "fig.svg"
    rc, out, err = run_cli(
        capsys, "track", "tomasi-omni3", "figure8 1", "--truth", truth, "--reference", reference, "--plot", figure,
        "--json",
    )  # fmt: skip
    assert rc == 0, err
    summary = json.loads(out)
    assert summary["path_length_m"] == pytest.approx(gerono_length(1.0), rel=1e-5)
    assert summary["max_wheel_speed_rad_s"] <= 12.0 * (1 + 1e-9)
    assert summary["max_error_m"] < 1e-4 and summary["rms_error_m"] <= summary["max_error_m"]
    assert summary["errors"] == "none" and summary["engine"] == "kinematic" and summary["step_s"] is None
    t, poses = read_trajectory(truth)
    assert t[0] == 0.0 and poses[0] == pytest.approx([0.0, 0.0, 0.0])
    assert np.diff(t) == pytest.approx(np.full(len(t) - 1, 1 / 50))
    assert len(t) == summary["samples"]
    t_ref, ref = read_trajectory(reference)
    assert np.array_equal(t_ref, t)
    assert ref[-1, :2] == pytest.approx([0.0, 0.0], abs=1e-9)  # the figure-eight ends where it began
    assert figure.read_text().lstrip().startswith("<?xml") and "<svg" in figure.read_text()


def test_a_path_file_with_blended_corners_is_tracked_as_a_user_runs_it(tmp_path):
    f = tmp_path / "corners.csv"
    f.write_text("x,y\n0,0\n1,0\n1,1\n")
    done = run_entry_point("track", "omni4", f, "--blend", "0.2", "--odometry", tmp_path / "odom.tum", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "omni4: corners.csv" in done.stdout and "distance to the path: RMS" in done.stdout
    assert "odometry written to" in done.stdout
    assert done.stderr == ""


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["tomasi-omni3", "figure9 1"], r"unknown path 'figure9 1'"),
        (["tomasi-omni3", "circle -1"], r"circle radius must be in \(0, 1000\] m"),
        (["tomasi-omni3", "missing.csv"], r"missing.csv"),
        (["tomasi-omni3", "figure8 1", "--heading", "sideways"], r"--heading 'sideways': one of tangent, fixed"),
        (["tomasi-omni3", "figure8 1", "--smooth"], r"smooth is for path files"),
        (["tomasi-omni3", "figure8 1", "--max-wheel-speed", "0"], r"speed must be a number > 0"),
        (["tomasi-omni3", "figure8 1", "--max-wheel-speed", "1e-9"], r"control ticks, more than --max-memory"),
        (["tomasi-omni3", "figure8 1", "--controller", "pid"], r"invalid choice: 'pid'"),
        (["tomasi-omni3", "figure8 1", "--engine", "physics", "--noise", "typical"], r"drop --noise"),
        (["diff-drive", "circle 1", "--heading", "fixed"], r"robot 'diff-drive' cannot drive path 'circle 1'"),
        (["ackermann", "circle 5", "--controller", "mpc"], r"robot 'ackermann' steers its wheels"),
        (["ackermann", "circle 1"], r"robot 'ackermann' cannot drive path 'circle 1'.*steering limits"),
        (["diff-drive", "circle 1", "--controller", "feedback"], r"cannot move sideways"),
        (["tomasi-omni3", "figure8 1", "--plot", "fig.xyz"], r"fig.xyz"),
    ],
)
def test_bad_input_is_one_line_and_status_2(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_cli(capsys, "track", *argv)
    assert rc == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), err
    assert re.search(message, lines[0]), lines[0]
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_an_output_on_the_path_file_or_an_existing_file_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    f = tmp_path / "p.csv"
    f.write_text("x,y\n0,0\n1,0\n")
    rc, _, err = run_cli(capsys, "track", "tomasi-omni3", "p.csv", "--truth", "p.csv")
    assert rc == 2 and "p.csv" in err and f.read_text() == "x,y\n0,0\n1,0\n"
    kept = tmp_path / "kept.tum"
    kept.write_text("mine\n")
    rc, _, err = run_cli(capsys, "track", "tomasi-omni3", "p.csv", "--reference", "kept.tum")
    assert rc == 2 and "--force" in err and kept.read_text() == "mine\n"
