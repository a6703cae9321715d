"""The ``motor`` field of a robot file's wheel (docs/conventions.md, "Motors"): ``stepper`` or
``dc``, optional (default ``stepper``, the seed robot's: Tomasi and Todt's NEMA 17 steppers);
read back as written, written back by the writer, refused when wrong in one line naming the
file, the wheel and the field. Expected messages are typed in from the conventions."""

from __future__ import annotations

import pytest

from omnikin.errors import InputError, RobotFileError
from omnikin.io.robot_file import load_robot, robot_to_dict, save_robot
from omnikin.kinematics.robot import wheel_set_problem


def robot_yaml(w2_extra: str = "", w2_encoder: bool = True, castor: str = "") -> str:
    encoder = ", encoder: {ticks_per_rev: 600}" if w2_encoder else ""
    lines = [
        "omnikin: 1",
        "name: motors",
        "wheels:",
        "  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 0.04125, encoder: {ticks_per_rev: 600}}",
        f"  - {{name: w2, type: omni, distance: 0.113, angle_deg: 120, radius: 0.04125{encoder}{w2_extra}}}",
        "  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125, encoder: {ticks_per_rev: 600}}",
    ]
    if castor:
        castor_wheel = "name: c, type: castor, x: -0.05, y: 0.0, drive_deg: 0, radius: 0.02, steer: {offset: 0.02}"
        lines.append(f"  - {{{castor_wheel}{castor}}}")
    return "\n".join(lines) + "\n"


def load(tmp_path, text):
    path = tmp_path / "robot.yaml"
    path.write_text(text, encoding="utf-8")
    return load_robot(path)


def error_of(tmp_path, text) -> str:
    with pytest.raises(RobotFileError) as info:
        load(tmp_path, text)
    message = str(info.value)
    assert "\n" not in message, message
    return message


def test_without_motor_a_wheel_has_a_stepper_and_the_file_is_written_back_without_one(tmp_path):
    robot = load(tmp_path, robot_yaml())
    assert [w.motor_kind for w in robot.wheels] == ["stepper"] * 3
    assert not any(w.counts_close_loop for w in robot.wheels)
    assert all("motor" not in w for w in robot_to_dict(robot)["wheels"])


@pytest.mark.parametrize("motor", ["stepper", "dc"])
def test_a_motor_is_read_and_written_back_as_given(tmp_path, motor):
    robot = load(tmp_path, robot_yaml(f", motor: {motor}"))
    assert robot.wheel("w2").motor == motor and robot.wheel("w1").motor is None
    assert robot.wheel("w2").counts_close_loop == (motor == "dc")
    save_robot(robot, tmp_path / "again.yaml")
    again = load_robot(tmp_path / "again.yaml")
    assert [w.motor for w in again.wheels] == [None, motor, None]
    assert robot_to_dict(again) == robot_to_dict(robot)


@pytest.mark.parametrize(
    ("extra", "encoder", "castor", "expected"),
    [
        (", motor: servo", True, "", "wheel 'w2' (#2): field 'motor': must be one of stepper, dc, got 'servo'"),
        (", motor: 1", True, "", "wheel 'w2' (#2): field 'motor': must be one of stepper, dc, got 1"),
        (", motor: null", True, "", "wheel 'w2' (#2): field 'motor': must be one of stepper, dc, got null"),
        (
            ", motor: dc",
            False,
            "",
            "wheel 'w2' (#2): field 'motor': a dc motor's speed loop closes on the wheel's encoder: give the wheel "
            "an encoder, or use stepper",
        ),
        ("", True, ", motor: stepper", "wheel 'c' (#4): field 'motor': a castor is passive: it has no motor"),
    ],
)
def test_a_wrong_motor_is_refused_in_one_line_naming_file_wheel_and_field(tmp_path, extra, encoder, castor, expected):
    message = error_of(tmp_path, robot_yaml(extra, encoder, castor))
    assert message.startswith(f"{tmp_path / 'robot.yaml'}: {expected}"), message


def test_the_presets_say_their_motors():
    """docs/conventions.md, "Motors": the seed robot's steppers, the DC motors of the robots built so."""
    expected = {
        "tomasi-omni3": "stepper",
        "garcia-sillas-omni3": "dc",
        "diff-drive": "dc",
        "mecanum4": "dc",
        "xr4000": "dc",
        "omni4": None,
        "synchro": None,
        "ackermann": None,
        "villasenor-omni3": None,
    }
    for name, motor in expected.items():
        robot = load_robot(name)
        assert {w.motor for w in robot.encoded} == {motor}, name


def test_a_robot_as_built_with_another_motor_does_not_fit(tmp_path):
    from dataclasses import replace

    robot = load(tmp_path, robot_yaml())
    other = replace(robot, wheels=tuple(replace(w, motor="dc") if w.name == "w3" else w for w in robot.wheels))
    assert wheel_set_problem(robot, other) == "wheel 'w3' has a dc motor, not a stepper motor as on 'motors'"
    with pytest.raises(InputError, match="wheel 'w2': motor must be one of stepper, dc"):
        replace(robot.wheel("w2"), motor="brushless")
