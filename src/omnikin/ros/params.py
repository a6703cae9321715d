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

A ``--params FILE`` is YAML, either flat (``cmd_vel_timeout: 0.2``) or in the ROS layout
(``omnikin_base: {ros__parameters: {...}}``); unknown names are errors.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import OmnikinError

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

    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}
    except OSError as exc:
        raise OmnikinError(f"{path}: cannot read: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise OmnikinError(f"{path}: invalid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise OmnikinError(f"{path}: expected a mapping of parameters")
    if len(data) == 1:
        (only,) = data.values()
        if isinstance(only, dict) and "ros__parameters" in only:
            data = only["ros__parameters"]
    flat = _flatten(data)
    for key, value in flat.items():
        if key not in DEFAULTS:
            raise OmnikinError(f"{path}: unknown parameter {key!r}; known: {sorted(DEFAULTS)}")
        want = type(DEFAULTS[key])
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, want) or (want is float and value != value):
            raise OmnikinError(f"{path}: parameter {key!r} must be a {want.__name__}, got {value!r}")
        values[key] = value
    return values
