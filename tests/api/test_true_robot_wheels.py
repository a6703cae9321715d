"""A robot as built must have the robot's wheels: the same names, types and encoders. A true
robot with an extra wheel, another robot's wheels, a wheel of another type or an encoder
added or removed is refused in one line naming the difference, wherever a true robot is given
(omnikin.run_umbmark, omnikin.simulate, the simulation core, the simulated back-end of the ROS
node, the command line). Positions, radii and encoder scales may differ: that is what a robot as
built gets wrong."""

from __future__ import annotations

import numpy as np
import pytest

import omnikin
from omnikin import InputError, load_robot
from omnikin.motion.plans import line
from omnikin.presets import preset_path
from omnikin.simulation.backend import SimBackend
from omnikin.simulation.kinematic import simulate_kinematic
from support.cli import run_entry_point

WHEELS = (
    "  - {name: w1, type: omni, distance: 0.113, angle_deg: 0,   radius: 0.04125, encoder: {ticks_per_rev: 600}}\n"
    "  - {name: w2, type: omni, distance: 0.113, angle_deg: 120, radius: 0.04125, encoder: {ticks_per_rev: 600}}\n"
    "  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125, encoder: {ticks_per_rev: 600}}\n"
)
"""The wheels of the tomasi-omni3 preset."""

HEAD = "omnikin: 1\nname: as-built\nwheels:\n"

BAD = {
    "extra-wheel": (
        WHEELS
        + "  - {name: w4, type: omni, distance: 0.2, angle_deg: 60, radius: 0.04, encoder: {ticks_per_rev: 600}}\n",
        "it has wheel 'w4', which 'tomasi-omni3' has not",
    ),
    "other-names": (WHEELS.replace("w3", "x3"), "it has wheel 'x3', which 'tomasi-omni3' has not"),
    "other-type": (
        WHEELS.replace("{name: w2, type: omni,", "{name: w2, type: swedish, roller_deg: 10, drive_deg: 210,"),
        "wheel 'w2' is of type 'swedish', not 'omni' as on 'tomasi-omni3'",
    ),
    "encoder-removed": (
        WHEELS.replace(
            "radius: 0.04125, encoder: {ticks_per_rev: 600}}\n  - {name: w2", "radius: 0.04125}\n  - {name: w2"
        ),
        "wheel 'w1' has no encoder, but on 'tomasi-omni3' it has one",
    ),
}


def robot_file(tmp_path, kind: str):
    path = tmp_path / f"{kind}.yaml"
    path.write_text(HEAD + BAD[kind][0])
    return path


@pytest.mark.parametrize("kind", sorted(BAD))
def test_api_refuses_a_true_robot_with_other_wheels(tmp_path, kind):
    path = robot_file(tmp_path, kind)
    expected = f"true robot 'as-built' does not fit robot 'tomasi-omni3': {BAD[kind][1]}"
    for call in (
        lambda: omnikin.run_umbmark("tomasi-omni3", true_robot=path, noise="none", calibrate=False, runs=1),
        lambda: omnikin.simulate("tomasi-omni3", true_robot=path),
        lambda: simulate_kinematic(line(1.0), load_robot(path), load_robot("tomasi-omni3")),
        lambda: SimBackend(load_robot("tomasi-omni3"), load_robot(path)),
    ):
        with pytest.raises(InputError) as info:
            call()
        assert str(info.value).startswith(expected) and "\n" not in str(info.value)


def test_another_preset_as_true_robot_is_refused():
    with pytest.raises(InputError, match=r"'omni4' does not fit robot 'tomasi-omni3': it has wheel 'w4'"):
        omnikin.simulate("tomasi-omni3", true_robot=load_robot("omni4"))
    with pytest.raises(InputError, match=r"'tomasi-omni3' does not fit robot 'omni4': it has no wheel 'w4'"):
        omnikin.simulate("omni4", true_robot=load_robot("tomasi-omni3"))


def test_a_true_robot_with_the_same_wheels_in_another_order_and_other_sizes_runs(tmp_path):
    """Same wheels listed w3, w1, w2 with w1's radius 1 % larger: accepted; driving 1 m to the
    left (+y, which turns w1) commanded by the nominal model, the true robot's y is about 1 m."""
    lines = WHEELS.splitlines(keepends=True)
    path = tmp_path / "as-built.yaml"
    path.write_text(HEAD + lines[2] + lines[0].replace("radius: 0.04125", "radius: 0.0416625") + lines[1])
    sim = omnikin.simulate("tomasi-omni3", "line 1 90", true_robot=path, noise="none")
    assert sim.true_robot.wheel_names == ["w3", "w1", "w2"]
    assert sim.run.truth[0, -1, 1] == pytest.approx(1.0, abs=0.02)
    assert not np.allclose(sim.run.truth[0, -1], sim.run.odometry[-1], atol=1e-9)  # the radius error shows


@pytest.mark.parametrize("command", ["umbmark", "simulate"])
def test_command_line_refuses_a_true_robot_with_other_wheels(tmp_path, command):
    path = robot_file(tmp_path, "extra-wheel")
    argv = {
        "umbmark": ["umbmark", "tomasi-omni3", "--true-robot", str(path), "--noise", "none", "--no-calibrate"]
        + ["--runs", "1", "-o", str(tmp_path / "x")],
        "simulate": ["simulate", "tomasi-omni3", "--true-robot", str(path), "--log", str(tmp_path / "x.csv")],
    }[command]
    proc = run_entry_point(*argv)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == (
        "omnikin: error: true robot 'as-built' does not fit robot 'tomasi-omni3': it has wheel 'w4', which "
        "'tomasi-omni3' has not (wheels: ['w1', 'w2', 'w3'])\n"
    )
    assert not (tmp_path / "x").exists() and not (tmp_path / "x.csv").exists()


def test_a_true_robot_with_an_off_centred_steering_wheel_where_it_is_centred_is_refused(tmp_path):
    path = tmp_path / "car.yaml"
    text = preset_path("ackermann").read_text(encoding="utf-8")
    old = "steer: {min_deg: -35, max_deg: 35}}"
    assert text.count(old) == 2
    path.write_text(text.replace(old, "steer: {offset: 0.02, min_deg: -35, max_deg: 35}}", 1))
    with pytest.raises(InputError) as info:
        omnikin.simulate("ackermann", "line 1 0", true_robot=path)
    assert str(info.value) == (
        "true robot 'ackermann' does not fit robot 'ackermann': wheel 'front_left' is off-centred "
        "(steer.offset > 0), but on 'ackermann' it is centred (steer.offset 0)"
    )
