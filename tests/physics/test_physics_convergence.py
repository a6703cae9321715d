"""The physics UMBmark floor converged in the time step (docs/physics.md, "Convergence").

The floor is UMBmark of the nominal tomasi-omni3 commanded by its own model (1 m square, rotate
mode, 50 Hz), each run starting its wheels at roller phases drawn from a seed. The same draws
are driven at the default step and at half of it; the floor must agree within two standard
errors of its spread over roller phases (the spread at the half step over the draws): a step
error below that cannot be told from another draw of phases. Two layouts of the rollers: both
rows in the wheel's mid-plane (the default) and side by side over a 28 mm wide wheel
(``physical.width``), where the contact alternates between two levers and the spread is large.

Also here: why the step may be at most half the contacts' time constant. MuJoCo lengthens a
contact time constant below twice the step to twice the step (``refsafe``, its documented
default), so a 4 ms step with the 4 ms contacts of the model simulates 8 ms contacts.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.io.robot_file import robot_from_dict, robot_to_dict  # noqa: E402
from omnikin.motion.plans import umbmark_square  # noqa: E402
from omnikin.physics.mjcf import CONTACT_SOLREF, DEFAULT_STEP, mjcf  # noqa: E402
from omnikin.physics.run import simulate_physics  # noqa: E402

DRAWS = 5
"""Draws of roller phases per direction."""

SEED = 7

WIDTH = 0.028
"""Wheel width [m] over which the side-by-side rows spread (rows 14 mm apart)."""


def tomasi(rows: str):
    robot = load_robot("tomasi-omni3")
    if rows == "mid-plane":
        return robot
    doc = robot_to_dict(robot)
    for wheel in doc["wheels"]:
        wheel.setdefault("physical", {})["width"] = WIDTH
    return robot_from_dict(doc)


def floor_runs(robot, step: float) -> np.ndarray:
    """Return errors ``(DRAWS, 2, 3)`` [m, m, rad] of the nominal robot's 1 m UMBmark squares
    (cw, ccw), each run at its own roller phases (the same draws at every step)."""
    phases = np.random.default_rng(SEED).random((DRAWS, 2, len(robot.rolling)))
    eps = np.empty((DRAWS, 2, 3))
    for k in range(DRAWS):
        for j, direction in enumerate(("cw", "ccw")):
            plan = umbmark_square(direction, 1.0, "rotate")
            run = simulate_physics(plan, robot, robot, rate=50.0, step=step, roller_phase=phases[k, j])
            eps[k, j] = run.epsilon[0]
    return eps


def e_max_syst(eps: np.ndarray) -> float:
    return float(max(np.hypot(*eps[:, j, :2].mean(axis=0)) for j in range(2)))


@pytest.mark.slow
@pytest.mark.parametrize("rows", ["mid-plane", "side by side"])
def test_the_floor_at_the_default_step_agrees_with_half_the_step_within_its_spread(rows):
    robot = tomasi(rows)
    coarse, fine = floor_runs(robot, DEFAULT_STEP), floor_runs(robot, DEFAULT_STEP / 2)
    position_errors = []
    for j in range(2):
        # standard errors over the draws of phases: of the centre of gravity and the mean heading
        se_position = math.sqrt(fine[:, j, :2].var(axis=0, ddof=1).sum() / DRAWS)
        se_heading = fine[:, j, 2].std(ddof=1) / math.sqrt(DRAWS)
        assert se_position > 0 and se_heading > 0  # the phases spread the runs
        cg_change = np.linalg.norm(coarse[:, j, :2].mean(axis=0) - fine[:, j, :2].mean(axis=0))
        assert cg_change <= 2 * se_position
        assert abs(coarse[:, j, 2].mean() - fine[:, j, 2].mean()) <= 2 * se_heading
        position_errors.append(se_position)
    assert abs(e_max_syst(coarse) - e_max_syst(fine)) <= 2 * max(position_errors)


def rest_height(xml: str) -> float:
    """Height [m] of the chassis frame after 1 s at rest on the floor."""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for _ in range(round(1.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    return float(data.qpos[2])


def test_mujoco_softens_contacts_whose_time_constant_is_below_twice_the_step():
    xml = mjcf(load_robot("tomasi-omni3"), DEFAULT_STEP)
    timeconst = CONTACT_SOLREF[0]
    step_attr, solref_attr = f'timestep="{DEFAULT_STEP:g}"', f'solref="{timeconst:g} 1"'
    assert step_attr in xml and solref_attr in xml
    double_step = rest_height(xml.replace(step_attr, f'timestep="{2 * DEFAULT_STEP:g}"'))
    double_timeconst = rest_height(xml.replace(solref_attr, f'solref="{2 * timeconst:g} 1"'))
    default = rest_height(xml)
    # at a step of the time constant the contacts are those of twice the time constant
    assert double_step == pytest.approx(double_timeconst, rel=1e-6)
    # and they sink several times deeper (penetration grows with the time constant squared)
    assert double_step < 4 * default < 0.0
