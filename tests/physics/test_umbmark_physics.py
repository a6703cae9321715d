"""``omnikin umbmark --engine physics`` and ``omnikin.run_umbmark(..., engine="physics")``: the
UMBmark study with every run driven in MuJoCo on the robot as built, and the floor of the nominal
robot.

Expected values, independent of the code under test:
- the floor: the convergence probe of a 1 m square of the nominal tomasi-omni3 in physics at 50 Hz
  (end heading +-0.13 deg, x -1.24 mm, y -+1.03 mm: a return error of about 2 mm, mirror-symmetric
  in cw and ccw), bounded here by :data:`FLOOR_BOUND`;
- the robot as built: the kinematic engine's UMBmark of the same robot without random errors
  (the seed builds the same robot in both engines), which the physics must match within the
  floor and the physics' validation tolerance (0.5 % of the distance driven, docs/physics.md);
- calibration: the kinematic study's assertion, E_max,syst reduced several-fold.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from omnikin.api.umbmark import run_umbmark, umbmark_cost
from omnikin.errors import InputError, ResourceLimitError
from support.cli import run_cli

pytest.importorskip("mujoco")

SMALL = dict(side=1.0, runs=1, rate=50.0, seed=1)
"""A small study: tomasi-omni3, a 1 m square, one run per direction, 50 Hz."""

FLOOR_BOUND = 0.005
"""Bound [m] of the floor of a 1 m square: the probe's return error is about 2 mm."""

PATH = 4.0
"""Distance [m] of one run of a 1 m square."""

TOLERANCE = 0.005 * PATH
"""The physics' validation tolerance (0.5 % of the distance) over one run [m]."""


@pytest.fixture(scope="module")
def study():
    return run_umbmark("tomasi-omni3", engine="physics", **SMALL)


def test_floor_of_the_nominal_robot_is_a_few_millimetres(study):
    floor = study.floor.values
    assert len(floor) == 1
    assert 0.0 < floor[0] < FLOOR_BOUND


def test_robot_as_built_shows_its_injected_errors_above_the_floor(study):
    kinematic = run_umbmark("tomasi-omni3", noise="none", calibrate=False, **SMALL)
    expected = kinematic.before[0].e_max_syst
    before = study.before[0].e_max_syst
    assert before > 5 * study.floor.values[0]
    assert abs(before - expected) <= study.floor.values[0] + TOLERANCE


def test_calibration_from_physics_runs_reduces_the_error_several_fold(study):
    before, after = study.before[0].e_max_syst, study.after[0].e_max_syst
    assert after < before / 5
    assert after < FLOOR_BOUND
    assert study.calibration.fits
    assert study.systematic == {"before": before, "after": after}


def test_result_and_report_state_the_engine_and_the_floor(study, tmp_path):
    doc = study.write(tmp_path / "report", figure_format="svg")
    figure = (tmp_path / "report" / "return_errors.svg").read_text()
    assert "floor (nominal robot in physics)" in figure and "noise floor" not in figure
    assert doc["engine"] == "physics" and doc["settings"]["engine"] == "physics"
    assert doc["settings"]["noise"] is None
    assert "roller contact" in doc["methods"]["noise_floor"]
    assert doc["noise_floor"]["e_max_syst_median"] == pytest.approx(study.floor.values[0])
    on_disk = json.loads((tmp_path / "report" / "result.json").read_text())
    assert on_disk["engine"] == "physics"
    report = (tmp_path / "report" / "report.md").read_text()
    assert "Engine: physics" in report and "roller contact alone" in report
    assert doc["after"]["at_noise_floor"] and "After calibration, E_max,syst" in report
    assert "is at or below the floor" in report and "noise floor" not in report.lower()
    assert "--engine physics" in study.command_line() and "--noise" not in study.command_line()


def test_kinematic_cost_keeps_its_samples_per_second():
    cost = umbmark_cost("tomasi-omni3", side=1.0, runs=1, rate=50.0)
    assert cost.seconds == pytest.approx(cost.samples / 1e7)


def test_physics_cost_is_wall_time_per_simulated_second():
    cost = umbmark_cost("tomasi-omni3", engine="physics", side=1.0, runs=1, rate=50.0)
    # the estimate is the simulated samples times the step cost measured on this machine (how long
    # that is depends on the machine and its load: its pace is benchmarks/bench_physics.py's)
    assert cost.samples > 0 and cost.seconds_per_sample > 0
    assert cost.seconds == pytest.approx(cost.samples * cost.seconds_per_sample)
    with pytest.raises(ResourceLimitError, match="max_time"):
        run_umbmark("tomasi-omni3", engine="physics", max_time=1.0, **SMALL)


@pytest.mark.parametrize("noise", ["typical", "none"])
def test_physics_refuses_a_noise_model_in_one_line(noise):
    with pytest.raises(InputError, match=r"physics engine has no random error model") as info:
        run_umbmark("tomasi-omni3", engine="physics", noise=noise, **SMALL)
    assert "\n" not in str(info.value)


def test_unknown_engine_is_refused_naming_the_choices():
    with pytest.raises(InputError, match=r"engine \(--engine\) must be one of kinematic, physics"):
        run_umbmark("tomasi-omni3", engine="mujoco", **SMALL)


def test_cli_umbmark_engine_physics_states_the_floor_with_its_spread_over_roller_phases(capsys, tmp_path):
    out = tmp_path / "r"
    rc, stdout, err = run_cli(
        capsys, "umbmark", "--engine", "physics", "--side", "1", "--runs", "3", "--rate", "50",
        "--no-calibrate", "--json", "-o", out, "--figures", "svg",
    )  # fmt: skip
    assert rc == 0, err
    doc = json.loads(stdout)
    assert doc["engine"] == "physics" and "after" not in doc
    floor = doc["noise_floor"]
    assert floor["procedures"] == 1
    assert 0.0 < floor["e_max_syst_median"] < FLOOR_BOUND
    # three runs per direction at their own roller phases: an interval of nonzero width around the floor
    low, high = floor["e_max_syst_interval"]
    assert low < floor["e_max_syst_median"] < high
    assert floor["e_max_syst_limit"] == high
    assert doc["before"]["e_max_syst_interval"][1] > doc["before"]["e_max_syst_interval"][0]
    report = (out / "report.md").read_text()
    assert f"interval over the runs' spread {low * 1000:.2f} to {high * 1000:.2f} mm" in report
    assert "roller phases" in doc["methods"]["noise_floor"]


def test_cli_refuses_noise_with_the_physics_engine(capsys, tmp_path):
    rc, _, err = run_cli(capsys, "umbmark", "--engine", "physics", "--noise", "typical", "-o", tmp_path / "r")
    assert rc == 2
    assert err.count("\n") == 1 and "drop --noise" in err
    assert not (tmp_path / "r").exists()


def test_trials_are_runs_at_their_own_roller_phases_and_make_the_floor():
    steps: list[str] = []
    report = run_umbmark("tomasi-omni3", engine="physics", trials=2, calibrate=False, progress=steps.append, **SMALL)
    # 2 procedures x 1 run x 2 directions before, then as many of the nominal robot for the floor
    assert steps == [f"UMBmark before calibration: run {k} of 4" for k in (1, 2, 3, 4)] + [
        f"floor (nominal robot): run {k} of 4" for k in (1, 2, 3, 4)
    ]
    first, second = report.before
    # each run starts its wheels at other roller phases: the procedures differ, by less than the floor
    assert first.e_max_syst != second.e_max_syst
    assert abs(second.e_max_syst - first.e_max_syst) < FLOOR_BOUND
    assert len(report.floor.values) == 2 and all(0.0 < v < FLOOR_BOUND for v in report.floor.values)
    doc = report.as_dict()
    assert doc["monte_carlo"]["before"]["procedures"] == 2
    assert doc["noise_floor"]["procedures"] == 2


def test_same_seed_same_runs_other_seed_other_roller_phases():
    settings = dict(SMALL, calibrate=False)
    one = run_umbmark("tomasi-omni3", engine="physics", true_robot="tomasi-omni3", **settings)
    again = run_umbmark("tomasi-omni3", engine="physics", true_robot="tomasi-omni3", **settings)
    other = run_umbmark("tomasi-omni3", engine="physics", true_robot="tomasi-omni3", **dict(settings, seed=2))
    ends = [np.vstack([r.before[0].cw.epsilon, r.before[0].ccw.epsilon]) for r in (one, again, other)]
    assert np.array_equal(ends[0], ends[1])
    assert not np.allclose(ends[0], ends[2], rtol=0.0, atol=1e-7)
    assert one.floor.values[0] == again.floor.values[0] != other.floor.values[0]


def test_a_robot_that_cannot_drive_the_square_is_refused_as_in_the_kinematic_study():
    with pytest.raises(InputError) as kinematic:
        run_umbmark("ackermann", noise="none", **SMALL)
    with pytest.raises(InputError) as physics:
        run_umbmark("ackermann", engine="physics", **SMALL)
    assert str(physics.value) == str(kinematic.value)
    assert "UMBmark does not apply to it" in str(physics.value)


def test_cli_summary_names_the_engine_and_the_floor(capsys, tmp_path):
    rc, stdout, err = run_cli(
        capsys, "umbmark", "--engine", "physics", "--side", "1", "--runs", "1", "--rate", "50",
        "--no-calibrate", "-o", tmp_path / "r", "--figures", "svg",
    )  # fmt: skip
    assert rc == 0, err
    assert "physics engine" in stdout
    assert "floor (nominal robot in physics, roller contact alone)" in stdout
    assert "noise floor" not in stdout


def test_time_step_belongs_to_the_physics_engine_and_is_checked_before_work(monkeypatch):
    with pytest.raises(InputError, match=r"^step \(--step\) is the time step of the physics engine"):
        run_umbmark("tomasi-omni3", step=0.001, noise="none", **SMALL)
    for bad in (0.004, 0.0, -1e-3, float("nan"), True, "0.001"):
        with pytest.raises(InputError, match=r"^step \(--step\) must be a time step in \[1e-05, 0\.002\] s"):
            run_umbmark("tomasi-omni3", engine="physics", step=bad, max_time=1e-9, **SMALL)
    # the computing time follows the number of steps per simulated second (each step's cost is
    # measured on the model, within some 30 %; the samples' share does not change with the step).
    # The measurement is this process's CPU time per step, which a loaded machine's caches
    # stretch unevenly between two measurements: it is held at one value here, so that what is
    # checked is how the estimate scales with the step, not the pace of the machine
    from omnikin.physics import cost

    monkeypatch.setattr(cost, "measure_step_seconds", lambda robot, step, step_option=False: (2e-5, 0.05))
    half = umbmark_cost("tomasi-omni3", engine="physics", step=0.001, side=1.0, runs=1, rate=50.0)
    default = umbmark_cost("tomasi-omni3", engine="physics", side=1.0, runs=1, rate=50.0)
    assert 1.4 * default.seconds < half.seconds < 2.6 * default.seconds
    assert half.samples == default.samples


def test_cli_umbmark_runs_at_the_given_time_step_and_says_so(capsys, tmp_path):
    args = ("--engine", "physics", "--side", "1", "--runs", "1", "--rate", "50", "--no-calibrate", "--json")
    rc, stdout, err = run_cli(capsys, "umbmark", *args, "--step", "0.001", "-o", tmp_path / "fine", "--figures", "svg")
    assert rc == 0, err
    fine = json.loads(stdout)
    rc, stdout, err = run_cli(capsys, "umbmark", *args, "-o", tmp_path / "default", "--figures", "svg")
    assert rc == 0, err
    default = json.loads(stdout)
    assert fine["settings"]["step"] == 0.001 and default["settings"]["step"] == 0.002
    # same seed, same roller phases: only the step differs, and the runs with it (by far less than the floor)
    before = [doc["before"]["e_max_syst"] for doc in (fine, default)]
    assert before[0] != before[1] and abs(before[0] - before[1]) < FLOOR_BOUND
    report = (tmp_path / "fine" / "report.md").read_text()
    assert "MuJoCo at a 1 ms time step" in report and "--engine physics --step 0.001" in report
    assert "--step" not in (tmp_path / "default" / "report.md").read_text()
    rc, _, err = run_cli(capsys, "umbmark", "--step", "0.001", "-o", tmp_path / "k")
    assert rc == 2 and err.count("\n") == 1 and "--engine physics" in err and not (tmp_path / "k").exists()
