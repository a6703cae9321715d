"""``omnikin show --json`` carries every field a robot file can hold, as the file gives it.

The expectation is the written file itself, read back with PyYAML's own safe loader; the file is
checked to use every key of the schema, so a field added to robot files without reaching
``show --json`` fails here.
"""

from __future__ import annotations

import json
import math

import pytest
import yaml

from omnikin.io.robot_file import (
    ENCODER_KEYS,
    IMU_AXES_KEYS,
    MOUNT_KEYS,
    PHYSICAL_BODY_KEYS,
    PHYSICAL_WHEEL_KEYS,
    SENSOR_KEYS,
    STEER_KEYS,
    TOP_KEYS,
    WHEEL_KEYS,
)
from support.cli import run_cli as cli

# Three wheels 0.2 m from the centre: a Swedish wheel placed by x, y; a steerable wheel placed by
# distance and angle; an omni wheel. Whole numbers only in the fields that hold counts.
ROBOT = """\
omnikin: 1
name: every-field
description: a robot file that uses every key of the schema
references: [Campion, Bastin and d'Andrea-Novel 1996]
physical: {mass: 2.5, com: [0.01, -0.02, 0.06], height: 0.02}
wheels:
  - name: s
    type: swedish
    x: 0.2
    y: 0.0
    drive_deg: 90.0
    roller_deg: 30.0
    radius: 0.05
    encoder: {ticks_per_rev: 512, gear_ratio: 19.2, invert: true, counter_bits: 16}
    max_speed: 30.0
    motor: dc
    physical: {width: 0.03, mass: 0.12, rollers: 12, rows: 2, friction: 0.8, max_torque: 0.4}
  - name: st
    type: steerable
    distance: 0.2
    angle_deg: 120.0
    drive_deg: 210.0
    radius: 0.04
    encoder: {ticks_per_rev: 1000, gear_ratio: 1.0, invert: false}
    steer: {offset: 0.02, min_deg: -90.0, max_deg: 90.0}
  - {name: o, type: omni, distance: 0.2, angle_deg: 240.0, radius: 0.05}
sensors:
  - name: imu
    type: imu
    mount: {x: 0.01, y: -0.02, z: 0.06, yaw_deg: 90.0}
    rate: 200.0
    gyro: {noise_density: 0.000087, bias: 0.005, bias_walk: 0.00004, scale: 0.01, misalignment_deg: 0.5}
    accel: {noise_density: 0.0039, bias: 0.05, bias_walk: 0.0006, scale: 0.01, misalignment_deg: 0.5}
  - name: laser
    type: lidar
    mount: {x: 0.0, y: 0.0, z: 0.12, yaw_deg: 0.0}
    rate: 10.0
    beams: 360
    fov_deg: 270.0
    range_min: 0.15
    range_max: 12.0
    range_noise: 0.01
    dropout: 0.01
  - {name: front, type: bumper, arc_deg: [-60.0, 60.0]}
"""

NESTED = {"encoder": ENCODER_KEYS, "steer": STEER_KEYS, "physical": set(PHYSICAL_WHEEL_KEYS)}


def leaves(value, path=()):
    """``(path of keys, value)`` of every leaf of a mapping (lists are leaves)."""
    if isinstance(value, dict):
        for key, item in value.items():
            yield from leaves(item, (*path, key))
    else:
        yield path, value


def test_the_robot_file_uses_every_key_of_the_schema():
    doc = yaml.safe_load(ROBOT)
    assert set(doc) == set(TOP_KEYS) and set(doc["physical"]) == set(PHYSICAL_BODY_KEYS)
    assert set().union(*doc["wheels"]) == WHEEL_KEYS
    for key, schema in NESTED.items():
        assert set().union(*(w[key] for w in doc["wheels"] if key in w)) == schema, key
    sensors = {s["type"]: s for s in doc["sensors"]}
    assert set(sensors) == set(SENSOR_KEYS)
    for kind, keys in SENSOR_KEYS.items():
        assert set(sensors[kind]) == set(keys), kind
    assert set(sensors["imu"]["mount"]) == set(MOUNT_KEYS)
    assert set(sensors["imu"]["gyro"]) == set(sensors["imu"]["accel"]) == set(IMU_AXES_KEYS)


def test_show_json_carries_every_field_of_the_robot_file_as_written(capsys, tmp_path):
    path = tmp_path / "every-field.yaml"
    path.write_text(ROBOT, encoding="utf-8")
    rc, out, err = cli(capsys, "show", path, "--json")
    assert rc == 0 and err == "", err
    shown = json.loads(out)
    expected = yaml.safe_load(ROBOT)
    del expected["omnikin"]  # the schema version: a file's, not the robot's
    wheels = expected.pop("wheels")
    cases = list(leaves(expected)) + [(("wheels", i, *p), v) for i, w in enumerate(wheels) for p, v in leaves(w)]
    for keys, want in cases:
        got = shown
        for key in keys:
            assert key in got if isinstance(got, dict) else key < len(got), (keys, "missing")
            got = got[key]
        # same JSON type (512 stays a whole number, not 512.0) and the same value; a placement
        # angle the same modulo 360 deg (240 is shown as -120)
        assert type(got) is type(want), (keys, got, want)
        if isinstance(want, (str, bool, list)):
            assert got == want, keys
        elif keys[-1] in ("angle_deg", "drive_deg"):
            assert math.remainder(got - want, 360.0) == pytest.approx(0.0, abs=1e-9), (keys, got, want)
        else:
            assert got == pytest.approx(want, rel=1e-12), (keys, got, want)
