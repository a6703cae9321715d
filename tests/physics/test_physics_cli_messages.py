"""One-line messages of the physics commands that name what the user gave: the option, the
path, the robot as built (not an internal parameter)."""

from __future__ import annotations

import pytest
import yaml

from omnikin.presets import preset_path
from support.cli import run_cli


@pytest.mark.parametrize(("option", "value"), [("--max-speed", "0"), ("--max-turn", "-1")])
def test_sim_names_a_limit_option_that_is_not_positive(capsys, option, value):
    rc, _, err = run_cli(capsys, "sim", "tomasi-omni3", option, value)
    assert rc == 2 and err == f"omnikin: error: {option} must be positive, got {value}\n"


@pytest.mark.parametrize("engine", ["kinematic", "physics"])
@pytest.mark.parametrize("path", ["spin 0", "line 0"])
def test_a_path_that_lasts_no_time_asks_for_a_length_or_angle(tmp_path, capsys, engine, path):
    rc, _, err = run_cli(
        capsys, "simulate", "tomasi-omni3", "--engine", engine, "--errors", "none", "--path", path,
        "--log", tmp_path / "o.csv",
    )  # fmt: skip
    assert rc == 2 and err.count("\n") == 1 and "give a length or angle other than 0" in err


def test_steering_limits_that_exclude_zero_drive_a_path_within_them(tmp_path, capsys):
    # synchro steered within [10, 80] deg: a line at 45 deg is drivable; the steering's preference
    # (zero by default) is no steering command and is not checked against the limits
    doc = yaml.safe_load(preset_path("synchro").read_text())
    for wheel in doc["wheels"]:
        wheel["steer"] = {"min_deg": 10, "max_deg": 80}
    (tmp_path / "limited.yaml").write_text(yaml.safe_dump(doc))
    rc, _, err = run_cli(
        capsys, "simulate", tmp_path / "limited.yaml", "--errors", "none", "--path", "line 1 45",
        "--log", tmp_path / "o.csv",
    )  # fmt: skip
    assert rc == 0, err
    rc, _, err = run_cli(
        capsys, "simulate", tmp_path / "limited.yaml", "--errors", "none", "--path", "line 1",
        "--log", tmp_path / "o.csv", "--force",
    )  # fmt: skip
    assert rc == 2 and "steer_hint" not in err and "outside its limits [10, 80] deg" in err
