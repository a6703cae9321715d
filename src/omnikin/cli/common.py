"""Helpers shared by the sub-commands."""

from __future__ import annotations

import numpy as np


def robot_as_built(robot, true_robot: str | None, errors: str, seed):
    """The robot as built and the errors drawn: a ``--true-robot`` file, or ``robot`` with a
    seeded draw of the ``--errors`` profile. ``seed``: a SeedSequence or an int."""
    from ..simulation.error_models import profile as error_profile

    if true_robot:
        return load_robot(true_robot), None
    drawn = error_profile(errors).sample(robot, np.random.default_rng(seed))
    return drawn.apply(robot), drawn


def console(width: int = 140, stderr: bool = False):
    """A rich console without markup or highlighting; ``width`` columns when not a terminal."""
    from rich.console import Console

    con = Console(highlight=False, markup=False, stderr=stderr)
    if not con.is_terminal:
        con = Console(highlight=False, markup=False, width=width, stderr=stderr)
    return con


def load_robot(spec):
    """A preset or robot file (:func:`omnikin.io.robot_file.load_robot`, imported on use)."""
    from ..io.robot_file import load_robot as load

    return load(spec)
