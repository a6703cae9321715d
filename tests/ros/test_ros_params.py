"""Parameter files and ``--ros-args -p`` names of ``omnikin ros`` (no rclpy needed).

A parameter spelled twice (flat and nested) is refused naming both spellings; an unknown name
is refused with the closest known one; files go through the strict YAML loader.
"""

from __future__ import annotations

import pytest

from omnikin.cli.main import main as cli_main
from omnikin.errors import InputError
from omnikin.ros.params import DEFAULTS, check_names, load_params, ros_args_names


def load(tmp_path, text: str) -> dict:
    p = tmp_path / "base.yaml"
    p.write_text(text)
    return load_params(p)


def refused(tmp_path, text: str) -> str:
    with pytest.raises(InputError) as info:
        load(tmp_path, text)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(str(tmp_path / "base.yaml")), msg
    return msg


@pytest.mark.parametrize(
    "text, name, first, second",
    [
        (
            "linear.x.max_velocity: 0.3\nlinear:\n  x:\n    max_velocity: 0.4\n",
            "linear.x.max_velocity",
            "linear.x.max_velocity",
            "linear: x: max_velocity",
        ),
        (
            "linear:\n  x:\n    max_velocity: 0.4\nlinear.x:\n  max_velocity: 0.3\n",
            "linear.x.max_velocity",
            "linear: x: max_velocity",
            "linear.x: max_velocity",
        ),
        (
            "omnikin_base:\n  ros__parameters:\n    angular.z.max_velocity: 1.0\n"
            "    angular:\n      z:\n        max_velocity: 2.0\n",
            "angular.z.max_velocity",
            "angular.z.max_velocity",
            "angular: z: max_velocity",
        ),
    ],
)
def test_a_parameter_given_twice_is_refused_naming_both_places(tmp_path, text, name, first, second):
    msg = refused(tmp_path, text)
    assert msg.endswith(f": parameter {name!r} given twice, as {first!r} and as {second!r}; keep one"), msg


def test_flat_and_nested_spellings_of_different_parameters_mix(tmp_path):
    values = load(tmp_path, "linear.x.max_velocity: 0.4\nlinear:\n  x:\n    max_acceleration: 0.8\n")
    assert values["linear.x.max_velocity"] == 0.4 and values["linear.x.max_acceleration"] == 0.8


@pytest.mark.parametrize(
    "text, suggestion",
    [
        ("publish_rat: 50.0\n", "did you mean 'publish_rate'?"),
        ("cmd_vel_timout: 0.2\n", "did you mean 'cmd_vel_timeout'?"),
        ("linear:\n  x:\n    max_velocty: 0.3\n", "did you mean 'linear.x.max_velocity'?"),
        ("omnikin_base:\n  ros__parameters:\n    use_stamped_vell: true\n", "did you mean 'use_stamped_vel'?"),
    ],
)
def test_an_unknown_parameter_suggests_the_closest_name(tmp_path, text, suggestion):
    msg = refused(tmp_path, text)
    assert "unknown parameter" in msg and msg.endswith(suggestion), msg


def test_an_unknown_parameter_far_from_every_name_lists_them(tmp_path):
    msg = refused(tmp_path, "bogus: 1\n")
    assert "unknown parameter 'bogus'; known: " + ", ".join(DEFAULTS) in msg, msg


def test_parameter_files_go_through_the_strict_yaml_loader(tmp_path):
    # PyYAML's safe loader takes the second value of a repeated key silently, and reads 2e-4 as
    # a string: the strict loader refuses the one and reads the other as a number
    msg = refused(tmp_path, "publish_rate: 50.0\npublish_rate: 100.0\n")
    assert "duplicate key 'publish_rate'" in msg, msg
    assert load(tmp_path, "wheel_slip: 3e-4\n")["wheel_slip"] == 3e-4


def test_check_names_allows_rclpy_own_parameters_only_when_asked():
    check_names(
        ["publish_rate", "use_sim_time", "start_type_description_service", "qos_overrides./odom.publisher.depth"],
        "--ros-args",
        ros_own=True,
    )
    with pytest.raises(InputError, match=r"^--ros-args: unknown parameter 'use_sim_time'"):
        check_names(["use_sim_time"], "--ros-args")
    with pytest.raises(
        InputError, match=r"^--ros-args: unknown parameter 'publish_rat'; did you mean 'publish_rate'\?$"
    ):
        check_names(["publish_rate", "publish_rat"], "--ros-args", ros_own=True)


def test_ros_args_names():
    args = [
        "-p",
        "publish_rat:=1.0",
        "-r",
        "__ns:=/robot1",
        "--param",
        "cmd_vel_timeout:=0.2",
        "-p",
        "omnikin_base:wheel_slip:=1e-4",
        "--params-file",
        "x.yaml",
        "-p",
    ]
    assert ros_args_names(args) == ["publish_rat", "cmd_vel_timeout"]  # node-prefixed ones: the node's
    assert ros_args_names(None) == []


def test_cli_refuses_an_unknown_ros_args_parameter_before_starting(capsys):
    rc = cli_main(["ros", "diff-drive", "--ros-args", "-p", "publish_rat:=100.0"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.strip().splitlines() == [
        "omnikin: error: --ros-args: unknown parameter 'publish_rat'; did you mean 'publish_rate'?"
    ]


def test_cli_refuses_a_parameter_given_twice(capsys, tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("cmd_vel_timeout: 0.2\nlinear.x.max_velocity: 0.3\nlinear:\n  x:\n    max_velocity: 0.4\n")
    rc = cli_main(["ros", "diff-drive", "--params", str(p)])
    lines = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(lines) == 1, lines
    assert "given twice, as 'linear.x.max_velocity' and as 'linear: x: max_velocity'" in lines[0]
