"""Borenstein's correction on degenerate input; the lever parameter's sign.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import numpy as np
import pytest

from omnikin import (
    OmnikinError,
    load_robot,
)


def test_borenstein_degenerate_input_is_an_error():
    from omnikin.evaluation.umbmark import borenstein

    with pytest.raises(OmnikinError, match="undefined"):
        borenstein(-1.0, 1.0, 1e-300, 0.33)


def test_lever_is_the_displacement_component_along_its_direction():
    """The lever is the hub displacement along (-sin a, cos a), a = drive + roller; the calibrate
    table shows that component (not a magnitude with the sign of dx)."""
    import math as _m

    from omnikin.evaluation.calibration import errors_from_vector, parameter_names

    robot = load_robot("tomasi-omni3")
    names = parameter_names(robot)
    p = np.zeros(len(names))
    p[names.index("w1.lever")] = -0.0004
    e = errors_from_vector(robot, p).wheels["w1"]
    w = robot.wheel("w1")
    a = w.drive + w.roller
    assert -_m.sin(a) * e.dx + _m.cos(a) * e.dy == pytest.approx(-0.0004, abs=1e-15)


def test_a_robot_without_encoders_is_refused_by_every_measuring_command(tmp_path, capsys, monkeypatch):
    """UMBmark, the calibration plan and the calibration measure through the encoders: a robot
    file without any is refused in one line by each of them, the calibration plan included."""
    from omnikin.cli.main import main

    robot = tmp_path / "uni.yaml"
    robot.write_text(
        "omnikin: 1\nname: uni\nwheels:\n"
        + "".join(
            f"  - {{name: w{i}, type: omni, distance: 0.113, angle_deg: {a}, radius: 0.04125}}\n"
            for i, a in enumerate((0, 120, 240), start=1)
        ),
        encoding="utf-8",
    )
    monkeypatch.chdir(tmp_path)
    for argv in (
        ["calibrate", str(robot), "--plan"],
        ["umbmark", str(robot), "-o", "r", "--runs", "3"],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "no wheel has an 'encoder' entry" in err[0], err
    assert not (tmp_path / "r").exists()


def test_runs_no_robot_of_the_layout_can_explain_are_refused_in_one_line():
    """Every recommended run measured as ending where it started (a robot that never moved):
    only wheels of vanishing radius explain that; the fit leaves the file's ranges on the way and
    says so instead of an internal error about a trial wheel."""
    from omnikin import load_robot
    from omnikin.errors import CalibrationFitError
    from omnikin.evaluation.calibration import least_squares_calibration, recommended_runs
    from omnikin.motion.plans import CalibrationRun

    robot = load_robot("tomasi-omni3")
    plans = recommended_runs(robot, 1.0)
    runs = [CalibrationRun(plan, (0.0, 0.0, 0.0), text) for text, plan in plans for _ in range(3)]
    with pytest.raises(CalibrationFitError, match=r"^calibration: no robot of this layout explains the runs") as info:
        least_squares_calibration(robot, runs)
    assert "\n" not in str(info.value) and "radius must lie in" in str(info.value)
