"""The files omnikin writes for its own commands read back as written (io/runs.py, writing side):
runs files for ``omnikin calibrate``, measurement files for ``omnikin umbmark analyze``."""

from __future__ import annotations

import math

import pytest

from omnikin.errors import InputError
from omnikin.evaluation.umbmark import analyze
from omnikin.io.runs import (
    calibration_runs_text,
    calibration_template,
    read_calibration_runs,
    read_umbmark_measurements,
    umbmark_measurements_text,
)
from omnikin.motion.plans import CalibrationRun, parse_plan


def runs_with(headings):
    return [
        CalibrationRun(parse_plan("line 4 0"), (4.0 + k * 1e-3, -2e-3, h), "line 4 0") for k, h in enumerate(headings)
    ]


@pytest.mark.parametrize("headings", [[0.01, -0.02], [math.nan, math.nan]])
def test_runs_files_read_back_as_written(tmp_path, headings):
    f = tmp_path / "runs.csv"
    f.write_text(calibration_runs_text(runs_with(headings), "made by a test\nsecond line"), encoding="utf-8")
    back = read_calibration_runs(f)
    assert [r.label for r in back] == ["line 4 0", "line 4 0"]
    for run, h in zip(back, headings, strict=True):
        assert run.plan == parse_plan("line 4 0")
        if math.isnan(h):
            assert math.isnan(run.measured[2])
        else:
            assert run.measured[2] == pytest.approx(h, abs=1e-7)  # written to 1e-5 deg
    assert f.read_text(encoding="utf-8").startswith("# made by a test\n# second line\n")


def test_a_heading_measured_in_some_runs_only_cannot_be_written():
    with pytest.raises(InputError, match="some runs and not in others"):
        calibration_runs_text(runs_with([0.01, math.nan]))


@pytest.mark.parametrize("theta", [True, False])
def test_measurement_files_read_back_as_written(tmp_path, theta):
    cw = [(0.1, -0.05, 0.01), (0.12, -0.03, 0.02), (0.09, -0.06, -0.01)]
    ccw = [(0.03, 0.07, 0.0), (0.05, 0.06, 0.03)]
    if not theta:
        cw, ccw = [e[:2] for e in cw], [e[:2] for e in ccw]
    res = analyze(cw, ccw)
    if not theta:  # analyze fills an unmeasured heading with zero
        for d in (res.cw, res.ccw):
            d.epsilon[:, 2] = math.nan
    f = tmp_path / "m.csv"
    f.write_text(umbmark_measurements_text(res), encoding="utf-8")
    back = read_umbmark_measurements(f)
    again = analyze(back["cw"], back["ccw"])
    assert again.e_max_syst == pytest.approx(res.e_max_syst, abs=1e-6)
    assert ("theta_abs_deg" in f.read_text(encoding="utf-8")) == theta


def test_the_template_has_every_path_repeated_and_the_runs_file_columns():
    text = calibration_template(["spin 180", "line 4 0"], 2, "fill me")
    rows = [line for line in text.splitlines() if not line.startswith("#")]
    assert rows == ["path,x_abs,y_abs,theta_abs_deg", "spin 180,,,", "spin 180,,,", "line 4 0,,,", "line 4 0,,,"]


@pytest.mark.parametrize("blank", ["\u3000", "\x1c", "\u00a0"])
def test_a_path_spaced_with_other_white_space_is_refused_naming_file_line_and_column(tmp_path, blank):
    """'line<U+3000>4' is not 'line 4' (as str.split() would read it): a path's words are
    separated by spaces and tabs, in a file as on the command line."""
    path = tmp_path / "runs.csv"
    path.write_text(f"path,x_abs,y_abs\nline 4,4,0\nline{blank}4,4,0\n", encoding="utf-8")
    with pytest.raises(InputError, match=rf"runs.csv: line 3, column 'path': .*white space U\+{ord(blank):04X}"):
        read_calibration_runs(path)


def test_simulate_refuses_other_white_space_around_a_path(capsys):
    from support.cli import run_cli

    rc, out, err = run_cli(capsys, "simulate", "diff-drive", "--path", "line 0.1\u3000; spin 90", "--log", "-")
    assert rc == 2 and out == "" and "white space U+3000" in err and err.count("\n") == 1, err
