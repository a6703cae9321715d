"""The repository's paths and the environment for omnikin subprocesses."""

from __future__ import annotations

import os
from pathlib import Path

import omnikin

ROOT = Path(__file__).resolve().parents[2]
"""The repository (docs/, examples/, firmware/)."""

SRC = str(Path(omnikin.__file__).resolve().parents[1])
"""The folder holding the omnikin under test: subprocesses (the CLI, ROS nodes) must import
this one, whatever their working folder."""


def omnikin_env(**extra: str) -> dict:
    """The environment for an omnikin subprocess: this process's, with :data:`SRC` first on
    ``PYTHONPATH`` (``extra`` variables added)."""
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = SRC + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env
