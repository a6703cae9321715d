"""A robot as built keeps the body of its design: the physical description differs from the
nominal one only where the errors say. A chassis derived from the as-built hub positions would
not: 1 mm off the circle, tomasi-omni3's wheels no longer stand evenly on a circle and its
1.655 kg cylinder becomes a 1.381 kg box.

Expected values from the errors alone: each hub moved by exactly its ``(dx, dy)``, each radius
``r (1 + e)``, each drive direction ``delta + d``; chassis (shape, size, mass, centre of mass,
inertia), wheel masses, widths, rollers per row and motors equal to the nominal's; the robot's
centre of mass moved by the wheels' masses times their displacements over the total mass.
"""

from __future__ import annotations

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.physics.description import describe
from omnikin.simulation.error_models import SystematicErrors, WheelErrors

HUB_ERRORS = {"w1": (0.001, -0.001), "w2": (-0.001, 0.0005), "w3": (0.0007, 0.001)}


@pytest.mark.parametrize("name", ["tomasi-omni3", "diff-drive", "synchro", "mecanum4"])
def test_an_as_built_robot_keeps_its_chassis_masses_and_motors_and_moves_only_its_wheels(name):
    nominal = load_robot(name)
    moves = dict(zip(nominal.rolling_names, HUB_ERRORS.values(), strict=False))
    errors = {
        n: WheelErrors(dx=dx, dy=dy, radius=0.004, drive=0.003 if not nominal.wheel(n).is_fixed else 0.0)
        for n, (dx, dy) in moves.items()
    }
    true = SystematicErrors(errors).apply(nominal)
    before, after = describe(nominal), describe(true)
    assert after.chassis == before.chassis
    assert after.mass == before.mass
    if name == "tomasi-omni3":
        assert after.chassis.shape == "cylinder" and after.chassis.mass == pytest.approx(1.655, abs=1e-3)
    moment = np.zeros(3)
    for w0, w1 in zip(before.wheels, after.wheels, strict=True):
        e = errors.get(w0.name, WheelErrors())
        assert w1.hub[0] - w0.hub[0] == pytest.approx(e.dx, abs=1e-15)
        assert w1.hub[1] - w0.hub[1] == pytest.approx(e.dy, abs=1e-15)
        assert w1.radius == pytest.approx(w0.radius * (1 + e.radius), rel=1e-15)
        assert w1.drive == pytest.approx(w0.drive + e.drive, abs=1e-15)
        for field in ("mass", "hub_mass", "width", "friction", "driven", "motor"):
            assert getattr(w1, field) == getattr(w0, field), (w0.name, field)
        if w0.rollers is not None:
            assert (w1.rollers.rows, w1.rollers.per_row, w1.rollers.mass) == (
                w0.rollers.rows,
                w0.rollers.per_row,
                w0.rollers.mass,
            )
            assert w1.rollers.crest == pytest.approx(w0.rollers.crest * (1 + e.radius), rel=1e-12)
        moment += w0.mass * np.array([e.dx, e.dy, w0.radius * e.radius])
        if w0.steering is not None:
            moment += w0.steering.fork_mass * np.array([e.dx, e.dy, w0.radius * e.radius])
    np.testing.assert_allclose(np.subtract(after.com, before.com), moment / before.mass, atol=1e-15)


def test_the_robot_built_exactly_is_described_as_the_nominal_one():
    nominal = load_robot("tomasi-omni3")
    assert describe(SystematicErrors({}).apply(nominal)) == describe(nominal)
    same = SystematicErrors({"w1": WheelErrors(dx=0.0)}).apply(nominal)
    assert describe(same) == describe(nominal)
