"""Robots from the literature, shipped as schema-1 robot files with their citation.

Load one with :func:`omnikin.io.robot_file.load_robot` (``load_robot("tomasi-omni3")``).
This package holds only the data files and their names.
"""

from __future__ import annotations

from pathlib import Path

from ..common.messages import did_you_mean
from ..errors import InputError

PRESET_DIR = Path(__file__).resolve().parent

PRESET_NAMES = (
    "tomasi-omni3",
    "tomasi-omni3-lidar",
    "garcia-sillas-omni3",
    "villasenor-omni3",
    "diff-drive",
    "ackermann",
    "synchro",
    "xr4000",
    "mecanum4",
    "omni4",
)


def preset_path(name: str) -> Path:
    """Path of the robot file of preset ``name``; an unknown name is an
    :class:`~omnikin.errors.InputError` naming the closest presets."""
    if name not in PRESET_NAMES:
        raise InputError(
            f"unknown preset {name!r}{did_you_mean(name, PRESET_NAMES)} (presets: {', '.join(PRESET_NAMES)})"
        )
    return PRESET_DIR / f"{name}.yaml"
