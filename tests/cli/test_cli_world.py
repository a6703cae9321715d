"""--world on the command line: the runs start at the world's start pose, stop at its walls and
report the contacts; a bad world file is one line."""

from __future__ import annotations

import json

import pytest

from support.cli import run_cli

WORLD = """\
omnikin_world: 1
name: one-wall
start: [0.5, -1, 90]
walls:
  - {name: north, points: [[-3, 1], [3, 1]], thickness: 0.1}
"""
FACE = 1.0 - 0.05  # the wall's near face, at y = 0.95


@pytest.fixture()
def world(tmp_path):
    path = tmp_path / "world.yaml"
    path.write_text(WORLD)
    return path


def test_simulate_stops_at_the_wall_ahead_and_names_it(capsys, tmp_path, world):
    rc, out, err = run_cli(
        capsys, "simulate", "tomasi-omni3", "--world", world, "--path", "line 3", "--errors", "none",
        "--noise", "none", "--bag", tmp_path / "run.bag", "--json",
    )  # fmt: skip
    assert rc == 0, err
    summary = json.loads(out)
    assert summary["start"] == pytest.approx([0.5, -1.0, 1.5707963267948966])
    (contact,) = summary["contacts"]
    assert contact["body"] == "north"
    assert contact["point"][1] == pytest.approx(FACE, abs=1e-9)
    # facing +y from y = -1, the robot stops short of the face by its reach: in its start frame
    # it went forward (x) less than 1.95 m while its odometry counted the whole 3 m
    assert 1.7 < summary["truth_end"][0] < FACE + 1.0
    assert summary["odometry_end"][0] == pytest.approx(3.0, abs=1e-9)
    assert "touched 'north'" in err


def test_track_in_a_world_reports_no_contact_along_a_clear_path(capsys, world):
    rc, out, err = run_cli(capsys, "track", "tomasi-omni3", "circle 0.4", "--world", world, "--json")
    assert rc == 0, err
    summary = json.loads(out)
    assert summary["world"] == str(world)
    assert summary["contacts"] == []
    assert summary["max_error_m"] < 0.05


def test_a_missing_or_bad_world_file_is_one_line(capsys, tmp_path):
    rc, _, err = run_cli(
        capsys, "simulate", "tomasi-omni3", "--world", tmp_path / "none.yaml", "--log", tmp_path / "x.csv"
    )
    assert rc == 2
    assert err.strip().count("\n") == 0 and "none.yaml" in err
    bad = tmp_path / "bad.yaml"
    bad.write_text(WORLD.replace("thickness: 0.1", "thickness: -1"))
    rc, _, err = run_cli(capsys, "track", "tomasi-omni3", "circle 0.4", "--world", bad)
    assert rc == 2
    assert err.strip() == (
        f"omnikin: error: {bad}: line 5: wall #1: field 'thickness': must lie in [0.001, 10] m, got -1"
    )


def test_a_world_file_is_an_input_no_output_may_replace(capsys, world):
    rc, _, err = run_cli(capsys, "simulate", "tomasi-omni3", "--world", world, "--log", world, "--force")
    assert rc == 2
    assert "is (or is inside, or contains) the input" in err
    assert world.read_text() == WORLD


def test_the_serial_back_end_has_no_world(capsys, world):
    rc, _, err = run_cli(capsys, "ros", "tomasi-omni3", "--backend", "serial", "--port", "/dev/null", "--world", world)
    assert rc == 2
    assert "--world apply only to --backend sim or physics" in err
