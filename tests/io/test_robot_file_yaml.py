"""Robot files: duplicate keys refused (YAML and JSON), YAML 1.1 exponents read as numbers.

Regression tests of the review findings, grouped here by module. Expected values are derived
independently of the code under test (closed forms typed in from the geometry, least squares
computed with NumPy, or the batch odometry as reference for the streaming estimator).
"""

from __future__ import annotations

import pytest

from omnikin import (
    RobotFileError,
    load_robot,
)


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
