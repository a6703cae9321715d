"""Parameters of the ROS 2 node, named as in ros2_controllers where the meaning is the same.

| name | default | meaning |
|---|---|---|
| ``cmd_vel_timeout`` | 0.5 | s without a valid command before the robot brakes to a stop (0 disables) |
| ``publish_rate`` | 50.0 | Hz of the control loop: read wheels, odometry, command wheels, publish |
| ``odom_frame_id`` | ``odom`` | frame of the odometry pose |
| ``base_frame_id`` | ``base_link`` | body frame |
| ``enable_odom_tf`` | true | publish odom -> base_link on ``/tf`` (needs ``tf2_msgs``) |
| ``link_tf_rate`` | 30.0 | Hz (at most) of the robot's links on ``/tf`` for rviz2 (0: none; needs ``tf2_msgs``) |
| ``use_stamped_vel`` | false | subscribe ``geometry_msgs/TwistStamped`` instead of ``Twist`` (timed from its stamp) |
| ``linear.x.max_velocity`` | 0.3 | m/s, bound on the body speed ``hypot(vx, vy)`` |
| ``linear.x.max_acceleration`` | 0.5 | m/s^2 |
| ``angular.z.max_velocity`` | 1.0 | rad/s |
| ``angular.z.max_acceleration`` | 2.0 | rad/s^2 |
| ``wheel_max_velocity`` | 0.0 | rad/s bound on every wheel (0: only the robot file's ``max_speed``) |
| ``wheel_slip`` | 2e-4 | sqrt(m), per-wheel slip intensity of the odometry covariance |
| ``reject_above`` | 100.0 | commands beyond this many times a limit are rejected as malformed |
| ``link_retry_period`` | 1.0 | s between attempts to re-arm a lost serial link (0: stay stopped) |
| ``path_controller`` | ``auto`` | a path's controller: feedback, mpc, pursuit, or auto (by layout, as track) |
| ``path_heading`` | ``given`` | a path's heading: given (its poses'), tangent, fixed, free (fixed wheels: tangent) |
| ``path_smooth`` | true | a smooth curve through a path's poses (a planner's dense path); false: straight segments |
| ``path_blend`` | 0.0 | m, radius of the arcs that cut the corners of a path that is not smooth (0: stop at them) |

A ``--params FILE`` is YAML (read with :func:`omnikin.io.robot_file.strict_yaml_loader`:
duplicate keys and explicit tags refused, ``2e-4`` a number), either flat (``cmd_vel_timeout: 0.2``) or in the
ROS layout (``omnikin_base: {ros__parameters: {...}}``); nested keys join with dots
(``linear: {x: {max_velocity: 0.5}}`` is ``linear.x.max_velocity``). Unknown names are errors
that suggest the closest known name, and so is a parameter spelled twice (flat and nested).
``--ros-args -p NAME:=VALUE`` overrides the file; unknown names there are errors too (ROS's own
``use_sim_time``, ``start_type_description_service`` and ``qos_overrides.*`` are allowed).
"""

from __future__ import annotations

import difflib
import itertools
import math
from pathlib import Path

from ..common.messages import shorten
from ..control.controllers import CONTROLLERS
from ..control.follower import FOLLOW_HEADINGS
from ..errors import InputError

DEFAULTS = {
    "cmd_vel_timeout": 0.5,
    "publish_rate": 50.0,
    "odom_frame_id": "odom",
    "base_frame_id": "base_link",
    "enable_odom_tf": True,
    "link_tf_rate": 30.0,
    "use_stamped_vel": False,
    "linear.x.max_velocity": 0.3,
    "linear.x.max_acceleration": 0.5,
    "angular.z.max_velocity": 1.0,
    "angular.z.max_acceleration": 2.0,
    "wheel_max_velocity": 0.0,
    "wheel_slip": 2e-4,
    "reject_above": 100.0,
    "link_retry_period": 1.0,
    "path_controller": "auto",
    "path_heading": "given",
    "path_smooth": True,
    "path_blend": 0.0,
}


ROS_OWN = ("use_sim_time", "start_type_description_service")
"""Parameters that rclpy itself declares: accepted in ``--ros-args``, as ``qos_overrides.*`` is."""


def unknown_parameter(name: str, source: str) -> InputError:
    """The error for an unknown parameter ``name`` in ``source``, suggesting the closest known name."""
    close = difflib.get_close_matches(name, DEFAULTS, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}?" if close else f"known: {', '.join(DEFAULTS)}"
    return InputError(f"{source}: unknown parameter {shorten(name)}; {hint}")


def check_names(names, source: str, ros_own: bool = False) -> None:
    """Refuse the first unknown name (sorted) in ``names``; ``ros_own`` also allows rclpy's own
    parameters (:data:`ROS_OWN`, ``qos_overrides.*``)."""
    for name in sorted(names):
        if name in DEFAULTS or (ros_own and (name in ROS_OWN or name.startswith("qos_overrides."))):
            continue
        raise unknown_parameter(name, source)


def ros_args_names(ros_args) -> list:
    """Names given with ``-p NAME:=VALUE`` (or ``--param``) in ``--ros-args``; names with a node
    prefix (``node:NAME:=VALUE``) are left to the node, which may be renamed."""
    args = list(ros_args or [])
    names = []
    for flag, item in itertools.pairwise(args):
        if flag in ("-p", "--param") and ":=" in item:
            name = item.split(":=", 1)[0]
            if ":" not in name:
                names.append(name)
    return names


def _flatten(d: dict, path: tuple = ()) -> list:
    """``(dotted name, path of keys, value)`` of every leaf of a nested mapping."""
    out = []
    for k, v in d.items():
        p = path + (str(k),)
        if isinstance(v, dict):
            out.extend(_flatten(v, p))
        else:
            out.append((".".join(p), p, v))
    return out


def _spelling(path: tuple) -> str:
    """How a file wrote a name: ``linear.x.max_velocity`` (flat) or ``linear: x: max_velocity`` (nested)."""
    return ": ".join(path)


def load_params(path: str | Path | None) -> dict:
    """Defaults updated by a parameter file (module docstring); every value type-checked."""
    values = dict(DEFAULTS)
    if path is None:
        return values
    from ..io.robot_file import load_yaml_file

    # a regular file of at most 256 KiB, no anchors/aliases, bounded nesting (the robot-file reader's checks)
    data = load_yaml_file(path, InputError, what="a parameter file") or {}
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a mapping of parameters")
    if len(data) == 1:
        (only,) = data.values()
        if isinstance(only, dict) and "ros__parameters" in only:
            data = only["ros__parameters"]
            if not isinstance(data, dict):
                raise InputError(f"{path}: ros__parameters must be a mapping of parameters, got {shorten(data)}")
    seen: dict = {}
    for key, keys, value in _flatten(data):
        if key not in DEFAULTS:
            raise unknown_parameter(key, str(path))
        if key in seen:
            raise InputError(
                f"{path}: parameter {key!r} given twice, as {shorten(_spelling(seen[key]))} and as "
                f"{shorten(_spelling(keys))}; keep one"
            )
        seen[key] = keys
        values[key] = value
    return validate(values, str(path))


RANGES = {
    "cmd_vel_timeout": (0.0, 3600.0, True),
    "publish_rate": (0.0, 10000.0, False),
    "link_tf_rate": (0.0, 10000.0, True),
    "linear.x.max_velocity": (0.0, 1e3, False),
    "linear.x.max_acceleration": (0.0, 1e4, False),
    "angular.z.max_velocity": (0.0, 1e3, False),
    "angular.z.max_acceleration": (0.0, 1e4, False),
    "wheel_max_velocity": (0.0, 1e5, True),
    "wheel_slip": (0.0, 1.0, True),
    "reject_above": (1.0, 1e9, True),
    "link_retry_period": (0.0, 3600.0, True),
    "path_blend": (0.0, 100.0, True),
}
"""Allowed ``(low, high, low_inclusive)`` of the numeric parameters."""

CHOICES = {
    "path_controller": ("auto", *CONTROLLERS),
    "path_heading": FOLLOW_HEADINGS,
}
"""Allowed values of the text parameters that name a choice."""


def validate(values: dict, source: str) -> dict:
    """Check types and ranges of every parameter; returns ``values`` with ints made floats.

    ``source`` names where the values came from (a file, or ``--ros-args``) in the error.
    """
    out = dict(values)
    for key, value in values.items():
        if key not in DEFAULTS:
            raise unknown_parameter(key, source)
        want = type(DEFAULTS[key])
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, want):
            raise InputError(f"{source}: parameter {key!r} must be a {want.__name__}, got {shorten(value)}")
        if key in RANGES and isinstance(value, float):  # every ranged parameter is a float
            low, high, inclusive = RANGES[key]
            ok = math.isfinite(value) and value <= high and (value >= low if inclusive else value > low)
            if not ok:
                rel = ">=" if inclusive else ">"
                raise InputError(
                    f"{source}: parameter {key!r} must be finite, {rel} {low:g} and <= {high:g}, got {value!r}"
                )
        if key in CHOICES and value not in CHOICES[key]:
            choices = ", ".join(repr(c) for c in CHOICES[key])
            raise InputError(f"{source}: parameter {key!r} must be one of {choices}, got {shorten(value)}")
        out[key] = value
    return out
