"""``omnikin simulate --engine physics`` and ``omnikin.simulate(..., engine="physics")``: the plan of
the kinematic engine driven in MuJoCo, its tick log read back by ``omnikin odometry``.

Expected values: the closed form of ``--path 'line 1'`` (1 m along x, heading 0) and the wheel
angles of that line, ``J (1, 0, 0)`` [rad] over the file's angle per tick. Tolerance 0.5 % of the
distance, the tolerance of the physics' validation (docs/physics.md: twists within 0.5 % of the
kinematics, measured 0.04-0.13 %; odometry from the simulated encoders within 0.5 % of the
truth), for the truth and the odometry alike.
"""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest

import omnikin
from omnikin import load_robot
from omnikin.presets import preset_path
from support.cli import run_cli, run_entry_point

TOLERANCE = 0.005
"""Of the 1 m line: 5 mm in position, 5 mrad in heading (docs/physics.md, "Validation")."""


def run(*argv, cwd):
    return run_entry_point(*argv, cwd=cwd, timeout=300)


HALF = math.sqrt(0.5)


@pytest.mark.parametrize(
    ("name", "path", "end"),
    [
        ("tomasi-omni3", "line 1", (1.0, 0.0, 0.0)),
        ("omni4", "line 1", (1.0, 0.0, 0.0)),
        ("diff-drive", "line 1", (1.0, 0.0, 0.0)),
        ("ackermann", "line 1", (1.0, 0.0, 0.0)),
        ("synchro", "line 1 45", (HALF, HALF, 0.0)),  # its wheels steer to 45 deg before they drive
    ],
)
def test_physics_line_log_read_by_odometry_ends_where_the_line_does_like_the_truth(name, path, end, tmp_path):
    sim = run("simulate", name, "--engine", "physics", "--errors", "none", "--path", path, "--log", "log.csv",
              "--json", cwd=tmp_path)  # fmt: skip
    assert sim.returncode == 0, sim.stderr
    summary = json.loads(sim.stdout)
    assert summary["engine"] == "physics"
    assert summary["saturated_commands"] == 0  # the plan keeps the motors' limits
    odo = run("odometry", name, "log.csv", "-o", "traj.csv", "--json", cwd=tmp_path)
    assert odo.returncode == 0, odo.stderr
    odometry = np.array(json.loads(odo.stdout)["final_pose"])
    truth = np.array(summary["truth_end"])
    for pose in (odometry, truth):
        np.testing.assert_allclose(pose, end, atol=TOLERANCE)
    np.testing.assert_allclose(odometry, summary["odometry_end"], atol=1e-9)  # the log is the run's odometry
    assert math.dist(truth[:2], odometry[:2]) < TOLERANCE


def test_physics_tick_log_holds_whole_ticks_of_the_wheel_angles_of_the_line(tmp_path):
    robot = load_robot("tomasi-omni3")
    proc = run("simulate", "tomasi-omni3", "--engine", "physics", "--errors", "none", "--path", "line 1",
               "--log", "log.csv", cwd=tmp_path)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in (tmp_path / "log.csv").read_text().splitlines() if not line.startswith("#")]
    rows = list(csv.reader(lines))
    assert rows[0] == ["t", *robot.encoded_names]
    assert all(re.fullmatch(r"-?\d+", cell) for row in rows[1:] for cell in row[1:])  # integer ticks
    last = np.array([int(c) for c in rows[-1][1:]])
    angles = robot.ik_matrix @ np.array([1.0, 0.0, 0.0])  # rad, wheel speeds per unit twist times 1 m
    expected = angles / robot.rad_per_tick(robot.encoded_names)
    assert np.all(np.abs(last - expected) <= np.maximum(1.0, TOLERANCE * np.abs(expected)))
    assert np.all(np.diff(np.array([float(r[0]) for r in rows[1:]])) > 0)


@pytest.mark.parametrize(
    ("options", "named"),
    [
        (["--engine", "physics", "--noise", "typical"], "--noise"),
        (["--engine", "physics", "--noise", "none"], "--noise"),
        (["--step", "0.001"], "--step"),
        (["--engine", "physics", "--step", "0.01"], "--step"),
    ],
)
def test_options_of_the_other_engine_are_refused_in_one_line(options, named, tmp_path, capsys):
    rc, _, err = run_cli(
        capsys, "simulate", "tomasi-omni3", "--path", "line 1", "--log", tmp_path / "log.csv", *options
    )
    assert rc == 2
    assert err.count("\n") == 1 and named in err
    assert not (tmp_path / "log.csv").exists()


def test_physics_engine_drives_the_robot_as_built_like_the_kinematic_engine(tmp_path, capsys):
    """--errors typical with --seed: the same robot as built in both engines; the kinematic
    engine's truth (its random slip is below 0.1 mm on 1 m) is the expected end pose."""
    ends = {}
    for engine in ("kinematic", "physics"):
        rc, out, err = run_cli(capsys, "simulate", "tomasi-omni3", "--engine", engine, "--path", "line 1",
                               "--seed", "3", "--log", tmp_path / f"{engine}.csv", "--json")  # fmt: skip
        assert rc == 0, err
        summary = json.loads(out)
        ends[engine] = np.array(summary["truth_end"])
    assert summary["noise"] is None and summary["injected_errors"]
    off_nominal = np.hypot(*ends["kinematic"][:2] - (1.0, 0.0))
    assert off_nominal > 2 * TOLERANCE  # the errors matter: the test could fail
    np.testing.assert_allclose(ends["physics"], ends["kinematic"], atol=TOLERANCE)


def test_python_api_runs_the_physics_engine_and_refuses_noise():
    sim = omnikin.simulate("diff-drive", "line 1", errors="none", engine="physics")
    np.testing.assert_allclose(sim.run.truth[0, -1], (1.0, 0.0, 0.0), atol=TOLERANCE)
    with pytest.raises(ValueError, match="noise"):
        omnikin.simulate("diff-drive", "line 1", errors="none", noise="typical", engine="physics")
    with pytest.raises(ValueError, match="engine"):
        omnikin.simulate("diff-drive", "line 1", engine="mujoco")


def test_commands_beyond_the_motors_speed_limit_are_counted_and_warned(tmp_path, capsys):
    """The robot as built (a file) has motors of 1 rad/s; the nominal robot plans the line for its
    own limits (about 12 rad/s), so the moving samples ask for more: held at the limit, and said so."""
    from omnikin.io.robot_file import robot_to_dict

    data = robot_to_dict(load_robot("tomasi-omni3"))
    for wheel in data["wheels"]:
        wheel["max_speed"] = 1.0
    slow = tmp_path / "slow.json"
    slow.write_text(json.dumps(data))
    rc, out, err = run_cli(capsys, "simulate", "tomasi-omni3", "--engine", "physics", "--true-robot", slow,
                           "--path", "line 1", "--log", tmp_path / "log.csv", "--json")  # fmt: skip
    assert rc == 0, err
    assert json.loads(out)["saturated_commands"] > 0
    lines = err.splitlines()
    assert all(line.startswith("omnikin: warning: tomasi-omni3: ") for line in lines), err
    assert sum("held at the limit" in line for line in lines) == 1
    # held at 1 rad/s the wheels turn less than commanded, and the run says by how much (each line
    # names a wheel; w1 stands on a line along x: cos(90 deg) = 0 of the metre)
    short = [line for line in lines if "short of the 866 mm it was commanded to turn" in line]
    assert {re.search(r"wheel '(\w+)'", line).group(1) for line in short} == {"w2", "w3"}, err


@pytest.mark.parametrize(
    ("path", "message"),
    [
        # legs parallel to y: the contacts lie 0.17-0.2 m behind the hips, the centre of mass 74 mm outside them
        ("line 1 90", "cannot stand with the steering of segment 1 of the path"),
        # legs parallel to x stand (10 mm of support) but the swing there carries the chassis over
        ("line 1", "tipped over at t ="),
    ],
)
def test_a_robot_that_cannot_stand_or_tips_over_ends_the_run_with_one_line(tmp_path, capsys, path, message):
    """Villasenor's legs trail up to 255 mm behind steering axes 150 mm apart: their contacts
    swing with the steering (docs/physics.md, "Known limits")."""
    rc, _, err = run_cli(capsys, "simulate", "villasenor-omni3", "--engine", "physics", "--errors", "none",
                         "--path", path, "--log", tmp_path / "log.csv")  # fmt: skip
    assert rc == 1
    assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "log.csv").exists()


def test_steered_wheels_reach_the_segments_steering_before_they_drive(tmp_path, capsys):
    """synchro on 'line 1 45': its wheels turn from 0 to 45 deg standing, then roll."""
    rc, _, err = run_cli(capsys, "simulate", "synchro", "--engine", "physics", "--errors", "none",
                         "--path", "line 1 45", "--log", tmp_path / "log.csv")  # fmt: skip
    assert rc == 0, err
    lines = [line for line in (tmp_path / "log.csv").read_text().splitlines() if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    moving = next(r for r in rows if any(int(r[w]) != 0 for w in ("w1", "w2", "w3")))
    for w in ("w1", "w2", "w3"):
        assert abs(float(moving[f"{w}_steer_deg"]) - 45.0) < 1.0  # within 0.6 deg (0.01 rad) and a tick's roll


def test_physics_truth_headings_are_wrapped_like_the_kinematic_engine():
    """Ten turns on the spot: the truth's heading lies in [-pi, pi) (it read 62.8 rad), and it
    differs from the exact end (0 after ten turns) by the engine's rotation error only: within
    0.5 % of the 20 pi turned (docs/physics.md validation tolerance)."""
    import math

    import omnikin

    sim = omnikin.simulate("tomasi-omni3", "spin 3600", engine="physics", errors="none")
    headings = sim.run.truth[..., 2]
    assert np.all((-math.pi <= headings) & (headings < math.pi))
    assert abs(headings[0, -1]) < 0.005 * 20 * math.pi


def test_xr4000_steered_sideways_at_rest_is_carried_by_its_trail_and_its_odometry_stays_finite():
    """'line 1 90': the wheels steer from 0 to 90 deg standing, which carries the chassis by
    ``d (cos(beta) - 1, sin(beta)) = (-d, d)`` (d = 20 mm trail; the encoders do not see it),
    then drive 1 m along y. Measured steering angles of the parallel wheels that differ by
    0.2 urad leave the odometry finite: it ends where the plan does."""
    import omnikin

    sim = omnikin.simulate("xr4000", "line 1 90", engine="physics", errors="none")
    d = 0.02
    truth, odometry = sim.run.truth[0, -1], sim.run.odometry[-1]
    assert odometry == pytest.approx([0.0, 1.0, 0.0], abs=1e-3)
    assert truth == pytest.approx([-d, 1.0 + d, 0.0], abs=1e-3)


def test_steering_held_at_its_end_stop_is_logged_within_the_limits(tmp_path):
    """synchro with steering limits 10..80 deg starts with its wheels pressed against the 10 deg
    stop; MuJoCo's soft joint limit lets them sit nanoradians past it, which the tick log must
    not carry (its reader refuses angles outside the file's limits)."""
    text = (
        preset_path("synchro")
        .read_text()
        .replace(
            "encoder: {ticks_per_rev: 1024}}", "encoder: {ticks_per_rev: 1024}, steer: {min_deg: 10, max_deg: 80}}"
        )
    )
    assert text.count("min_deg: 10") == 3
    (tmp_path / "limited.yaml").write_text(text)
    sim = run("simulate", "./limited.yaml", "--engine", "physics", "--errors", "none", "--path", "line 1 45",
              "--log", "log.csv", "--json", cwd=tmp_path)  # fmt: skip
    assert sim.returncode == 0, sim.stderr
    with open(tmp_path / "log.csv") as f:
        steering = np.array(
            [
                [float(row[k]) for k in row if k.endswith("_steer_deg")]
                for row in csv.DictReader(line for line in f if not line.startswith("#"))
            ]
        )
    assert steering.min() >= 10.0 and steering.max() <= 80.0
    assert steering[1] == pytest.approx([10.0] * 3, abs=1e-6)  # at the stop when the run starts
    summary = json.loads(sim.stdout)
    np.testing.assert_allclose(summary["truth_end"], (HALF, HALF, 0.0), atol=TOLERANCE)
