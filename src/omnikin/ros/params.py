"""Parameters of the ROS 2 node, named as in ros2_controllers where the meaning is the same.

| name | default | meaning |
|---|---|---|
| ``cmd_vel_timeout`` | 0.5 | s without a valid command before the robot brakes to a stop (0 disables) |
| ``publish_rate`` | 50.0 | Hz of the control loop: read wheels, odometry, command wheels, publish |
| ``odom_frame_id`` | ``odom`` | frame of the odometry pose |
| ``base_frame_id`` | ``base_link`` | body frame |
| ``enable_odom_tf`` | true | publish odom -> base_link on ``/tf`` (needs ``tf2_msgs``) |
| ``use_stamped_vel`` | false | subscribe ``geometry_msgs/TwistStamped`` instead of ``Twist`` |
| ``linear.x.max_velocity`` | 0.3 | m/s, bound on the body speed ``hypot(vx, vy)`` |
| ``linear.x.max_acceleration`` | 0.5 | m/s^2 |
| ``angular.z.max_velocity`` | 1.0 | rad/s |
| ``angular.z.max_acceleration`` | 2.0 | rad/s^2 |
| ``wheel_max_velocity`` | 0.0 | rad/s bound on every wheel (0: only the robot file's ``max_speed``) |
| ``wheel_slip`` | 2e-4 | sqrt(m), per-wheel slip intensity of the odometry covariance |
| ``reject_above`` | 100.0 | commands beyond this many times a limit are rejected as malformed |
| ``link_retry_period`` | 1.0 | s between attempts to re-arm a lost serial link (0: stay stopped) |

A ``--params FILE`` is YAML, either flat (``cmd_vel_timeout: 0.2``) or in the ROS layout
(``omnikin_base: {ros__parameters: {...}}``); unknown names are errors.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError

DEFAULTS = {
    "cmd_vel_timeout": 0.5,
    "publish_rate": 50.0,
    "odom_frame_id": "odom",
    "base_frame_id": "base_link",
    "enable_odom_tf": True,
    "use_stamped_vel": False,
    "linear.x.max_velocity": 0.3,
    "linear.x.max_acceleration": 0.5,
    "angular.z.max_velocity": 1.0,
    "angular.z.max_acceleration": 2.0,
    "wheel_max_velocity": 0.0,
    "wheel_slip": 2e-4,
    "reject_above": 100.0,
    "link_retry_period": 1.0,
}


def _flatten(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, key + "."))
        else:
            out[key] = v
    return out


def load_params(path: str | Path | None) -> dict:
    """Defaults updated by a parameter file (module docstring); every value type-checked."""
    values = dict(DEFAULTS)
    if path is None:
        return values
    import yaml

    from ..io.robot_file import strict_yaml_loader

    try:
        data = yaml.load(Path(path).read_text(encoding="utf-8-sig"), Loader=strict_yaml_loader()) or {}
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a UTF-8 text file (byte {exc.start}: {exc.reason})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1} column {mark.column + 1}" if mark is not None else ""
        raise InputError(f"{path}: invalid YAML{at}: {getattr(exc, 'problem', None) or 'syntax error'}") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a mapping of parameters")
    if len(data) == 1:
        (only,) = data.values()
        if isinstance(only, dict) and "ros__parameters" in only:
            data = only["ros__parameters"]
            if not isinstance(data, dict):
                raise InputError(f"{path}: ros__parameters must be a mapping of parameters, got {data!r}")
    flat = _flatten(data)
    for key, value in flat.items():
        if key not in DEFAULTS:
            raise InputError(f"{path}: unknown parameter {key!r}; known: {sorted(DEFAULTS)}")
        values[key] = value
    return validate(values, str(path))


RANGES = {
    "cmd_vel_timeout": (0.0, 3600.0, True),
    "publish_rate": (0.0, 10000.0, False),
    "linear.x.max_velocity": (0.0, 1e3, False),
    "linear.x.max_acceleration": (0.0, 1e4, False),
    "angular.z.max_velocity": (0.0, 1e3, False),
    "angular.z.max_acceleration": (0.0, 1e4, False),
    "wheel_max_velocity": (0.0, 1e5, True),
    "wheel_slip": (0.0, 1.0, True),
    "reject_above": (1.0, 1e9, True),
    "link_retry_period": (0.0, 3600.0, True),
}
"""Allowed ``(low, high, low_inclusive)`` of the numeric parameters."""


def validate(values: dict, source: str) -> dict:
    """Check types and ranges of every parameter; returns ``values`` with ints made floats.

    ``source`` names where the values came from (a file, or ``--ros-args``) in the error.
    """
    out = dict(values)
    for key, value in values.items():
        if key not in DEFAULTS:
            raise InputError(f"{source}: unknown parameter {key!r}; known: {sorted(DEFAULTS)}")
        want = type(DEFAULTS[key])
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, want):
            raise InputError(f"{source}: parameter {key!r} must be a {want.__name__}, got {value!r}")
        if key in RANGES:
            low, high, inclusive = RANGES[key]
            ok = math.isfinite(value) and value <= high and (value >= low if inclusive else value > low)
            if not ok:
                rel = ">=" if inclusive else ">"
                raise InputError(f"{source}: parameter {key!r} must be finite, {rel} {low:g} and <= {high:g}, "
                                   f"got {value!r}")
        out[key] = value
    return out
