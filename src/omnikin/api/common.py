"""What the API's entry points share: resolving robots and profiles given by name, JSON output."""

from __future__ import annotations

import math
import os

from ..kinematics.robot import Robot, require_same_wheels
from ..simulation.error_models import ErrorProfile, NoiseModel, error_profile, noise_profile


def robot_of(spec) -> Robot:
    """A :class:`~omnikin.kinematics.robot.Robot`, or one loaded from a preset name or robot file.

    Parameters
    ----------
    spec : str, os.PathLike or Robot
        A robot (returned as it is), a preset name or the path of a robot file
        (:func:`omnikin.load_robot`).

    Returns
    -------
    Robot

    Raises
    ------
    RobotFileError
        As :func:`omnikin.load_robot`.
    """
    if isinstance(spec, Robot):
        return spec
    from ..io.robot_file import load_robot

    return load_robot(spec)


def noise_of(spec) -> NoiseModel:
    return spec if isinstance(spec, NoiseModel) else noise_profile(spec)


def errors_of(spec) -> ErrorProfile:
    return spec if isinstance(spec, ErrorProfile) else error_profile(spec)


def setting_name(spec) -> str | None:
    """How a setting given as a name, a path or an object is recorded."""
    if spec is None or isinstance(spec, str):
        return spec
    if isinstance(spec, os.PathLike):
        return os.fspath(spec)
    if isinstance(spec, Robot):
        return spec.name
    return repr(spec)


def as_built(robot: Robot, true_robot, errors, seed_sequence):
    """The robot as built and the errors drawn (None for a given ``true_robot``). A given
    ``true_robot`` must have the wheels of ``robot`` (names, types, encoders:
    :func:`~omnikin.kinematics.robot.wheel_set_problem`), else an InputError names the difference."""
    from ..evaluation.procedure import draw_as_built

    if true_robot is not None:
        true = robot_of(true_robot)
        require_same_wheels(robot, true)
        return true, None
    return draw_as_built(robot, errors_of(errors), seed_sequence)


def require_callable(**callbacks) -> None:
    """Refuse, in one :class:`~omnikin.errors.InputError` naming the argument, a callback given
    as something that cannot be called (``progress=5``); None passes."""
    from ..common.messages import shorten
    from ..errors import InputError

    for name, function in callbacks.items():
        if function is not None and not callable(function):
            raise InputError(f"{name} must be a function (or None), got {shorten(function)}")


def finite_or_none(x):
    """``x`` for JSON: non-finite numbers become None (JSON has no infinity)."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def dumps(document: dict) -> str:
    """The JSON text of a result document: strict JSON (:func:`omnikin.io.jsonfile.to_json`; a
    NaN or infinity left in it is an error naming its field), with a final newline.

    Parameters
    ----------
    document : dict
        A result document (e.g. :meth:`~omnikin.api.umbmark.UMBmarkReport.as_dict`): numbers, text, lists and dicts.

    Returns
    -------
    str
        The JSON text, ending in a newline.

    Raises
    ------
    NonFiniteValueError
        A NaN or infinity in ``document`` (the message names its field).
    """
    from ..io.jsonfile import to_json

    return to_json(document) + "\n"


def require_viz():
    from ..viz import require_matplotlib

    require_matplotlib()
