"""Helpers shared by the sub-commands."""

from __future__ import annotations

import numpy as np


def robot_as_built(robot, true_robot: str | None, errors: str, seed):
    """The robot as built and the errors drawn: a ``--true-robot`` file, or ``robot`` with a
    seeded draw of the ``--errors`` profile. ``seed``: a SeedSequence or an int."""
    from ..io.robot_file import load_robot
    from ..simulation.errors import profile as error_profile

    if true_robot:
        return load_robot(true_robot), None
    drawn = error_profile(errors).sample(robot, np.random.default_rng(seed))
    return drawn.apply(robot), drawn
