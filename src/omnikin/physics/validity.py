"""What the physics engine accepts: a physical description (:mod:`omnikin.physics.description`)
is turned into a MuJoCo model only when that model resolves the robot at every accepted time
step (up to :data:`~omnikin.physics.description.MAX_STEP`); otherwise :func:`check_resolvable`
refuses it before any simulation with one line naming the wheel or part, the quantity, its value
and the range or the reason (docs/physics.md, "What the engine accepts").

The conditions (SI units):

- **Wheel size.** The contacts are soft with a fixed time constant (2 ``MAX_STEP`` = 4 ms,
  :data:`omnikin.physics.mjcf.CONTACT_SOLREF`); MuJoCo's soft contact holds a weight by sinking
  ``x = g (1 - d) / d (d_max tc)^2`` whatever the size (``d`` the impedance, 0.95 when shallow:
  8 um; the measured shortfalls below say 13-25 um), which shortens the rolling radius: a robot on wheels of radius
  ``r`` drives about ``16-25 um / r`` short (tomasi-omni3's layout, ``line 1``: 0.04 % at 41 mm;
  0.23 % at 5 mm, 0.48 % with the hubs ten radii out; 0.43 % at 3 mm). Below
  :data:`MIN_RADIUS` the shortfall approaches the validation tolerance of 0.5 %.
- **Derived defaults in the file's ranges.** A chassis mass, a wheel mass or a motor torque the
  description derives from the layout (docs/physics.md, "Defaults") must lie within the range
  the robot file could give it (:mod:`omnikin.kinematics.physical`): a 1000 m robot would otherwise weigh
  3e10 kg and get 1e12 N m motors that no file could state.
- **Rows on the wheel's side.** With ``physical.width`` the rows of a Swedish wheel spread
  over it (docs/physics.md, "Rows side by side"); a row further along the axle than the hub's
  own distance from the body origin along it, ``|hub . axle|``, would roll on the far side of
  the robot's centre (the turn rate's closed form ``l^2 / (l^2 - d^2)`` changes sign at
  ``d = l``): tomasi-omni3 with ``width`` 10 m drove ``line 1`` to 0.25 m.
- **Light bodies against the weight they carry.** The robot's mass over the mass of its
  lightest moving body (a roller, a hub or a fork) at most :data:`MAX_MASS_RATIO`: the contact
  solver loses the light rollers under loads that many times their weight. tomasi-omni3 with
  its default 2 x 6 rollers (each 1/24 of the wheel) drove ``line 1`` within 0.1 % up to
  2.4e8 (1 t on 0.1 g wheels) and diverged at 2.4e9 (10 t on 0.1 g wheels); with 64 x 1 rollers
  of 7.8 mg, 1.3e8 (1 t) drove a 1 m square, 3.8e8 (3 t) diverged after 18 s of it and 1.3e9
  (10 t) at once. The bound keeps a margin below the first failure.
- **Bodies MuJoCo can load.** MuJoCo refuses moving bodies whose mass or principal inertia is
  not above ``mjMINVAL`` (1e-15); every body needs at least :data:`MIN_MASS` and
  :data:`MIN_INERTIA`, twice that. Rollers bind first: a roller's spin inertia is
  ``0.4 m b^2``, its cross-section radius ``b`` about ``r tan^2(pi / n)``.

The servos' stability at the step is not a condition here: the description gives every driven
wheel and every steering joint the rotor inertia that keeps it
(:func:`~omnikin.physics.description.rotor_inertia`,
:func:`~omnikin.physics.description.steering_rotor_inertia`).
"""

from __future__ import annotations

import math

from ..errors import InputError
from ..kinematics.physical import MASS_RANGE, TORQUE_RANGE
from .description import PhysicalRobot, WheelBody, roller_shape

MIN_RADIUS = 0.01
"""Smallest wheel radius [m] the engine accepts: the contacts' sinking (16-40 um) shortens the
rolling radius by about 0.3-0.4 % there (measured: ``line 1`` 0.30 % short, 0.39 % with one row
of rollers), more below (module docstring)."""
MAX_MASS_RATIO = 1e8
"""Largest ratio of the robot's mass to the mass of its lightest moving body (module docstring)."""
MJ_MINVAL = 1e-15
"""MuJoCo's ``mjMINVAL``: moving bodies need a mass and principal inertias above it."""
MIN_MASS = 2.0 * MJ_MINVAL
"""Smallest mass [kg] of a moving body: twice :data:`MJ_MINVAL`."""
MIN_INERTIA = 2.0 * MJ_MINVAL
"""Smallest principal inertia [kg m^2] of a moving body: twice :data:`MJ_MINVAL` (measured:
rollers of 3e-15 kg m^2 in 64 x 1 and 8e-15 in 64 x 4 on tomasi-omni3 drive ``line 1`` within
0.12 % and ``spin 3`` within 0.1 %)."""


def _outside(value: float, bounds: tuple[float, float]) -> bool:
    return not bounds[0] <= value <= bounds[1]


def _derived(owner: str, quantity: str, value: float, unit: str, bounds, field: str, why: str) -> None:
    if _outside(value, bounds):
        raise InputError(
            f"{owner}: {quantity} {value:.3g} {unit}, derived {why}, lies outside [{bounds[0]:g}, {bounds[1]:g}] "
            f"{unit}, the range a robot file may give: give {field}"
        )


def _most_rollers(wheel: WheelBody) -> int:
    """Largest rollers per row (at least 3) at which the rollers of ``wheel`` keep
    :data:`MIN_INERTIA` with the wheel's mass, 2 when none does."""
    rollers = wheel.rollers
    assert rollers is not None
    total = rollers.mass * len(rollers.rollers)
    scale = rollers.radius / roller_shape(rollers.angle, rollers.per_row)[1]
    for n in range(rollers.per_row, 2, -1):
        b = roller_shape(rollers.angle, n)[1] * scale
        if 0.4 * total / (rollers.rows * n) * b * b >= MIN_INERTIA:
            return n
    return 2


def _bodies(wheel: WheelBody) -> list[tuple[str, float, tuple[float, ...]]]:
    """``(part, mass, principal inertias)`` of the moving bodies of ``wheel``."""
    parts: list[tuple[str, float, tuple[float, ...]]] = [("hub", wheel.hub_mass, wheel.hub_inertia)]
    if wheel.rollers is not None:
        parts.append(("roller", wheel.rollers.mass, wheel.rollers.inertia))
    if wheel.steering is not None:
        parts.append(("fork", wheel.steering.fork_mass, wheel.steering.fork_inertia))
    return parts


def check_resolvable(robot: PhysicalRobot) -> None:
    """Raise :class:`~omnikin.errors.InputError` (one line) unless ``robot`` meets the
    conditions of the module docstring; the first condition broken is named. A robot drawn by an
    error profile (its name ends in "(as built)") is named as the draw, whose values the user did
    not write."""
    try:
        _check(robot)
    except InputError as e:
        if robot.name.endswith("(as built)"):
            raise InputError(
                f"robot {robot.name!r}, drawn from the --errors profile with --seed: {e} (another --seed or "
                "--errors none builds another)"
            ) from None
        raise


def _check(robot: PhysicalRobot) -> None:
    for wheel in robot.wheels:
        if wheel.radius < MIN_RADIUS:
            raise InputError(
                f"wheel {wheel.name!r}: radius {wheel.radius:.3g} m is below the {MIN_RADIUS:g} m the physics engine "
                "resolves (its contacts sink 16-40 um whatever the size, which would shorten the rolling radius by "
                "more than 0.4 %)"
            )
    for wheel in robot.wheels:
        rollers = wheel.rollers
        reach = abs(sum(h * a for h, a in zip(wheel.hub[:2], wheel.axle[:2], strict=True)))
        if rollers is not None and rollers.rows > 1 and max(rollers.offsets) >= reach:
            most = 2.0 * reach * rollers.rows / (rollers.rows - 1)
            raise InputError(
                f"wheel {wheel.name!r}: physical.width {wheel.width:.3g} m puts its outer row of rollers "
                f"{max(rollers.offsets):.3g} m along the axle, past the robot's centre ({reach:.3g} m from the hub "
                f"along it): the width must stay below {most:.3g} m"
            )
    chassis = robot.chassis
    _derived("chassis", "mass", chassis.mass, "kg", MASS_RANGE, "physical.mass", "at 1000 kg/m^3 from its size")
    for wheel in robot.wheels:
        owner = f"wheel {wheel.name!r}"
        given = set(wheel.fields)
        if "mass" not in given:
            _derived(owner, "mass", wheel.mass, "kg", MASS_RANGE, "its physical.mass", "at 1000 kg/m^3 from its size")
        if "max_torque" not in given:
            if wheel.motor is not None:
                torque = wheel.motor.max_torque
                _derived(owner, "motor torque", torque, "N m", TORQUE_RANGE, "its physical.max_torque", "as mu N r")
            if wheel.steering is not None and wheel.steering.actuated:
                torque = wheel.steering.max_torque
                why = "as mu N (trail + r)"
                _derived(owner, "steering torque", torque, "N m", TORQUE_RANGE, "its physical.max_torque", why)
    _check_mass_ratio(robot)
    _check_bodies("robot", [("chassis", chassis.mass, chassis.inertia)], "a heavier chassis (physical.mass)")
    for wheel in robot.wheels:
        advice = "a heavier wheel (physical.mass)"
        if wheel.rollers is not None:
            most = _most_rollers(wheel)
            fewer = f"at most {most} rollers per row, " if most >= 3 else ""
            advice = f"{fewer}fewer rows or {advice}"
        _check_bodies(f"wheel {wheel.name!r}", _bodies(wheel), advice)


def _check_mass_ratio(robot: PhysicalRobot) -> None:
    """Refuse a robot heavier than :data:`MAX_MASS_RATIO` times its lightest moving body,
    naming the wheel, the body and the least wheel mass that would do (rounded up)."""
    part, body, wheel = min(((p, m, w) for w in robot.wheels for p, m, _ in _bodies(w)), key=lambda item: item[1])
    if robot.mass <= MAX_MASS_RATIO * body:
        return
    least = wheel.mass * robot.mass / (MAX_MASS_RATIO * body) * 1.001  # the wheels weigh in the robot too
    digits = 10.0 ** (math.floor(math.log10(least)) - 2)
    least = math.ceil(least / digits) * digits
    fewer = "fewer rollers, " if part == "roller" else ""
    raise InputError(
        f"wheel {wheel.name!r}: its {part} of {body:.3g} kg carries a robot of {robot.mass:.3g} kg, "
        f"{robot.mass / body:.2g} times its mass; the physics engine resolves at most {MAX_MASS_RATIO:g}: give the "
        f"wheel a physical.mass of at least {least:.3g} kg (now {wheel.mass:.3g}), {fewer}or a lighter chassis"
    )


def _check_bodies(owner: str, parts: list[tuple[str, float, tuple[float, ...]]], advice: str) -> None:
    """Refuse the first of ``parts`` (part, mass [kg], principal inertias [kg m^2]) of ``owner``
    below :data:`MIN_MASS` or :data:`MIN_INERTIA`, with ``advice``."""
    for part, mass, inertia in parts:
        if mass < MIN_MASS or min(inertia) < MIN_INERTIA:
            raise InputError(
                f"{owner}: {part} mass {mass:.3g} kg, inertia {min(inertia):.3g} kg m^2 lies below the "
                f"{MIN_MASS:g} kg, {MIN_INERTIA:g} kg m^2 the engine needs (MuJoCo's mjMINVAL {MJ_MINVAL:g}): "
                f"give {advice}"
            )
