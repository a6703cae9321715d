"""Physical parameters of a robot as built, beyond its kinematics: what a physics engine needs.

Every field is optional: a missing one (None) is derived from the wheel layout by
:mod:`omnikin.physics.description`, which documents each default. The robot file carries them
as ``physical:`` mappings, one at the top level (:class:`PhysicalBody`) and one per wheel
(:class:`PhysicalWheel`); ``docs/conventions.md`` lists the fields, units and ranges.

Frames: the body frame of ``docs/conventions.md`` (x forward, y left, z up, origin on the
floor under the body centre used by the kinematics). SI units.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields

from ..common.arrays import container_problem, range_problem, whole_problem
from ..common.messages import shorten
from ..errors import InputError

# --- ranges (docs/conventions.md, "Physical fields") --------------------------------------------
MASS_RANGE = (1e-4, 1e5)
"""Mass [kg] of a chassis or a wheel: from a 0.1 g micro-robot part to a 100 t vehicle."""
WIDTH_RANGE = (1e-4, 10.0)
"""Wheel width [m] (along the axle), bounded like the radius."""
HEIGHT_RANGE = (1e-3, 10.0)
"""Chassis thickness [m]."""
COM_LIMIT = 1e3
"""Largest ``|x|``, ``|y|``, ``z`` of the centre of mass [m], bounded like a wheel's position."""
COM_Z_MIN = 1e-4
"""Lowest height of the centre of mass above the floor [m]: it lies above the floor."""
FRICTION_RANGE = (1e-3, 10.0)
"""Sliding friction coefficient between tyre (or roller) and floor: ice 0.01-0.05, rubber on
concrete about 1, racing tyres up to about 2."""
TORQUE_RANGE = (1e-5, 1e5)
"""Motor torque limit at the wheel [N m]."""
ROLLERS_RANGE = (3, 64)
"""Rollers per row on a Swedish wheel."""
ROWS_RANGE = (1, 4)
"""Rows of rollers on a Swedish wheel (omni wheels often have 2, staggered)."""


def _number(owner: str, name: str, value, low: float, high: float, unit: str) -> None:
    """Raise :class:`InputError` naming ``owner`` and ``physical.<name>`` unless ``value`` is None
    or a finite number in ``[low, high]`` (:func:`omnikin.common.arrays.range_problem`)."""
    problem = None if value is None else range_problem(value, low, high, unit)
    if problem:
        raise InputError(f"{owner}: physical.{name} {problem}")


def _whole(owner: str, name: str, value, low: int, high: int) -> None:
    """As :func:`_number` for a whole number (:func:`omnikin.common.arrays.whole_problem`)."""
    problem = None if value is None else whole_problem(value, low, high)
    if problem:
        raise InputError(f"{owner}: physical.{name} {problem}")


@dataclass(frozen=True)
class PhysicalWheel:
    """Physical fields of one wheel (None: derived from the layout).

    ``width`` [m] along the axle; ``mass`` [kg] of the wheel with its rollers; ``rollers``
    per row and ``rows`` (Swedish wheels only); ``friction`` sliding coefficient with the
    floor; ``max_torque`` [N m] of the motor at the wheel (driven wheels; for steerable
    wheels also the steering motor).
    """

    width: float | None = None
    mass: float | None = None
    rollers: int | None = None
    rows: int | None = None
    friction: float | None = None
    max_torque: float | None = None

    def check(self, owner: str) -> None:
        """Raise :class:`InputError` naming ``owner`` (the wheel) and the field if a value is out of range."""
        _number(owner, "width", self.width, *WIDTH_RANGE, "m")
        _number(owner, "mass", self.mass, *MASS_RANGE, "kg")
        _whole(owner, "rollers", self.rollers, *ROLLERS_RANGE)
        _whole(owner, "rows", self.rows, *ROWS_RANGE)
        _number(owner, "friction", self.friction, *FRICTION_RANGE, "")
        _number(owner, "max_torque", self.max_torque, *TORQUE_RANGE, "N m")

    def __post_init__(self):
        self.check("wheel")

    @property
    def given(self) -> dict:
        """The fields set (not None), by name."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}


@dataclass(frozen=True)
class PhysicalBody:
    """Physical fields of the chassis (None: derived from the layout).

    ``mass`` [kg] of the chassis without wheels; ``com`` (x, y, z) [m] its centre of mass in
    the body frame, z above the floor; ``height`` [m] the thickness of the chassis plate.
    """

    mass: float | None = None
    com: tuple[float, float, float] | None = None
    height: float | None = None

    def __post_init__(self):
        _number("body", "mass", self.mass, *MASS_RANGE, "kg")
        _number("body", "height", self.height, *HEIGHT_RANGE, "m")
        if self.com is not None:
            why = container_problem(self.com, "the order x, y, z")
            if why:
                raise InputError(f"body: physical.com must be 3 numbers (x, y, z) [m] in order: {why}")
            com = tuple(itertools.islice(self.com, 4))  # an endless iterator is not read to its end
            if len(com) != 3:
                raise InputError(f"body: physical.com must be 3 numbers (x, y, z) [m], got {shorten(self.com)}")
            for axis, v in zip("xyz", com, strict=True):
                low = COM_Z_MIN if axis == "z" else -COM_LIMIT
                _number("body", f"com.{axis}", v, low, COM_LIMIT, "m")
            object.__setattr__(self, "com", tuple(float(v) for v in com))

    @property
    def given(self) -> dict:
        """The fields set (not None), by name."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}
