"""Robot files, schema version 1 (``docs/conventions.md``): YAML, JSON accepted.

Every problem is reported as :class:`~omnikin.errors.RobotFileError` naming the
file, the wheel and the field, in one line, quoting user values through
:func:`~omnikin.common.messages.shorten`, e.g.
``robot.yaml: wheel 'w2' (#2): field 'radius': must lie in [0.0001, 10] m, got -0.04``.
Degrees appear only in fields ending in ``_deg``; the loaded
:class:`~omnikin.kinematics.robot.Robot` holds radians.

Hostile files are refused before they cost time or memory (docs/conventions.md, "Robot
file"): only regular files up to 256 KiB are read (:mod:`omnikin.io.textfile`); the YAML
reader (:func:`strict_yaml_loader`, also used for ROS parameter files) refuses anchors,
aliases and merge keys (a 1 KB alias bomb would otherwise expand to gigabytes), explicit tags
(PyYAML reads ``!!float '1'`` as a number, ROS 2's parameter parser as text), nesting
deeper than :data:`MAX_DEPTH`, duplicate keys, over-long integer literals, and numbers that
YAML readers read differently (YAML 1.1, which PyYAML follows, reads ``0120`` as the octal 80,
``2:00`` as 120 and ``0x1``, ``0b1``, ``1_000`` as numbers; YAML 1.2 reads ``0120`` as 120 and
``2:00`` as text): a number in an omnikin file is a plain decimal as
:mod:`omnikin.common.number_text` spells it (ASCII digits), ``120`` not ``0120``. JSON
gets the same depth, key and integer checks (it has no other number forms).
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from typing import Any

from ..common.arrays import range_problem, whole_problem
from ..common.messages import did_you_mean, digits_apart, shorten
from ..common.number_text import PLAIN_NUMBER, PLAIN_NUMBER_HELP, number_problem
from ..errors import OmnikinError, PresetShadowWarning, RobotFileError
from ..kinematics.encoder import COUNTER_BITS_RANGE, GEAR_RATIO_RANGE, TICKS_PER_REV_RANGE, Encoder
from ..kinematics.physical import (
    COM_LIMIT,
    COM_Z_MIN,
    FRICTION_RANGE,
    HEIGHT_RANGE,
    MASS_RANGE,
    ROLLERS_RANGE,
    ROWS_RANGE,
    TORQUE_RANGE,
    WIDTH_RANGE,
    PhysicalBody,
    PhysicalWheel,
)
from ..kinematics.robot import Robot, name_collisions, robot_name_problem
from ..kinematics.se2 import MAX_DIRECTION_DEG
from ..kinematics.sensors import SENSOR_TYPES, Bumper, Imu, ImuAxes, Lidar, Mount
from ..kinematics.wheels import (
    MAX_SPEED_RANGE,
    MOTOR_TYPES,
    OFFSET_RANGE,
    POSITION_LIMIT,
    RADIUS_RANGE,
    ROLLER_LIMIT_DEG,
    SWEDISH_TYPES,
    WHEEL_TYPES,
    Steer,
    Wheel,
    motor_problem,
    name_problem,
)
from ..presets import PRESET_NAMES, preset_path
from .textfile import read_text

SCHEMA_VERSION = 1
TOP_KEYS = {
    "omnikin": True,
    "name": True,
    "description": False,
    "references": False,
    "physical": False,
    "wheels": True,
    "sensors": False,
}
WHEEL_KEYS = {
    "name",
    "type",
    "distance",
    "angle_deg",
    "x",
    "y",
    "drive_deg",
    "roller_deg",
    "radius",
    "encoder",
    "max_speed",
    "steer",
    "physical",
    "motor",
}
ENCODER_KEYS = {"ticks_per_rev", "gear_ratio", "invert", "counter_bits"}
STEER_KEYS = {"offset", "min_deg", "max_deg"}
PHYSICAL_WHEEL_KEYS = tuple(f.name for f in fields(PhysicalWheel))
"""Keys of a wheel's ``physical:`` mapping (docs/conventions.md, "Physical fields")."""
PHYSICAL_BODY_KEYS = tuple(f.name for f in fields(PhysicalBody))
"""Keys of the top-level ``physical:`` mapping (the chassis)."""

FIELD_RANGES: dict[str, tuple[float, float, str]] = {
    "x": (-POSITION_LIMIT, POSITION_LIMIT, "m"),
    "y": (-POSITION_LIMIT, POSITION_LIMIT, "m"),
    "distance": (0.0, POSITION_LIMIT, "m"),
    "angle_deg": (-MAX_DIRECTION_DEG, MAX_DIRECTION_DEG, "deg"),
    "drive_deg": (-MAX_DIRECTION_DEG, MAX_DIRECTION_DEG, "deg"),
    "roller_deg": (-ROLLER_LIMIT_DEG, ROLLER_LIMIT_DEG, "deg"),
    "radius": (*RADIUS_RANGE, "m"),
    "max_speed": (*MAX_SPEED_RANGE, "rad/s"),
    "encoder.ticks_per_rev": (*TICKS_PER_REV_RANGE, ""),
    "encoder.gear_ratio": (*GEAR_RATIO_RANGE, ""),
    "steer.offset": (*OFFSET_RANGE, "m"),
    "steer.min_deg": (-180.0, 180.0, "deg"),
    "steer.max_deg": (-180.0, 180.0, "deg"),
    "physical.width": (*WIDTH_RANGE, "m"),
    "physical.mass": (*MASS_RANGE, "kg"),
    "physical.friction": (*FRICTION_RANGE, ""),
    "physical.max_torque": (*TORQUE_RANGE, "N m"),
    "physical.height": (*HEIGHT_RANGE, "m"),
    "physical.com.x": (-COM_LIMIT, COM_LIMIT, "m"),
    "physical.com.y": (-COM_LIMIT, COM_LIMIT, "m"),
    "physical.com.z": (COM_Z_MIN, COM_LIMIT, "m"),
}
"""Allowed range of every numeric field (inclusive; docs/conventions.md gives the reasons)."""

WHOLE_RANGES: dict[str, tuple[int, int]] = {
    "encoder.counter_bits": COUNTER_BITS_RANGE,
    "physical.rollers": ROLLERS_RANGE,
    "physical.rows": ROWS_RANGE,
}
"""Allowed range of every field that holds a whole number (inclusive)."""

DEFAULT_DRIVE_DEG = {"mecanum": 0.0}
"""Drive direction of a wheel type when ``drive_deg`` is omitted [deg]; omni wheels take the
counter-clockwise tangent, every other type must give ``drive_deg`` (docs/conventions.md)."""

MAX_SENSORS = 32
"""Most sensors of a robot file."""

MAX_DEPTH = 32
"""Deepest nesting of mappings and lists in a robot or parameter file (a robot file needs 4)."""

MAX_INT_CHARS = 100
"""Longest integer literal read as an integer; longer decimal ones are read as floats (and
then refused by the range of their field), other long forms are errors."""


class _Where:
    """Formats error locations: file, wheel, field."""

    def __init__(self, source: str):
        self.source = source

    def error(self, msg: str, wheel: str | None = None, field: str | None = None) -> RobotFileError:
        parts = [self.source]
        if wheel is not None:
            parts.append(wheel)
        if field is not None:
            parts.append(f"field {field!r}")
        return RobotFileError(": ".join(parts) + ": " + msg)


def _number(where: _Where, value: Any, wheel: str | None, field: str) -> float:
    """``value`` as a float within ``FIELD_RANGES[field]``, else an error naming wheel and field."""
    problem = range_problem(value, *FIELD_RANGES[field])
    if problem:
        raise where.error(problem, wheel, field)
    return float(value)


def _whole(where: _Where, value: Any, wheel: str | None, field: str) -> int:
    """``value`` as an int within ``WHOLE_RANGES[field]``, else an error naming wheel and field."""
    problem = whole_problem(value, *WHOLE_RANGES[field])
    if problem:
        raise where.error(problem, wheel, field)
    return int(value)


def _check_keys(where: _Where, data: Mapping, allowed, wheel: str | None, field: str | None):
    """Refuse keys of ``data`` not in ``allowed``, suggesting the closest allowed key of the first."""
    unknown = sorted(set(map(str, data)) - set(allowed))
    if unknown:
        hint = did_you_mean(unknown[0], allowed) if len(unknown[0]) <= 100 else ""
        raise where.error(
            f"unknown key(s) {shorten(unknown)}; allowed: {sorted(allowed)}{hint}", wheel, field if field else None
        )


def _encoder(where: _Where, data: Any, wheel: str) -> Encoder:
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping with keys {sorted(ENCODER_KEYS)}, got {shorten(data)}", wheel, "encoder")
    _check_keys(where, data, ENCODER_KEYS, wheel, "encoder")
    if "ticks_per_rev" not in data:
        raise where.error("missing required key 'ticks_per_rev'", wheel, "encoder")
    tpr = _number(where, data["ticks_per_rev"], wheel, "encoder.ticks_per_rev")
    gear = _number(where, data.get("gear_ratio", 1.0), wheel, "encoder.gear_ratio")
    invert = data.get("invert", False)
    if not isinstance(invert, bool):
        raise where.error(f"must be true or false, got {shorten(invert)}", wheel, "encoder.invert")
    bits = _whole(where, data["counter_bits"], wheel, "encoder.counter_bits") if "counter_bits" in data else None
    return Encoder(tpr, gear, invert, bits)


def _steer(where: _Where, data: Any, wheel: str) -> Steer:
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping with keys {sorted(STEER_KEYS)}, got {shorten(data)}", wheel, "steer")
    _check_keys(where, data, STEER_KEYS, wheel, "steer")
    offset = _number(where, data.get("offset", 0.0), wheel, "steer.offset")
    lo = _number(where, data.get("min_deg", -180.0), wheel, "steer.min_deg")
    hi = _number(where, data.get("max_deg", 180.0), wheel, "steer.max_deg")
    if not lo < hi:
        p = digits_apart(lo, hi)
        raise where.error(f"need -180 <= min_deg < max_deg <= 180, got {lo:.{p}g} and {hi:.{p}g}", wheel, "steer")
    return Steer(offset, math.radians(lo), math.radians(hi))


def _physical_mapping(where: _Where, data: Any, keys: tuple[str, ...], wheel: str | None) -> Mapping:
    """``data``, a ``physical:`` mapping of some of ``keys``; an empty one (``physical:`` or
    ``physical: {}``, often a slip of indentation) is an error: leave the key out instead."""
    if data is None or (isinstance(data, Mapping) and not data):
        raise where.error(
            f"is empty: give some of {list(keys)}, or leave 'physical' out (the physics description "
            f"then derives every field from the layout)",
            wheel,
            "physical",
        )
    if not isinstance(data, Mapping):
        raise where.error(
            f"must be a mapping with some of the keys {list(keys)}, got {shorten(data)}", wheel, "physical"
        )
    _check_keys(where, data, keys, wheel, "physical")
    return data


def _physical_wheel(where: _Where, data: Any, wheel: str, kind: str) -> PhysicalWheel:
    """A wheel's ``physical:`` mapping (docs/conventions.md, "Physical fields"): each field in
    its range, rollers only on Swedish wheels, no motor torque on a (passive) castor."""
    data = _physical_mapping(where, data, PHYSICAL_WHEEL_KEYS, wheel)
    for key in ("rollers", "rows"):
        if key in data and kind not in SWEDISH_TYPES:
            raise where.error(
                f"only Swedish wheels (omni, mecanum, swedish) have rollers, not {kind!r}", wheel, f"physical.{key}"
            )
    if "max_torque" in data and kind == "castor":
        raise where.error("a castor is passive: it has no motor", wheel, "physical.max_torque")
    values: dict[str, Any] = {}
    for key in PHYSICAL_WHEEL_KEYS:
        if key in data:
            field = f"physical.{key}"
            check = _whole if field in WHOLE_RANGES else _number
            values[key] = check(where, data[key], wheel, field)
    return PhysicalWheel(**values)


def _physical_body(where: _Where, data: Any) -> PhysicalBody:
    """The top-level ``physical:`` mapping: chassis mass [kg], centre of mass ``com`` [x, y, z]
    [m] (body frame, z above the floor) and thickness ``height`` [m]."""
    data = _physical_mapping(where, data, PHYSICAL_BODY_KEYS, None)
    values: dict[str, Any] = {}
    for key in ("mass", "height"):
        if key in data:
            values[key] = _number(where, data[key], None, f"physical.{key}")
    if "com" in data:
        com = data["com"]
        if not isinstance(com, (list, tuple)) or len(com) != 3:
            raise where.error(f"must be a list of 3 numbers [x, y, z] in m, got {shorten(com)}", None, "physical.com")
        values["com"] = tuple(
            _number(where, v, None, f"physical.com.{axis}") for axis, v in zip("xyz", com, strict=True)
        )
    return PhysicalBody(**values)


def _placement(where: _Where, data: Mapping, label: str) -> tuple[float, float]:
    """Hub position ``(x, y)`` [m] from ``x``/``y`` or ``distance``/``angle_deg``."""
    polar = [k for k in ("distance", "angle_deg") if k in data]
    cart = [k for k in ("x", "y") if k in data]
    if polar and cart:
        raise where.error("give either distance/angle_deg or x/y, not both", label)
    if cart:
        if len(cart) != 2:
            raise where.error("Cartesian placement needs both 'x' and 'y'", label)
        return _number(where, data["x"], label, "x"), _number(where, data["y"], label, "y")
    if not polar:
        raise where.error("missing placement: give distance and angle_deg, or x and y", label)
    if len(polar) != 2:
        raise where.error("polar placement needs both 'distance' and 'angle_deg'", label)
    dist = _number(where, data["distance"], label, "distance")
    beta = math.radians(_number(where, data["angle_deg"], label, "angle_deg"))
    x, y = dist * math.cos(beta), dist * math.sin(beta)
    return (0.0 if abs(x) < 1e-15 * max(dist, 1) else x), (0.0 if abs(y) < 1e-15 * max(dist, 1) else y)


def _drive(where: _Where, data: Mapping, label: str, kind: str, x: float, y: float) -> float:
    """Drive direction [rad]: ``drive_deg``, else the default of the wheel type (docs/conventions.md):
    omni wheels the counter-clockwise tangent, mecanum wheels body +x; the other types must say."""
    if "drive_deg" in data:
        return math.radians(_number(where, data["drive_deg"], label, "drive_deg"))
    if kind in DEFAULT_DRIVE_DEG:
        return math.radians(DEFAULT_DRIVE_DEG[kind])
    if kind != "omni":
        raise where.error(
            f"required for a {kind} wheel: the direction its hub moves at positive wheel speed "
            f"and zero steering (0: along body +x, as on differential drives, cars and castors; "
            f"angle_deg + 90: the counter-clockwise tangent)",
            label,
            "drive_deg",
        )
    if x == 0.0 and y == 0.0:
        raise where.error("a wheel at the origin has no default drive direction: give drive_deg", label, "drive_deg")
    return math.atan2(y, x) + math.pi / 2


def _roller(where: _Where, data: Mapping, label: str, kind: str) -> float:
    """Roller angle gamma [rad] of a Swedish wheel (0 for every other wheel)."""
    if kind not in SWEDISH_TYPES:
        if "roller_deg" in data:
            raise where.error(
                f"only Swedish wheels (omni, mecanum, swedish) have rollers, not {kind!r}", label, "roller_deg"
            )
        return 0.0
    if kind == "omni":
        if "roller_deg" in data and _number(where, data["roller_deg"], label, "roller_deg") != 0.0:
            raise where.error(
                f"an omni wheel has roller_deg 0, got {shorten(data['roller_deg'])} "
                f"(use type 'swedish' for other roller angles)",
                label,
                "roller_deg",
            )
        return 0.0
    if "roller_deg" not in data:
        raise where.error(f"required for a {kind} wheel", label, "roller_deg")
    gamma = data["roller_deg"]
    if kind == "mecanum" and (isinstance(gamma, bool) or gamma not in (45, -45)):
        raise where.error(
            f"a mecanum wheel has roller_deg +45 or -45, got {shorten(gamma)} (use type 'swedish' for other angles)",
            label,
            "roller_deg",
        )
    return math.radians(_number(where, gamma, label, "roller_deg"))


def _wheel(where: _Where, data: Any, index: int) -> Wheel:
    label = f"wheel #{index}"
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping, got {shorten(data)}", label)
    if isinstance(data.get("name"), str) and data["name"]:
        label = f"wheel {shorten(data['name'])} (#{index})"
    _check_keys(where, data, WHEEL_KEYS, label, None)
    for key in ("name", "type", "radius"):
        if key not in data:
            raise where.error("missing required key", label, key)
    name, kind = data["name"], data["type"]
    problem = name_problem(name)
    if problem:
        raise where.error(problem, label, "name")
    if kind not in WHEEL_TYPES:
        raise where.error(f"unknown wheel type {shorten(kind)}; one of {list(WHEEL_TYPES)}", label, "type")
    x, y = _placement(where, data, label)
    drive = _drive(where, data, label, kind, x, y)
    radius = _number(where, data["radius"], label, "radius")
    roller = _roller(where, data, label, kind)

    steer = None
    if "steer" in data:
        if kind not in ("steerable", "castor"):
            raise where.error(f"only steerable wheels and castors have 'steer', not {kind!r}", label, "steer")
        steer = _steer(where, data["steer"], label)
    if kind == "castor" and (steer is None or steer.offset <= 0.0):
        raise where.error("a castor needs steer.offset > 0 (the trail behind its swivel axis)", label, "steer")
    if kind == "castor" and "encoder" in data:
        raise where.error("castors are passive and unmeasured in schema 1: remove 'encoder'", label, "encoder")
    encoder = _encoder(where, data["encoder"], label) if "encoder" in data else None
    max_speed = _number(where, data["max_speed"], label, "max_speed") if "max_speed" in data else None
    physical = _physical_wheel(where, data["physical"], label, kind) if "physical" in data else None
    motor = data.get("motor")
    if "motor" in data:
        problem = motor_problem(motor, kind, encoder is not None)
        if motor is None:
            problem = f"must be one of {', '.join(MOTOR_TYPES)}, got null (leave 'motor' out for the default)"
        if problem:
            raise where.error(problem, label, "motor")
    try:
        return Wheel(name, kind, x, y, drive, radius, roller, encoder, max_speed, steer, physical, motor)
    except OmnikinError as exc:  # a combination the file checks above do not see
        raise where.error(str(exc), label) from None


SENSOR_KEYS = {
    "imu": ("name", "type", "mount", "rate", "gyro", "accel"),
    "lidar": ("name", "type", "mount", "rate", "beams", "fov_deg", "range_min", "range_max", "range_noise", "dropout"),
    "bumper": ("name", "type", "arc_deg"),
}
"""Keys of a sensor of each type (docs/sensors.md)."""
MOUNT_KEYS = ("x", "y", "z", "yaw_deg")
IMU_AXES_KEYS = ("noise_density", "bias", "bias_walk", "scale", "misalignment_deg")


def _sensor(where: _Where, data: Any, index: int):
    """Sensor ``index`` (1-based) of the ``sensors:`` list: its keys and types here, its values by
    the sensor's own checks (:mod:`omnikin.kinematics.sensors`), each problem naming the sensor."""
    label = f"sensor #{index}"
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping, got {shorten(data)}", label)
    if isinstance(data.get("name"), str) and data["name"]:
        label = f"sensor {shorten(data['name'])} (#{index})"
    for key in ("name", "type"):
        if key not in data:
            raise where.error("missing required key", label, key)
    kind = data["type"]
    if kind not in SENSOR_TYPES:
        hint = did_you_mean(str(kind), SENSOR_TYPES) if isinstance(kind, str) and len(kind) <= 100 else ""
        raise where.error(f"unknown sensor type {shorten(kind)}; one of {list(SENSOR_TYPES)}{hint}", label, "type")
    _check_keys(where, data, SENSOR_KEYS[kind], label, None)

    def degrees(value, field: str) -> float:
        problem = range_problem(value, -MAX_DIRECTION_DEG, MAX_DIRECTION_DEG, "deg")
        if problem:
            raise where.error(problem, label, field)
        return math.radians(float(value))

    def mapping(value, keys, field: str) -> Mapping:
        if not isinstance(value, Mapping):
            raise where.error(
                f"must be a mapping with some of the keys {list(keys)}, got {shorten(value)}", label, field
            )
        _check_keys(where, value, keys, label, field)
        return value

    try:
        if kind == "bumper":
            arc = data.get("arc_deg", [-180, 180])
            if not isinstance(arc, list) or len(arc) != 2:
                raise where.error(f"must be [low, high] in deg, got {shorten(arc)}", label, "arc_deg")
            return Bumper(data["name"], (degrees(arc[0], "arc_deg"), degrees(arc[1], "arc_deg")))
        given = mapping(data.get("mount", {}), MOUNT_KEYS, "mount")
        mount = Mount(
            given.get("x", 0.0),
            given.get("y", 0.0),
            given.get("z", 0.0),
            degrees(given.get("yaw_deg", 0.0), "mount.yaw_deg"),
        )
        if kind == "imu":
            triads = {}
            for field in ("gyro", "accel"):
                axes = mapping(data.get(field, {}), IMU_AXES_KEYS, field)
                values = {k: axes[k] for k in IMU_AXES_KEYS[:-1] if k in axes}
                if "misalignment_deg" in axes:
                    values["misalignment"] = degrees(axes["misalignment_deg"], f"{field}.misalignment_deg")
                triads[field] = ImuAxes(**values)
            return Imu(data["name"], mount, data.get("rate", 100.0), triads["gyro"], triads["accel"])
        options = {
            k: data[k] for k in ("rate", "beams", "range_min", "range_max", "range_noise", "dropout") if k in data
        }
        if "fov_deg" in data:
            options["fov"] = degrees(data["fov_deg"], "fov_deg")
        return Lidar(data["name"], mount, **options)
    except RobotFileError:
        raise
    except OmnikinError as exc:
        raise where.error(str(exc).removeprefix(f"sensor {data['name']!r}: "), label) from None


def robot_from_dict(data: Any, source: str = "<robot>") -> Robot:
    """Validate a schema-1 mapping and build the :class:`Robot` it describes."""
    where = _Where(source)
    if not isinstance(data, Mapping):
        raise where.error(f"a robot file must be a mapping at top level, got {type(data).__name__}")
    _check_keys(where, data, TOP_KEYS, None, None)
    for key, required in TOP_KEYS.items():
        if required and key not in data:
            raise where.error("missing required key", None, key)
    if data["omnikin"] != SCHEMA_VERSION or isinstance(data["omnikin"], bool):
        raise where.error(
            f"unsupported schema version {shorten(data['omnikin'])}; this omnikin reads version {SCHEMA_VERSION}",
            None,
            "omnikin",
        )
    name = data["name"]
    problem = robot_name_problem(name)
    if problem:
        raise where.error(problem, None, "name")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise where.error(f"must be a string, got {shorten(description)}", None, "description")
    refs = data.get("references", [])
    if not isinstance(refs, list) or not all(isinstance(r, str) for r in refs):
        raise where.error(f"must be a list of strings, got {shorten(refs)}", None, "references")
    physical = _physical_body(where, data["physical"]) if "physical" in data else None
    wheels = data["wheels"]
    if not isinstance(wheels, list) or not wheels:
        raise where.error(f"must be a non-empty list of wheels, got {shorten(wheels)}", None, "wheels")
    parsed = [_wheel(where, w, i + 1) for i, w in enumerate(wheels)]
    for i, problem in name_collisions([w.name for w in parsed]):
        raise where.error(problem, f"wheel {shorten(parsed[i].name)} (#{i + 1})", "name")
    sensors = data.get("sensors", [])
    if not isinstance(sensors, list) or len(sensors) > MAX_SENSORS:
        raise where.error(f"must be a list of at most {MAX_SENSORS} sensors, got {shorten(sensors)}", None, "sensors")
    fitted = [_sensor(where, item, i + 1) for i, item in enumerate(sensors)]
    try:
        return Robot(name, tuple(parsed), description, tuple(refs), physical, sensors=tuple(fitted))
    except OmnikinError as exc:
        raise RobotFileError(f"{source}: {exc}") from None


# --- reading YAML and JSON safely ---------------------------------------------------------------
_EXPONENT = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+")
"""Floats YAML 1.1 reads as strings (``5e-2``: no dot) but YAML 1.2 and JSON as numbers. Written
without nested repetition so that a long hostile scalar is matched in linear time."""

_NO_ALIASES = (
    "anchors (&name) and aliases (*name) are not allowed in omnikin files (a 1 KB alias bomb "
    "expands to gigabytes): write the values out"
)


def strict_yaml_loader():
    """A PyYAML SafeLoader for robot and parameter files (module docstring).

    Refuses, with the line and column: anchors and aliases, merge keys (``<<``), explicit tags
    (``!!float '1'``: :data:`_NO_TAGS`), nesting deeper than :data:`MAX_DEPTH`, keys that are not
    scalars, duplicate keys, the YAML 1.1 booleans ``yes``/``no``/``on``/``off`` (text in YAML
    1.2: only ``true`` and ``false`` are booleans), and the YAML 1.1 number forms other readers
    read differently (octal ``0120``, base-60 ``2:00`` and ``1:30.5``, hexadecimal ``0x1``, binary ``0b1``, digit
    separators ``1_000``; the message gives the plain decimal to write). A number is accepted
    only as the one number grammar spells it (:data:`omnikin.common.number_text.PLAIN_NUMBER`; a whole
    number as a plain decimal without leading zeros), besides YAML's ``.inf`` and ``.nan``, which
    the range of their field refuses by name. Reads ``5e-2`` as a float (YAML 1.2); a plain
    decimal integer of more than :data:`MAX_INT_CHARS` digits as a float (refused by the range of
    its field). ROS 2's own parameter parser (rcl_yaml_param_parser) refuses aliases too.
    """
    import yaml
    from yaml.composer import ComposerError
    from yaml.constructor import ConstructorError

    class StrictLoader(yaml.SafeLoader):
        depth = 0

        def compose_node(self, parent, index):
            event = self.peek_event()
            if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None) is not None:
                raise ComposerError(None, None, _NO_ALIASES, event.start_mark)
            tag = getattr(event, "tag", None)
            if tag is not None:
                raise _RefusedYaml(_tag_problem(tag), event.start_mark)
            if self.depth >= MAX_DEPTH:
                raise ComposerError(None, None, f"nested deeper than {MAX_DEPTH} levels", event.start_mark)
            self.depth += 1
            try:
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

    def mapping(loader, node, deep=False):
        keys = set()
        for key_node, _ in node.value:
            mark = key_node.start_mark
            if key_node.tag == "tag:yaml.org,2002:merge":
                raise ConstructorError(None, None, "merge keys (<<) are not allowed: write the keys out", mark)
            if not isinstance(key_node, yaml.ScalarNode):
                raise ConstructorError(None, None, "a key must be a plain value, not a list or mapping", mark)
            key = loader.construct_object(key_node, deep=deep)
            if key in keys:
                raise ConstructorError(None, None, f"duplicate key {shorten(key)}", mark)
            keys.add(key)
        return loader.construct_mapping(node, deep=deep)

    def scalar(loader, node):
        value = loader.construct_scalar(node)
        if node.style is None and len(value) <= MAX_INT_CHARS and _EXPONENT.fullmatch(value):
            return float(value)
        return value

    def yaml11_value(loader, node):
        """What YAML 1.1 (PyYAML) reads the number ``node`` as, for the hint; None where it fails
        (``0x_`` is a YAML 1.1 integer that PyYAML cannot convert) or the text is too long."""
        convert = yaml.SafeLoader.construct_yaml_int if "int" in node.tag else yaml.SafeLoader.construct_yaml_float
        if len(node.value) > MAX_INT_CHARS:
            return None
        try:
            return convert(loader, node)
        except (ValueError, IndexError):
            return None

    def integer(loader, node):
        text = loader.construct_scalar(node)
        if not _DECIMAL_INT.fullmatch(text):
            raise _RefusedYaml(_number_form_problem(text, yaml11_value(loader, node)), node.start_mark)
        if len(text) <= MAX_INT_CHARS:
            return int(text)
        return float(text)  # inf or a huge float: refused by the range of its field

    def real(loader, node):
        text = loader.construct_scalar(node)
        if _YAML_NON_FINITE.fullmatch(text):
            return yaml.SafeLoader.construct_yaml_float(loader, node)  # refused by its field's range
        if not PLAIN_NUMBER.fullmatch(text):
            raise _RefusedYaml(_number_form_problem(text, yaml11_value(loader, node)), node.start_mark)
        return float(text)

    def boolean(loader, node):
        text = loader.construct_scalar(node)
        if text.lower() not in ("true", "false"):
            raise _RefusedYaml(
                f"{shorten(text)} is a boolean in YAML 1.1 but text in YAML 1.2: write true or false, "
                "or quote it for the text",
                node.start_mark,
            )
        return text.lower() == "true"

    StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, mapping)
    StrictLoader.add_constructor("tag:yaml.org,2002:bool", boolean)
    StrictLoader.add_constructor("tag:yaml.org,2002:str", scalar)
    StrictLoader.add_constructor("tag:yaml.org,2002:int", integer)
    StrictLoader.add_constructor("tag:yaml.org,2002:float", real)
    return StrictLoader


_DECIMAL_INT = re.compile(r"[-+]?(?:0|[1-9][0-9]*)")
"""The integers every reader reads alike (YAML 1.1 and 1.2, JSON): plain decimal, no leading zero."""

_YAML_NON_FINITE = re.compile(r"[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN)")
"""YAML's spellings of infinity and NaN: read as floats, then refused by the range of the field
they stand in, which names it."""

_NO_TAGS = (
    "YAML readers disagree on tags (PyYAML reads !!float '1' as 1.0, ROS 2 as the text '1'): "
    "write a number plain (1.5), text in quotes"
)


def _tag_problem(tag: str) -> str:
    """Why the explicit tag ``tag`` (as PyYAML resolves it) is refused, naming it as written."""
    shown = "!!" + tag.removeprefix("tag:yaml.org,2002:") if tag.startswith("tag:yaml.org,2002:") else tag
    return f"explicit tag {shorten(shown)} not allowed: {_NO_TAGS}"


def _number_form_problem(text: str, value) -> str:
    """Why the YAML 1.1 number ``text`` is refused (:func:`strict_yaml_loader`), with the plain
    decimal to write instead; ``value`` is what YAML 1.1 (PyYAML) reads, None if not computed."""
    body = text.lstrip("+-").lower()
    digits = body.replace("_", "")
    sign = text[:1] if text[:1] in ("+", "-") else ""
    if len(text) > 40:  # a hostile literal: named by its start, no value quoted
        text, value = f"{text[:24]}... ({len(text)} characters)", None
    read = "" if value is None else f" ({value!r})"
    instead = f"write {value!r}, not {text}" if value is not None else "write a plain decimal number"
    if digits.startswith(("0x", "0b")):
        base = "hexadecimal" if digits.startswith("0x") else "binary"
        return f"{text} is a {base} number in YAML 1.1{read}, not a plain decimal: {instead}"
    if ":" in body:
        return f"{text} is a base-60 (sexagesimal) number in YAML 1.1{read} but text in YAML 1.2: {instead}"
    if len(digits) > 1 and digits[0] == "0" and digits[1].isdigit():
        plain = sign + (digits.lstrip("0") or "0")
        instead = f"write {plain}, not {text}" if value is not None else "write it without leading zeros"
        return f"{text} is octal in YAML 1.1{read} but decimal in YAML 1.2: {instead}"
    if "_" in body:
        return f"{text} has digit separators (_), one number in YAML 1.1 only{read}: {instead}"
    return number_problem(text) or f"{shorten(text)} is not a plain decimal number ({PLAIN_NUMBER_HELP})"


class _RefusedYaml(Exception):
    """Valid YAML that omnikin refuses: an explicit tag, or a number written in a YAML 1.1 form that
    other readers read differently (raised out of the loader; :func:`parse_yaml` names the file,
    line and column)."""

    def __init__(self, problem: str, mark):
        super().__init__(problem)
        self.problem = problem
        self.mark = mark


def parse_yaml(text: str, source: str, error: type[Exception] = RobotFileError) -> Any:
    """The data of a YAML document read with :func:`strict_yaml_loader` (None if empty); every
    problem raises ``error`` naming ``source``, the line and the column."""
    return parse_yaml_lines(text, source, error)[0]


def parse_yaml_lines(
    text: str, source: str, error: type[Exception] = RobotFileError
) -> tuple[Any, dict[tuple[Any, ...], int]]:
    """:func:`parse_yaml`, and the 1-based line where each value of the document starts, keyed by
    its path (``("walls", 0, "thickness")``: mapping keys as written, list indices from 0; ``()``
    the document)."""
    import yaml

    try:
        loader = strict_yaml_loader()(text)
        try:
            node = loader.get_single_node()
            data = loader.construct_document(node) if node is not None else None
        finally:
            loader.dispose()
        lines: dict[tuple[Any, ...], int] = {}
        if node is not None:
            _node_lines(node, (), lines)
        return data, lines
    except _RefusedYaml as exc:
        raise error(f"{source}: line {exc.mark.line + 1} column {exc.mark.column + 1}: {exc.problem}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1} column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise error(f"{source}: invalid YAML{at}: {problem}") from None


def _node_lines(node, path: tuple[Any, ...], lines: dict[tuple[Any, ...], int]) -> None:
    """Record the line of ``node`` at ``path`` and of everything below it (iteratively deep:
    the loader already bounds the nesting)."""
    import yaml

    stack = [(node, path)]
    while stack:
        item, where = stack.pop()
        lines[where] = item.start_mark.line + 1
        if isinstance(item, yaml.MappingNode):
            for key, value in item.value:
                stack.append((value, (*where, key.value)))
        elif isinstance(item, yaml.SequenceNode):
            for i, value in enumerate(item.value):
                stack.append((value, (*where, i)))


def load_yaml_file(path: str | Path, error: type[Exception], what: str = "a YAML file") -> Any:
    """Read and parse a small YAML file (robot or ROS parameter file) with every check above."""
    return parse_yaml(read_text(path, error, what=what), str(path), error)


_JSON_TOKENS = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}]', re.DOTALL)


def _json_depth_check(text: str, source: str) -> None:
    """Refuse JSON nested deeper than :data:`MAX_DEPTH` before the (recursive) decoder sees it."""
    depth = 0
    for m in _JSON_TOKENS.finditer(text):
        token = m.group()
        if token in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                line = text.count("\n", 0, m.start()) + 1
                raise RobotFileError(f"{source}: invalid JSON at line {line}: nested deeper than {MAX_DEPTH} levels")
        elif token in "]}":
            depth -= 1


def _json_int(text: str) -> int | float:
    """JSON integers: exact up to :data:`MAX_INT_CHARS` digits, longer ones as floats (then refused
    by the range of their field) instead of Python's ``int`` digit-limit ValueError."""
    return int(text) if len(text) <= MAX_INT_CHARS else float(text)


def _unique_json_keys(source: str):
    def hook(pairs):
        seen: set = set()
        for key, _ in pairs:
            if key in seen:
                raise RobotFileError(f"{source}: duplicate key {shorten(key)}")
            seen.add(key)
        return dict(pairs)

    return hook


def parse_robot_text(text: str, source: str) -> Robot:
    """Parse YAML or JSON text (JSON is YAML 1.2 too; tried first when it looks like JSON)."""
    if text.lstrip().startswith("{"):
        _json_depth_check(text, source)
        try:
            data = json.loads(text, object_pairs_hook=_unique_json_keys(source), parse_int=_json_int)
        except json.JSONDecodeError as exc:
            raise RobotFileError(f"{source}: invalid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}") from None
    else:
        data = parse_yaml(text, source)
    return robot_from_dict(data, source)


ROBOT_FILE_SUFFIXES = (".yaml", ".yml", ".json")
"""Endings of robot file names (any other name is read as a robot file too when it is not a preset)."""


def is_preset_spec(spec) -> bool:
    """Whether the robot specification ``spec`` names a preset: a string equal to a preset name
    (``omnikin presets``), whatever exists in the current folder. Anything else is the path of
    a robot file: a string that is no preset name (``./omni4``, ``robots/omni4``,
    ``omni4.yaml``) or a :class:`os.PathLike` (``Path("omni4")``). docs/conventions.md, "Naming
    a robot"."""
    return isinstance(spec, str) and spec in PRESET_NAMES


def robot_file_of(spec) -> str | None:
    """The path of the robot file ``spec`` names, or None when it names a preset
    (:func:`is_preset_spec`); for the inputs a command must not overwrite."""
    if spec is None or is_preset_spec(spec):
        return None
    return os.fspath(spec) if isinstance(spec, os.PathLike) else str(spec)


def load_preset(name: str) -> Robot:
    """The preset ``name`` from the files shipped with omnikin (never a file of the current folder)."""
    path = preset_path(name)
    return parse_robot_text(read_text(path, RobotFileError, what="a robot file"), path.name)


def load_robot(spec: str | Path) -> Robot:
    """Load a robot from a preset name (``omnikin presets`` lists them) or a robot file path.

    The rule (:func:`is_preset_spec`): a preset name given as a string always means the shipped
    preset; to load a file or folder of the current folder that has a preset's name, write it as
    a path (``./omni4``). When a preset name is also a file or folder in the current folder, a
    :class:`PresetShadowWarning` says so (the command line prints it as one line on stderr).
    Only a regular file of at most 256 KiB is read (:func:`omnikin.io.textfile.read_text`): a
    directory, device, FIFO, binary or non-UTF-8 file is an error naming it.
    """
    if is_preset_spec(spec):
        name = str(spec)
        if os.path.lexists(name):
            import warnings

            kind = "folder" if os.path.isdir(name) else "file"
            warnings.warn(
                f"{name!r} is the preset {name}, not the {kind} {name!r} in the current folder "
                f"(write ./{name} to load that {kind})",
                PresetShadowWarning,
                stacklevel=1,  # one location: the default filter shows it once per process
            )
        return load_preset(name)
    spec_str = robot_file_of(spec) or ""
    if not os.path.lexists(spec_str):  # False, not an OSError, for a name too long or with NUL
        raise RobotFileError(
            f"{shorten(spec_str, 1000)}: no such robot file or preset"
            f"{did_you_mean(spec_str, PRESET_NAMES)}; presets: {', '.join(PRESET_NAMES)}"
        )
    return parse_robot_text(read_text(spec_str, RobotFileError, what="a robot file"), spec_str)


def _clean(x: float) -> float:
    return float(round(float(x), 12))


def _count(x) -> int | float:
    """A count that may be fractional (ticks per revolution): an int when whole, so that a file
    saying 512 is written back as 512, not 512.0; else a float."""
    x = float(x)
    return int(x) if x.is_integer() else x


def robot_to_dict(robot: Robot) -> dict:
    """Schema-1 mapping of ``robot`` (Cartesian placement, explicit drive_deg). A robot as built
    is written as the robot it is: its design (:attr:`omnikin.kinematics.robot.Robot.design`) is not part
    of a robot file."""
    wheels = []
    for w in robot.wheels:
        d: dict[str, Any] = {
            "name": w.name,
            "type": w.type,
            "x": _clean(w.x),
            "y": _clean(w.y),
            "drive_deg": _clean(math.degrees(w.drive)),
        }
        if w.type in ("mecanum", "swedish"):
            d["roller_deg"] = _clean(math.degrees(w.roller))
        d["radius"] = float(w.radius)
        if w.encoder is not None:
            d["encoder"] = {
                "ticks_per_rev": _count(w.encoder.ticks_per_rev),
                "gear_ratio": float(w.encoder.gear_ratio),
                "invert": bool(w.encoder.invert),
            }
            if w.encoder.counter_bits is not None:
                d["encoder"]["counter_bits"] = int(w.encoder.counter_bits)
        if w.max_speed is not None:
            d["max_speed"] = float(w.max_speed)
        if w.steer is not None:
            d["steer"] = {
                "offset": float(w.steer.offset),
                "min_deg": _clean(math.degrees(w.steer.lower)),
                "max_deg": _clean(math.degrees(w.steer.upper)),
            }
        if w.physical is not None and w.physical.given:
            d["physical"] = physical_to_dict(w.physical)
        if w.motor is not None:
            d["motor"] = w.motor
        wheels.append(d)
    out: dict[str, Any] = {
        "omnikin": SCHEMA_VERSION,
        "name": robot.name,
        "description": robot.description,
        "references": list(robot.references),
    }
    if robot.physical is not None and robot.physical.given:
        out["physical"] = physical_to_dict(robot.physical)
    out["wheels"] = wheels
    if robot.sensors:
        out["sensors"] = [sensor_to_dict(sensor) for sensor in robot.sensors]
    return out


def sensor_to_dict(sensor) -> dict[str, Any]:
    """The ``sensors:`` entry of ``sensor`` (degrees where the file has them)."""
    out: dict[str, Any] = {"name": sensor.name, "type": sensor.type}
    if isinstance(sensor, Bumper):
        out["arc_deg"] = [_clean(math.degrees(a)) for a in sensor.arc]
        return out
    m = sensor.mount
    out["mount"] = {"x": m.x, "y": m.y, "z": m.z, "yaw_deg": _clean(math.degrees(m.yaw))}
    out["rate"] = sensor.rate
    if isinstance(sensor, Imu):
        for field in ("gyro", "accel"):
            axes = getattr(sensor, field)
            out[field] = {
                "noise_density": axes.noise_density,
                "bias": axes.bias,
                "bias_walk": axes.bias_walk,
                "scale": axes.scale,
                "misalignment_deg": _clean(math.degrees(axes.misalignment)),
            }
        return out
    out.update(
        beams=sensor.beams,
        fov_deg=_clean(math.degrees(sensor.fov)),
        range_min=sensor.range_min,
        range_max=sensor.range_max,
        range_noise=sensor.range_noise,
        dropout=sensor.dropout,
    )
    return out


def physical_to_dict(physical: PhysicalWheel | PhysicalBody) -> dict[str, Any]:
    """The ``physical:`` mapping of a wheel or the chassis: the fields given (a field left out is
    derived by the physics description), as plain ints, floats and lists."""
    out: dict[str, Any] = {}
    for key, value in physical.given.items():
        if key in ("rollers", "rows"):
            out[key] = int(value)
        elif key == "com":
            out[key] = [float(v) for v in value]
        else:
            out[key] = float(value)
    return out


def robot_text(robot: Robot, path: str | Path) -> str:
    """``robot`` as the text of a robot file named ``path``: strict JSON for ``.json``, else YAML."""
    data = robot_to_dict(robot)
    if Path(path).suffix.lower() == ".json":
        from .jsonfile import to_json

        return to_json(data) + "\n"
    import yaml

    return yaml.safe_dump(data, sort_keys=False)


def save_robot(robot: Robot, path: str | Path) -> None:
    """Write ``robot`` as YAML (``.yaml``/``.yml``) or strict JSON (``.json``), atomically.

    Whether ``path`` may be written (it exists, it is an input) is the caller's check
    (:func:`omnikin.io.output.check_output`); this only guarantees no half-written file.
    """
    from .output import write_text

    write_text(path, robot_text(robot, path))
