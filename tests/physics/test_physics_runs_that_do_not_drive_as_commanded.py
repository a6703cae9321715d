"""A physics run that does not drive as commanded says so (docs/physics.md, "Runs that do not
drive as commanded"): ``omnikin simulate --engine physics`` warns in one line per problem and
gives the counts in ``--json``; the UMBmark study names such runs (warnings, result.json,
report.md); wheels that
spin past the odometry's speed bound are a physics failure, not bad input.

Expected values from the plan, not the engine: ``line 1`` asks tomasi-omni3's wheels w2 and w3
(drive directions at +-30 deg to x) for ``cos(30 deg) = 0.866 m`` of rim each and w1 for none;
a robot whose wheels hold no grip (friction 0.001) or whose motors give 1e-5 N m cannot turn
them that far (``mu N r`` is 1e-3 of the default torque; 1e-5 N m accelerates the robot's 3.6 kg
through its 0.05 m wheels at 5e-5 m/s^2, a millimetre in 6 s).
"""

from __future__ import annotations

import json
import math
import re

import pytest

from omnikin import load_robot
from omnikin.io.robot_file import robot_to_dict
from omnikin.motion.plans import parse_plan
from omnikin.physics.run import ALIGN_MAX, TAIL_MAX, simulate_physics
from support.cli import run_cli

RIM = 1000.0 * math.cos(math.radians(30.0))
"""Rim distance [mm] ``line 1`` commands each of tomasi-omni3's wheels w2 and w3."""


def _variant(tmp_path, name: str, **physical) -> str:
    """tomasi-omni3 with ``physical`` on every wheel, as a file."""
    data = robot_to_dict(load_robot("tomasi-omni3"))
    for wheel in data["wheels"]:
        wheel["physical"] = dict(physical)
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(data))
    return str(path)


def _simulate(capsys, tmp_path, robot, path="line 1", *extra):
    rc, out, err = run_cli(capsys, "simulate", robot, "--engine", "physics", "--errors", "none", "--path", path,
                           "--log", tmp_path / "log.csv", "--force", "--json", *extra)  # fmt: skip
    assert rc == 0, err
    return json.loads(out), err.splitlines()


def test_wheels_without_grip_are_reported_short_of_the_turn_they_were_commanded(tmp_path, capsys):
    summary, lines = _simulate(capsys, tmp_path, _variant(tmp_path, "ice", friction=0.001))
    assert summary["truth_end"][0] < 0.1  # the line is not driven...
    off = summary["wheels_off_command"]  # ...and the run says which wheels and by how much
    assert set(off) == {"w2", "w3"}
    assert all(0.8 * RIM < 1000.0 * v <= RIM for v in off.values())  # positive: short of the turn, either way round
    assert set(summary["lagging_wheels"]) == {"w2", "w3"}  # their motors (mu N r) cannot follow either
    short = [line for line in lines if f"short of the {RIM:.4g} mm it was commanded to turn" in line]
    assert {re.search(r"wheel '(\w+)'", line).group(1) for line in short} == {"w2", "w3"}
    assert all(line.startswith("omnikin: warning: ") for line in lines)


def test_rows_side_by_side_turning_faster_than_the_mid_plane_rows_are_not_slip(tmp_path, capsys):
    """Rows 0.1 m either side of the mid-plane (width 0.2 m): the contact lies up to 0.1 m along the
    axle from where the kinematic rows put it, and the robot turns 24 % faster than they say
    (docs/physics.md, "Rows side by side"): rolling, which the slip check must not call slip
    (it warned of all three wheels slipping at 0.078 m/s)."""
    wide = _variant(tmp_path, "wide", rows=2, width=0.2)
    summary, lines = _simulate(capsys, tmp_path, wide, "spin 90", "--rate", "50")
    assert summary["truth_end"][2] > 1.05 * math.pi / 2  # the faster turn of the wide rows...
    assert summary["slipping_wheels"] == {} and not any("slipped" in line for line in lines)  # ...is not slip


def test_motors_too_weak_to_move_the_robot_leave_it_moving_and_say_so(tmp_path, capsys):
    summary, lines = _simulate(capsys, tmp_path, _variant(tmp_path, "weak", max_torque=1e-5))
    assert summary["truth_end"][0] < 0.01
    assert summary["at_rest"] is False
    assert set(summary["wheels_off_command"]) == {"w2", "w3"}
    assert sum(f"still moving {TAIL_MAX:g} s after the plan ended" in line for line in lines) == 1


def test_steering_the_motors_cannot_reach_is_named_by_its_segment(tmp_path, capsys):
    data = robot_to_dict(load_robot("synchro"))
    for wheel in data["wheels"]:
        wheel["physical"] = {"max_torque": 1e-5}
    weak = tmp_path / "weak-synchro.json"
    weak.write_text(json.dumps(data))
    summary, lines = _simulate(capsys, tmp_path, str(weak), "line 0.01 90; line 0.01 0")
    assert summary["steering_not_reached"] == [1, 2]
    assert sum(f"segment 1, 2 was not reached within {ALIGN_MAX:g} s" in line for line in lines) == 1


@pytest.mark.parametrize(
    ("name", "path"),
    [
        ("tomasi-omni3", "square cw rotate 1"),
        ("mecanum4", "square cw rotate 1"),
        ("diff-drive", "square ccw rotate 1"),
        ("synchro", "square cw rotate 1"),
        ("xr4000", "square cw rotate 1"),
        ("ackermann", "arc 3 30"),
    ],
)
def test_the_presets_drive_their_plans_without_a_problem_reported(name, path):
    """No false alarm: the presets follow their commands (docs/physics.md, "Validation")."""
    robot = load_robot(name)
    run = simulate_physics(parse_plan(path), robot, robot, rate=50.0)
    assert run.problems() == []
    assert run.at_rest and not run.wheels and not run.short and not run.steering_not_reached


def test_the_umbmark_study_names_every_run_that_did_not_drive_as_commanded(tmp_path, capsys):
    """Every run of the study on the gripless robot ends short: 2 UMBmark runs and 2 of the floor
    (the nominal robot is the same file), each named in one warning line, in result.json and in
    the report, never averaged silently."""
    ice = _variant(tmp_path, "ice", friction=0.001)
    rc, out, err = run_cli(capsys, "umbmark", ice, "--engine", "physics", "--errors", "none", "--side", "1",
                           "--runs", "1", "--rate", "50", "--no-calibrate", "-o", tmp_path / "report")  # fmt: skip
    assert rc == 0, err
    warned = [line for line in err.splitlines() if line.startswith("omnikin: warning: ")]
    named = [re.match(r"omnikin: warning: (.+?, run \d of 2 \((?:cw|ccw)\)): ", line).group(1) for line in warned]
    assert named == [
        "UMBmark before calibration, run 1 of 2 (cw)",
        "UMBmark before calibration, run 2 of 2 (ccw)",
        "floor (nominal robot), run 1 of 2 (cw)",
        "floor (nominal robot), run 2 of 2 (ccw)",
    ]
    doc = json.loads((tmp_path / "report" / "result.json").read_text())
    assert doc["physics_problems"] == [line.removeprefix("omnikin: warning: ") for line in warned]
    assert "**4 runs did not drive as commanded**" in (tmp_path / "report" / "report.md").read_text()


def test_a_study_whose_calibration_runs_did_not_drive_reports_without_a_calibration(tmp_path, capsys):
    """Motors too weak to move the robot: the calibration runs end where they started, which no
    robot of the layout explains (the fit runs the radii to nothing). The study still writes its
    report, says why there is no calibration, and names the runs (it stopped with an error about a
    trial wheel's radius before)."""
    weak = _variant(tmp_path, "weak", max_torque=2e-5)
    rc, out, err = run_cli(capsys, "umbmark", weak, "--engine", "physics", "--errors", "none", "--side", "1",
                           "--runs", "1", "--rate", "50", "-o", tmp_path / "report", "--json")  # fmt: skip
    assert rc == 0, err
    doc = json.loads((tmp_path / "report" / "result.json").read_text())
    assert "calibration" not in doc and "after" not in doc
    failed = [p for p in doc["physics_problems"] if p.startswith("calibration: no robot of this layout explains")]
    assert len(failed) == 1 and "\n" not in failed[0]
    assert any(p.startswith("calibration run 1 of ") for p in doc["physics_problems"])
    report = (tmp_path / "report" / "report.md").read_text()
    assert "no robot of this layout explains them" in report and "no UMBmark after calibration" in report


def test_simulated_wheels_spinning_past_the_odometry_bound_are_a_physics_failure(tmp_path, capsys):
    """tomasi-omni3 with a 1000 kg chassis (in the documented range): at the 2 ms step its wheels
    spun at about 1300 rad/s, which the odometry refused as an impossible jump and blamed on the
    encoders' counter width. Either the run drives, or it fails as a physics failure naming the
    wheel and the time, never as bad input."""
    data = robot_to_dict(load_robot("tomasi-omni3"))
    data["physical"] = {"mass": 1000}
    heavy = tmp_path / "heavy.json"
    heavy.write_text(json.dumps(data))
    rc, out, err = run_cli(capsys, "simulate", heavy, "--engine", "physics", "--errors", "none", "--path", "line 1",
                           "--log", tmp_path / "log.csv", "--json")  # fmt: skip
    assert "counter" not in err and "impossible jump" not in err
    if rc != 0:
        assert rc == 1  # a failure while running, not bad input (2)
        assert err.count("\n") == 1
        assert re.search(r"the simulated wheel 'w\d' spun at [\d.]+ rad/s between t = [\d.]+ and [\d.]+ s", err), err
