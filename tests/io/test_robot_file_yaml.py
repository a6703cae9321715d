"""Robot files: duplicate keys refused (YAML and JSON), explicit YAML tags refused, exponents read as numbers.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from omnikin import (
    RobotFileError,
    load_robot,
)
from support.paths import omnikin_env


def test_duplicate_key_yaml_refused(tmp_path):
    p = tmp_path / "dup.yaml"
    p.write_text(
        "omnikin: 1\nname: r\nwheels:\n"
        "  - {name: a, type: omni, x: 0.1, y: 0, radius: 0.05, radius: -1}\n"
        "  - {name: b, type: omni, distance: 0.1, angle_deg: 120, radius: 0.05}\n"
        "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n"
    )
    with pytest.raises(RobotFileError, match=r"duplicate key.*radius"):
        load_robot(p)


def test_duplicate_key_json_refused(tmp_path):
    p = tmp_path / "dup.json"
    p.write_text(
        '{"omnikin": 1, "name": "r", "wheels": [{"name": "a", "type": "omni", "x": 0.1, "y": 0,'
        ' "radius": 0.05, "radius": 0.06}]}'
    )
    with pytest.raises(RobotFileError, match=r"duplicate key.*radius"):
        load_robot(p)


def test_yaml_exponent_without_dot_is_a_number(tmp_path):
    p = tmp_path / "exp.yaml"
    p.write_text(
        "omnikin: 1\nname: r\nwheels:\n"
        "  - {name: a, type: omni, distance: 1e-1, angle_deg: 0, radius: 5e-2}\n"
        "  - {name: b, type: omni, distance: 0.1, angle_deg: 120, radius: 5E-2}\n"
        "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n"
    )
    r = load_robot(p)
    assert [w.radius for w in r.wheels] == [0.05, 0.05, 0.05]
    assert r.wheels[0].x == 0.1


# --- YAML 1.1 number forms: refused, not reinterpreted -----------------------------------------------
def omni3_text(angle: str = "120", ticks: str = "512") -> str:
    """Three omni wheels 0.1 m from the centre; wheel b's angle and encoder given as written."""
    return (
        "omnikin: 1\nname: r\nwheels:\n"
        "  - {name: a, type: omni, distance: 0.1, angle_deg: 0, radius: 0.05}\n"
        f"  - name: b\n    type: omni\n    distance: 0.1\n    angle_deg: {angle}\n    radius: 0.05\n"
        f"    encoder: {{ticks_per_rev: {ticks}}}\n"
        "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n"
    )


@pytest.mark.parametrize(
    "angle, ticks, line, message",
    [
        # YAML 1.1 (PyYAML) reads 0120 as the octal 80, YAML 1.2 as 120
        ("0120", "512", 8, "0120 is octal in YAML 1.1 (80) but decimal in YAML 1.2: write 120, not 0120"),
        ("-0120", "512", 8, "write -120, not -0120"),
        ("120", "0600", 10, "0600 is octal in YAML 1.1 (384) but decimal in YAML 1.2: write 600, not 0600"),
        ("120", "0_600", 10, "write 600, not 0_600"),
        # base 60: 2:00 = 2 * 60 + 0, 1:30.5 = 60 + 30.5
        ("2:00", "512", 8, "2:00 is a base-60 (sexagesimal) number in YAML 1.1 (120) but text in YAML 1.2"),
        ("1:30.5", "512", 8, "write 90.5, not 1:30.5"),
        ("120", "0x200", 10, "0x200 is a hexadecimal number in YAML 1.1 (512), not a plain decimal: write 512"),
        ("120", "0b1000000000", 10, "binary number in YAML 1.1 (512)"),
        ("1_20", "512", 8, "1_20 has digit separators (_), one number in YAML 1.1 only (120): write 120"),
        ("1_20.0", "512", 8, "write 120.0, not 1_20.0"),
    ],
)
def test_yaml_number_forms_read_differently_by_yaml_versions_are_refused(tmp_path, angle, ticks, line, message):
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text(angle, ticks))
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    text = str(info.value)
    assert text.startswith(f"{path}: line {line} column ") and message in text and "\n" not in text, text


@pytest.mark.parametrize("angle", ["120", "+120", "120.0", "0120.0", "1.2e2", "1.2E+2"])
def test_plain_decimal_numbers_read_as_written(tmp_path, angle):
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text(angle, "600"))
    b = load_robot(path).wheel("b")
    # 0.1 m at 120 deg: (-0.05, 0.1 sin 60 deg)
    assert b.x == pytest.approx(-0.05, abs=1e-15) and b.y == pytest.approx(0.1 * 3**0.5 / 2, abs=1e-15)
    assert b.encoder.ticks_per_rev == 600


def test_quoted_number_forms_stay_text_and_are_refused_as_such(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text("'0120'"))
    with pytest.raises(RobotFileError, match=r"field 'angle_deg': must be a number, got '0120'"):
        load_robot(path)


@pytest.mark.parametrize(
    "literal, message",
    [("0100", "write 100, not 0100"), ("1:40", "(100)"), ("0x64", "(100)"), ("1_00", "write 100, not 1_00")],
)
def test_ros_parameter_files_refuse_the_same_number_forms(tmp_path, literal, message):
    from omnikin.errors import InputError
    from omnikin.ros.params import load_params

    path = tmp_path / "params.yaml"
    path.write_text(f"omnikin:\n  ros__parameters:\n    publish_rate: {literal}\n")
    with pytest.raises(InputError) as info:
        load_params(path)
    text = str(info.value)
    assert text.startswith(f"{path}: line 3 column 19: ") and message in text, text
    path.write_text("omnikin:\n  ros__parameters:\n    publish_rate: 100\n")
    assert load_params(path)["publish_rate"] == 100


# --- explicit tags: refused, never handed to PyYAML's own readers --------------------------------
# PyYAML's int/float readers fail on each of these with a ValueError or IndexError, or read it past
# the number grammar (non-ASCII digits, blanks: 1.5): omnikin refuses the tag before they see it.
TAGGED = [
    "!!int 'abc'",
    "!!int ''",
    "!!float ''",
    "!!int '0:12'",
    "!!int '0x'",
    "!!float '0x10'",
    "!!float '\u0661.\u0665'",  # Arabic-Indic 1.5
    "!!float '\uff11.\uff15'",  # full-width 1.5
    "!!float '1.5 '",
    "!!int '\u0663'",
    "!!int '0o17'",
    "!!int 12",
    "!!float 1.5",
    "!!str 1.5",
    "!!bool yes",
    "!!timestamp 2001-01-01",
    "!!binary AAAA",
    "!!set {a}",
    "!!omap [a: 1]",
    "! 12",
]


@pytest.mark.parametrize("value", TAGGED)
def test_explicitly_tagged_values_are_refused_naming_the_line_and_column(tmp_path, value):
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text(angle=value))
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    text = str(info.value)
    tag = value.split()[0]
    # angle_deg of wheel b is on line 8, its value after "    angle_deg: " (14 characters)
    assert text.startswith(f"{path}: line 8 column 16: explicit tag '{tag}' not allowed"), text
    assert "\n" not in text and "write a number plain (1.5)" in text, text


def test_a_tagged_key_or_list_item_is_refused_too(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text().replace("    radius: 0.05\n", "    !!str radius: 0.05\n"))
    with pytest.raises(RobotFileError, match=r": line 9 column 5: explicit tag '!!str' not allowed"):
        load_robot(path)
    path.write_text(omni3_text().replace("references", "x") + "references: [a, !!str b]\n")
    with pytest.raises(RobotFileError, match=r": line 12 column 17: explicit tag '!!str' not allowed"):
        load_robot(path)


@pytest.mark.parametrize("literal, base", [("0x_", "hexadecimal"), ("-0b_", "binary")])
def test_yaml11_numbers_pyyaml_cannot_read_are_refused_as_such(tmp_path, literal, base):
    # YAML 1.1's integer pattern matches 0x_ and 0b_, but they hold no digit: no value to suggest
    # (the value on line 10 starts after "    encoder: {ticks_per_rev: ", 29 characters)
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text(ticks=literal))
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(info.value) == (
        f"{path}: line 10 column 30: {literal} is a {base} number in YAML 1.1, not a plain decimal: "
        "write a plain decimal number"
    )


def test_show_refuses_a_tagged_number_in_one_line_with_status_2(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text(omni3_text(ticks="!!int 'abc'"))
    p = subprocess.run(
        [sys.executable, "-m", "omnikin.cli.main", "show", str(path), "--json"],
        capture_output=True,
        text=True,
        env=omnikin_env(),
        timeout=120,
    )
    assert p.returncode == 2 and p.stdout == "", (p.returncode, p.stderr)
    assert p.stderr.splitlines() == [
        f"omnikin: error: {path}: line 10 column 30: explicit tag '!!int' not allowed: YAML readers "
        "disagree on tags (PyYAML reads !!float '1' as 1.0, ROS 2 as the text '1'): write a number "
        "plain (1.5), text in quotes"
    ]


@pytest.mark.parametrize("value", ["!!float 'x'", "!!float '1.5 '", "!!int '0x'"])
def test_ros_parameter_files_refuse_explicit_tags(tmp_path, value):
    from omnikin.errors import InputError
    from omnikin.ros.params import load_params

    path = tmp_path / "params.yaml"
    path.write_text(f"omnikin:\n  ros__parameters:\n    publish_rate: {value}\n")
    with pytest.raises(InputError) as info:
        load_params(path)
    text = str(info.value)
    assert text.startswith(f"{path}: line 3 column 19: explicit tag '{value.split()[0]}' not allowed"), text
