"""Command-line edge cases: infeasible twists reported, Ackermann spins, file lines named after
duplicates, extreme robot files, absurd simulation plans, bag topic names.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from omnikin import (
    load_robot,
)
from omnikin.cli.main import main
from support.cli import run_cli


def test_cli_villasenor_allow_infeasible(capsys):
    assert main(["ik", "villasenor-omni3", "0", "0", "1", "--allow-infeasible", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["feasible"] is False
    v = load_robot("villasenor-omni3")
    assert data["steer_limited"] == [w.offset > math.hypot(w.x, w.y) for w in v.steerable]


def test_cli_ackermann_spin_json(capsys):
    assert main(["ik", "ackermann", "0", "0", "1", "--allow-infeasible", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["feasible"] is False
    # front hubs at (0.6, +-0.25) move along (-+0.25, 0.6): 67.4 deg off the axis either way, limit 35 deg
    assert data["steer_names"] == ["front_left", "front_right"]
    assert data["steer_limited"] == [True, True]
    # the rear axle sits at the centre of rotation: no side slip
    assert np.allclose(data["violation"], 0.0, atol=1e-12)


def test_cli_ackermann_spin_text_names_steering(capsys):
    assert main(["ik", "ackermann", "0", "0", "1", "--allow-infeasible"]) == 0
    out = capsys.readouterr().out
    verdict = [ln for ln in out.splitlines() if ln.startswith("infeasible")]
    assert len(verdict) == 1
    assert "steering" in verdict[0] and "front_left" in verdict[0] and "front_right" in verdict[0]
    assert "slide" not in out and "side slip" not in out


def test_cli_names_file_line_after_duplicates(tmp_path, capsys):
    log = tmp_path / "log.csv"
    lines = [
        "t,w1,w2,w3",  # 1
        "# logger v1",  # 2
        "0.0,0,0,0",  # 3
        "0.1,10,10,10",  # 4
        "0.1,10,10,10",  # 5 duplicate
        "",  # 6
        "0.1,10,10,10",  # 7 duplicate
        "0.2,20,20,20",  # 8
        "0.15,30,30,30",  # 9 time goes back
    ]
    log.write_text("\n".join(lines) + "\n")
    rc = main(["odometry", "tomasi-omni3", str(log), "-o", str(tmp_path / "out.csv")])
    assert rc == 2
    err = capsys.readouterr().err
    error_lines = [ln for ln in err.splitlines() if ln.startswith("omnikin: error:")]
    assert len(error_lines) == 1
    assert "line 9" in error_lines[0]
    for wrong in ("line 5", "line 6", "line 7", "line 8"):
        assert wrong not in error_lines[0]


@pytest.mark.parametrize("first", ["x: 0.1, y: 0, radius: 1.0e-320", "x: 1.0e+308, y: 1.0e+308, radius: 0.05"])
def test_show_extreme_robot_file_one_line_error(tmp_path, capsys, first):
    p = tmp_path / "r.yaml"
    p.write_text(
        "omnikin: 1\nname: r\nwheels:\n"
        f"  - {{name: a, type: omni, {first}, encoder: {{ticks_per_rev: 100}}}}\n"
        "  - {name: b, type: omni, distance: 0.1, angle_deg: 120, radius: 0.05}\n"
        "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n"
    )
    assert main(["show", str(p)]) == 2
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("omnikin: error:")
    assert "Traceback" not in cap.err


def test_simulate_refuses_absurd_plans_and_stamps(capsys, tmp_path):
    pytest.importorskip("rosbags")
    rc, _, err = run_cli(capsys, "simulate", "tomasi-omni3", "--path", "spin 1e300", "--bag", tmp_path / "a.bag")
    assert rc == 2 and "'spin 1e300': angle must lie in" in err and "deg, got 1e+300" in err
    rc, _, err = run_cli(capsys, "simulate", "tomasi-omni3", "--start", "3e9", "--bag", tmp_path / "b.bag")
    assert rc == 2 and "do not fit a ROS 2 bag" in err and "2147483647 s" in err


def test_bag_topic_names_are_checked(capsys, tmp_path):
    pytest.importorskip("rosbags")
    rc, _, err = run_cli(
        capsys,
        "bag",
        "odometry",
        "tomasi-omni3",
        tmp_path / "in.bag",
        "-o",
        tmp_path / "o.bag",
        "--odom-topic",
        "bad topic!!",
    )
    assert rc == 2 and "not a valid ROS 2 topic name" in err
