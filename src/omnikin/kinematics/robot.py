"""A robot = wheels mounted on a body: inverse and forward kinematics, analysis.

Conventions (``docs/conventions.md``): body twist ``(vx, vy, omega)`` [m/s, m/s,
rad/s] of the body origin in body axes; wheel quantities ``(..., n)`` in robot-file
order over the *rolling* wheels (every wheel but castors, which are passive and
unmeasured); steering angles ``(..., n_steer)`` [rad] over the steerable wheels in
file order, relative to each wheel's mounting drive direction.

Inverse kinematics stacks the wheels' rolling rows into the ``n x 3`` wheel
Jacobian ``J`` (``omega = J twist``, :mod:`omnikin.kinematics.wheels`). Fixed standard wheels
add no-side-slip rows ``C_f twist = 0``: a twist that violates them is refused
(or its violation returned on request).

Forward kinematics solves the least-squares problem (conventions: unweighted, in
rad/s, with rank tolerance) with the fixed wheels' constraints imposed exactly::

    twist = N pinv(A N) b,   A = [J; S / r],   b = [omega; 0]

where ``N`` spans the null space of ``C_f`` and ``S`` holds the sliding rows of
steerable wheels at their measured steering angles (:meth:`omnikin.kinematics.wheels.Wheel.swivel_row`),
each divided by its radius so that it weighs like a wheel-speed reading of zero: a measured
steering angle says that the contact does not slide sideways. For an off-centred wheel the row
reads ``offset * beta' / r`` at steering rate ``beta'``; forward kinematics and odometry take
the steering as steady over an interval (zero), as the kinematic engines drive it (they turn
the steering at once, between samples). Without these rows the off-centred wheels of XR4000
standing parallel leave the motion across them to rounding: in a physics run, steering angles
0.2 urad apart turned encoder ticks into kilometres of odometry. For a layout of Swedish wheels
only, ``N = I`` and ``A = J``: ``twist = pinv(J) omega`` exactly as in the
conventions. The residual ``b - A twist`` measures slip / model error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from functools import cached_property

import numpy as np

from ..common.arrays import as_components, as_real_array, frozen, require_finite
from ..common.messages import digits_apart, shorten
from ..errors import InfeasibleTwistError, InputError, SingularLayoutError
from .linalg import RANK_TOL, null_space, rank
from .mobility import Configuration, Mobility, analyse, generic_configuration
from .physical import PhysicalBody
from .se2 import MAX_ANGLE
from .sensors import Bumper, Imu, Lidar, Sensor
from .wheels import DERIVED_SUFFIXES, Wheel

STEER_LIMIT_SLACK = 1e-9
"""How far [rad] a given steering angle may lie outside its wheel's limits (round-off of a
conversion from degrees); :meth:`Robot.fk` and the matrices refuse angles beyond it."""

MAX_ROBOT_NAME = 128
"""Longest robot name [characters]: it is quoted in messages, reports and bag metadata."""


def robot_name_problem(name) -> str | None:
    """None if ``name`` is a usable robot name (1 to 128 printable characters, no blanks at either
    end), else why not."""
    if not isinstance(name, str) or not name.strip():
        return f"must be a non-empty string, got {shorten(name)}"
    if len(name) > MAX_ROBOT_NAME:
        return f"at most {MAX_ROBOT_NAME} characters, got {len(name)}"
    if not name.isprintable() or name != name.strip():
        return f"printable characters without blanks at either end, got {shorten(name)}"
    return None


def name_collisions(names: Sequence[str]) -> list[tuple[int, str]]:
    """``(index, problem)`` for each wheel name that clashes (empty if none): a repeated name, or
    a name equal to one derived from another wheel's (``w`` and ``w_steer_deg``, see
    :data:`omnikin.kinematics.wheels.DERIVED_SUFFIXES`). ``index`` is 0-based. Linear in the number of wheels."""
    first: dict[str, int] = {}
    problems = []
    for i, n in enumerate(names):
        if n in first:
            problems.append((i, f"duplicate wheel name {shorten(n)} (also wheel #{first[n] + 1})"))
        else:
            first[n] = i
    for i, n in enumerate(names):
        for suffix, meaning in DERIVED_SUFFIXES.items():
            base = n[: -len(suffix)]
            if n.endswith(suffix) and base in first:
                problems.append(
                    (
                        i,
                        f"wheel name {shorten(n)} is taken by the {meaning} of wheel {shorten(base)} "
                        f"(#{first[base] + 1}): rename one of them",
                    )
                )
    return sorted(problems)


def wheel_set_problem(robot: Robot, other: Robot) -> str | None:
    """None if ``other`` (a robot as built) has the wheels of ``robot``, else the first
    difference in one phrase: the same wheel names (in any order), each of the same type,
    with an encoder exactly where ``robot`` has one, a steerable wheel centred (zero
    ``steer.offset``) exactly where it is on ``robot``. Positions, radii, angles, encoder
    scales, offsets and steering limits may differ: those are what a robot as built gets wrong."""
    mine, theirs = robot.wheel_names, set(other.wheel_names)
    extra = [n for n in other.wheel_names if n not in set(mine)]
    if extra:
        return f"it has wheel {shorten(extra[0])}, which {robot.name!r} has not (wheels: {shorten(mine)})"
    missing = [n for n in mine if n not in theirs]
    if missing:
        return f"it has no wheel {shorten(missing[0])} (wheels of {robot.name!r}: {shorten(mine)})"
    for w in robot.wheels:
        o = other.wheel(w.name)
        if o.type != w.type:
            return f"wheel {w.name!r} is of type {o.type!r}, not {w.type!r} as on {robot.name!r}"
        if (o.encoder is None) != (w.encoder is None):
            has, lacks = ("has no", "has one") if o.encoder is None else ("has an", "has none")
            return f"wheel {w.name!r} {has} encoder, but on {robot.name!r} it {lacks}"
        if o.motor_kind != w.motor_kind and not w.is_castor:
            return f"wheel {w.name!r} has a {o.motor_kind} motor, not a {w.motor_kind} motor as on {robot.name!r}"
        if w.is_steerable and o.is_centred_steerable != w.is_centred_steerable:
            centred = {True: "centred (steer.offset 0)", False: "off-centred (steer.offset > 0)"}
            return (
                f"wheel {w.name!r} is {centred[o.is_centred_steerable]}, but on {robot.name!r} it is "
                f"{centred[w.is_centred_steerable]}"
            )
    return None


def require_same_wheels(robot: Robot, true_robot: Robot) -> None:
    """Refuse a robot as built whose wheels are not those of ``robot`` (one line naming the
    first difference: :func:`wheel_set_problem`)."""
    if true_robot is robot:
        return
    problem = wheel_set_problem(robot, true_robot)
    if problem:
        raise InputError(f"true robot {true_robot.name!r} does not fit robot {robot.name!r}: {problem}")


def heading_array(heading, name: str = "heading") -> np.ndarray:
    """``heading`` [rad] as a float array: real, finite and ``|heading| <=``
    :data:`~omnikin.kinematics.se2.MAX_ANGLE`, else an InputError naming ``name``."""
    th = as_real_array(heading, name)
    require_finite(th, name)
    big = np.abs(th) > MAX_ANGLE
    if big.any():
        index = tuple(int(i) for i in np.argwhere(big)[0])
        at = f" at index {index}" if index else ""
        p = digits_apart(abs(float(th[index])), MAX_ANGLE)
        raise InputError(
            f"{name}{at}: {float(th[index]):.{p}g} rad is beyond +-{MAX_ANGLE:g} rad; give the heading in radians "
            f"(wrapped, or unwrapped over fewer than {MAX_ANGLE / (2 * np.pi):.0f} turns)"
        )
    return th


def _checked_after():
    """NumPy error state for a computation whose result :func:`_refuse_overflow` checks afterwards:
    no RuntimeWarning printed for the overflow it reports."""
    return np.errstate(over="ignore", invalid="ignore")


def _refuse_overflow(result: np.ndarray, what: str, name: str, given: np.ndarray) -> None:
    """Finite input can still overflow (a twist of 1e308 m/s times 1/r): raise an InputError
    naming the input ``name`` (and the offending sample of ``given``) rather than return inf/NaN."""
    bad = ~np.isfinite(result)
    if not bad.any():
        return
    index = tuple(int(i) for i in np.argwhere(bad)[0][:-1])
    at = f" at index {index}" if index else ""
    value = ""
    if given.shape[:-1] == result.shape[:-1]:
        value = " " + shorten(given[index].tolist())
    raise InputError(f"{name}{at}:{value} is too large: the {what} overflow (not finite); give values of physical size")


@dataclass(frozen=True)
class IKResult:
    """Inverse kinematics of one twist or a stack of twists (:meth:`Robot.ik`).

    Attributes
    ----------
    wheel_speeds : ndarray, shape (..., n)
        Speeds [rad/s] of the rolling wheels (all but castors), in file order.
    steer_angles : ndarray, shape (..., n_steer)
        Steering angles [rad] of the steerable wheels, relative to their ``drive`` direction.
    violation : ndarray, shape (..., n_fixed)
        Side-slip speed [m/s] each fixed (standard) wheel would need.
    steer_limited : ndarray of bool, shape (..., n_steer)
        True where no alignment lies within the steering limits (or, for an off-centred
        wheel, no steady alignment exists at all).
    feasible : ndarray of bool, shape (...)
        True where no fixed wheel slides and every steering is within limits.
    """

    wheel_speeds: np.ndarray
    steer_angles: np.ndarray
    violation: np.ndarray
    steer_limited: np.ndarray

    @property
    def feasible(self) -> np.ndarray:
        """True where no fixed wheel slides and every steering is within limits."""
        ok = np.all(np.abs(self.violation) <= 1e-9, axis=-1)
        return ok & ~np.any(self.steer_limited, axis=-1)


@dataclass(frozen=True)
class FKResult:
    """Forward kinematics of wheel speeds (:meth:`Robot.fk`).

    Attributes
    ----------
    twist : ndarray, shape (..., 3)
        Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s], velocity of the body origin in body
        axes: the least-squares fit over the admissible motions.
    residual : ndarray, shape (..., n_rows)
        Readings minus the fit's prediction [rad/s]: one row per wheel read, then one row per
        steerable wheel (its side slip over its radius).
    residual_norm : ndarray, shape (...)
        Euclidean norm of ``residual`` [rad/s].
    """

    twist: np.ndarray
    residual: np.ndarray

    @property
    def residual_norm(self) -> np.ndarray:
        """Euclidean norm of the residual, scaled so that it does not overflow for huge readings."""
        scale = np.max(np.abs(self.residual), axis=-1, keepdims=True, initial=0.0)
        safe = np.where(scale > 0, scale, 1.0)
        return np.linalg.norm(self.residual / safe, axis=-1) * safe[..., 0]


def steering_beyond(wheel: str, value: float, lower: float, upper: float) -> str:
    """``wheel 'w' steered to V rad (D deg), outside its limits [lo, hi] deg`` (or ``beyond
    +-MAX_ANGLE rad`` for a wheel that turns all the way round), printed with the digits that
    tell ``value`` from the limit it passes (:func:`~omnikin.common.messages.digits_apart`)."""
    if math.isinf(lower) or upper >= MAX_ANGLE:
        p = digits_apart(abs(value), MAX_ANGLE)
        limits = f"beyond +-{MAX_ANGLE:g} rad"
    else:
        lo, hi = math.degrees(lower), math.degrees(upper)
        p = digits_apart(math.degrees(value), lo if value < lower else hi)
        limits = f"outside its limits [{lo:.{p}g}, {hi:.{p}g}] deg"
    return f"wheel {wheel!r} steered to {value:.{p}g} rad ({math.degrees(value):.{p}g} deg), {limits}"


@dataclass(frozen=True)
class Robot:
    """A wheeled mobile robot: a name and its wheels (see :mod:`omnikin.kinematics.wheels`).

    Construction validates the layout: unique wheel names, at least one rolling
    wheel, some motion left by the fixed wheels, and every admissible motion
    turning at least one wheel. A singular layout raises
    :class:`~omnikin.errors.SingularLayoutError` saying why.

    Arrays of wheel quantities follow the order of ``wheels`` (docs/conventions.md): ``n`` the
    rolling wheels (all but castors), ``n_steer`` the steerable ones, ``n_fixed`` the standard ones.

    Parameters
    ----------
    name : str
        1 to 128 printable characters, no blank at either end.
    wheels : sequence of Wheel
        The wheels, in file order; names unique and none derived from another's
        (docs/conventions.md, "Names").
    description : str, default ""
        Free text.
    references : sequence of str, default ()
        Literature describing the robot.
    physical : PhysicalBody or None, default None
        Physical fields of the chassis (see the attribute below).
    design : Robot or None, default None
        For a robot as built, the robot it was built to (see the attribute below).
    sensors : sequence of Imu, Lidar or Bumper, default ()
        The sensors it carries (see the attribute below).

    Raises
    ------
    InputError
        A bad name, a wheel that is not a :class:`~omnikin.kinematics.wheels.Wheel`, colliding wheel names,
        or a ``design`` with other wheels.
    SingularLayoutError
        No rolling wheel, an immobile layout, or a motion that turns no wheel.
    """

    name: str
    wheels: tuple[Wheel, ...]
    description: str = ""
    references: tuple[str, ...] = field(default_factory=tuple)
    physical: PhysicalBody | None = None
    """Physical fields of the chassis (mass, centre of mass, thickness) for physics engines;
    None: derived from the layout (:mod:`omnikin.physics.description`)."""
    design: Robot | None = None
    """For a robot as built (:meth:`omnikin.simulation.error_models.SystematicErrors.apply`), the
    robot it was built to: the same wheel names in the same order, its own ``design`` None.
    A physics description takes the body from it (chassis, masses, motors: the errors move only
    what they name, :func:`omnikin.physics.description.describe`), and a wheel controller whose
    speed loop closes on its encoder counts by its scale. None: this robot is its own design. A
    robot file holds no design (what it describes is one)."""
    sensors: tuple[Sensor, ...] = ()
    """The sensors it carries besides the encoders (:mod:`omnikin.kinematics.sensors`): IMUs,
    lidars, bumpers; names unique, none a wheel's."""

    def __post_init__(self):
        problem = robot_name_problem(self.name)
        if problem:
            raise InputError(f"robot name: {problem}")
        object.__setattr__(self, "wheels", tuple(self.wheels))
        object.__setattr__(self, "references", tuple(self.references))
        for i, w in enumerate(self.wheels):
            if not isinstance(w, Wheel):
                raise InputError(f"robot {self.name!r}: wheel #{i + 1} is not a Wheel, got {shorten(w)}")
        if self.physical is not None and not isinstance(self.physical, PhysicalBody):
            raise InputError(
                f"robot {self.name!r}: physical must be a PhysicalBody or None, got {shorten(self.physical)}"
            )
        collisions = name_collisions([w.name for w in self.wheels])
        if collisions:
            raise InputError(f"robot {self.name!r}: {collisions[0][1]}")
        object.__setattr__(self, "sensors", tuple(self.sensors))
        seen = {w.name for w in self.wheels}
        for i, sensor in enumerate(self.sensors):
            if not isinstance(sensor, (Imu, Lidar, Bumper)):
                raise InputError(
                    f"robot {self.name!r}: sensor #{i + 1} is not an Imu, Lidar or Bumper, got {shorten(sensor)}"
                )
            if sensor.name in seen:
                raise InputError(
                    f"robot {self.name!r}: sensor {sensor.name!r}: its name is also a wheel's or another sensor's"
                )
            seen.add(sensor.name)
        if self.design is not None:
            if not isinstance(self.design, Robot) or self.design.design is not None:
                raise InputError(
                    f"robot {self.name!r}: design must be a Robot that is its own design, or None, "
                    f"got {shorten(self.design)}"
                )
            if self.design.wheel_names != self.wheel_names:
                raise InputError(
                    f"robot {self.name!r} was not built to its design {self.design.name!r}: wheels "
                    f"{shorten(self.wheel_names)}, not {shorten(self.design.wheel_names)}"
                )
        if not self.rolling:
            raise SingularLayoutError(
                f"robot {self.name!r}: no rolling wheel (castors alone cannot move or measure it)"
            )
        self._check_layout()

    # --- wheel groups ---------------------------------------------------------
    @cached_property
    def rolling(self) -> tuple[Wheel, ...]:
        """Wheels with a rolling row (all but castors), in file order."""
        return tuple(w for w in self.wheels if not w.is_castor)

    @cached_property
    def steerable(self) -> tuple[Wheel, ...]:
        return tuple(w for w in self.wheels if w.is_steerable)

    @cached_property
    def fixed(self) -> tuple[Wheel, ...]:
        return tuple(w for w in self.wheels if w.is_fixed)

    @cached_property
    def encoded(self) -> tuple[Wheel, ...]:
        """Rolling wheels with an encoder (the measured, usually driven, wheels), in file order."""
        return tuple(w for w in self.rolling if w.encoder is not None)

    @property
    def wheel_names(self) -> list[str]:
        """Names of every wheel, in file order (castors included)."""
        return [w.name for w in self.wheels]

    @property
    def rolling_names(self) -> list[str]:
        """Names of the rolling wheels (all but castors): the order of every wheel-speed array."""
        return [w.name for w in self.rolling]

    @property
    def encoded_names(self) -> list[str]:
        """Names of the encoded wheels: the order of every tick or wheel-angle array."""
        return [w.name for w in self.encoded]

    @property
    def steer_names(self) -> list[str]:
        return [w.name for w in self.steerable]

    def rad_per_tick(self, names=None) -> np.ndarray:
        """Encoder scale [rad per tick, signed by ``invert``] of the encoded wheels ``names``
        (default: all of them, file order); a wheel without an encoder is an error.

        Parameters
        ----------
        names : sequence of str, optional
            Wheels with an encoder; default all encoded wheels, file order.

        Returns
        -------
        ndarray, shape (len(names),)
            Wheel angle per tick [rad], negative for an inverted encoder.

        Raises
        ------
        InputError
            An unknown wheel, or one without an encoder.
        """
        wheels = self.encoded if names is None else [self.wheel(n) for n in names]
        out = []
        for w in wheels:
            if w.encoder is None:
                raise InputError(f"robot {self.name!r}: wheel {w.name!r} has no encoder")
            out.append(w.encoder.rad_per_tick)
        return np.array(out, dtype=float)

    def rolling_index(self, names) -> list[int]:
        """Positions of the rolling wheels ``names`` in a wheel-speed array (one dictionary
        look-up each); a castor or unknown name is an error.

        Parameters
        ----------
        names : sequence of str
            Rolling wheel names.

        Returns
        -------
        list of int
            Index of each along the last axis of :meth:`wheel_speeds` (``n``).

        Raises
        ------
        InputError
            A castor, an unknown name or one that is not text.
        """
        index = self._rolling_index
        try:
            return [index[n] for n in names]
        except (KeyError, TypeError):
            bad = next(n for n in names if not isinstance(n, str) or n not in index)
            raise InputError(
                f"robot {self.name!r} has no rolling wheel {shorten(bad)} "
                f"(rolling wheels: {shorten(self.rolling_names)})"
            ) from None

    @cached_property
    def _rolling_index(self) -> dict[str, int]:
        return {w.name: i for i, w in enumerate(self.rolling)}

    @cached_property
    def _by_name(self) -> dict[str, Wheel]:
        return {w.name: w for w in self.wheels}

    def wheel(self, name: str) -> Wheel:
        """The wheel called ``name`` (a dictionary look-up).

        Parameters
        ----------
        name : str

        Returns
        -------
        Wheel

        Raises
        ------
        InputError
            No wheel of that name (the message lists the wheels).
        """
        try:
            return self._by_name[name]
        except (KeyError, TypeError):
            raise InputError(
                f"robot {self.name!r} has no wheel {shorten(name)} (wheels: {shorten(self.wheel_names)})"
            ) from None

    # --- matrices ---------------------------------------------------------------
    def _steer_array(self, steer, name: str = "steer", *, within_limits: bool = True) -> np.ndarray:
        """Steering angles ``(..., n_steer)`` [rad], checked (docs/conventions.md, "Angles"): real
        and finite; a wheel with steering limits within them (:data:`STEER_LIMIT_SLACK`), a wheel
        that turns all the way round (limits -180 .. 180 deg) any angle up to
        :data:`~omnikin.kinematics.se2.MAX_ANGLE` in size (an orientation; the interval steering of
        odometry may cross +-180 deg). Else an InputError naming ``name``, the wheel and the angle.
        ``within_limits=False``: a preference, not a steering (the hint of :meth:`ik`, zero by
        default even for a wheel whose limits exclude zero), checked for its size only."""
        if steer is None:
            return np.zeros(len(self.steerable))
        if not self.steerable:
            if np.size(steer):
                raise InputError(f"robot {self.name!r} has no steerable wheel: do not pass steering angles")
            return np.zeros(0)
        arr = as_components(steer, len(self.steerable), name)
        require_finite(arr, name)
        free = np.full(len(self.steerable), np.inf)
        lower, upper = self.steer_limits if within_limits else (-free, free)
        outside = (arr < lower - STEER_LIMIT_SLACK) | (arr > upper + STEER_LIMIT_SLACK) | (np.abs(arr) > MAX_ANGLE)
        if outside.any():
            index = tuple(int(i) for i in np.argwhere(outside)[0])
            k = index[-1]
            at = f" at index {index[:-1]}" if len(index) > 1 else ""
            value = float(arr[index])
            raise InputError(
                f"{name}{at}: {steering_beyond(self.steerable[k].name, value, lower[k], upper[k])} "
                f"(steering angles are in radians, relative to the wheel's drive_deg)"
            )
        return arr

    @cached_property
    def steer_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Steering limits ``(lower, upper)``, each ``(n_steer,)`` [rad, relative to the wheel's
        drive direction], over the steerable wheels in file order: each wheel's ``steer.lower``
        and ``steer.upper``, or ``-inf`` and ``+inf`` for a wheel that turns all the way round
        (no ``steer``, or limits -180 .. 180 deg: any orientation, up to
        :data:`~omnikin.kinematics.se2.MAX_ANGLE` in size). The model accepts an angle up to
        :data:`STEER_LIMIT_SLACK` beyond a finite limit (round-off of a conversion from degrees).
        Read-only arrays, for good (:func:`~omnikin.common.arrays.frozen`: the robot keeps them)."""
        lims = [(w.steer.lower, w.steer.upper) if w.steer is not None else (-np.pi, np.pi) for w in self.steerable]
        full = [hi - lo >= 2 * np.pi - 1e-9 for lo, hi in lims]
        lower = np.array([-np.inf if f else lo for (lo, _), f in zip(lims, full, strict=True)])
        upper = np.array([np.inf if f else hi for (_, hi), f in zip(lims, full, strict=True)])
        return frozen(lower), frozen(upper)

    def _steer_of(self, steer: np.ndarray) -> dict[str, np.ndarray]:
        return {w.name: steer[..., i] for i, w in enumerate(self.steerable)}

    def jacobian(self, steer=None, wheels: Sequence[str] | None = None) -> np.ndarray:
        """Wheel Jacobian ``(..., n, 3)``: ``omega = J twist`` [rad/s per twist].

        Without steerable wheels the matrix is constant: it is built once and returned
        read-only for good (:func:`~omnikin.common.arrays.frozen`; copy it to modify it).

        Parameters
        ----------
        steer : array_like, shape (..., n_steer), optional
            Steering angles [rad] relative to each wheel's drive direction; default zero.
        wheels : sequence of str, optional
            Rolling wheels whose rows to give, in that order; default all, file order.

        Returns
        -------
        ndarray, shape (..., len(wheels), 3)
            Rolling rows ``[cos a, sin a, x sin a - y cos a] / (r cos gamma)``,
            ``a = delta + gamma`` (docs/conventions.md, "Wheels"), in [rad/s] per
            ``(m/s, m/s, rad/s)``.

        Raises
        ------
        InputError
            Steering angles of the wrong shape, not finite or outside the wheels' limits; an
            unknown wheel name.
        """
        if wheels is None and self._constant_at(steer):
            return self._jacobian_constant
        return self._jacobian(self._steer_array(steer), wheels)

    def _jacobian(self, steer: np.ndarray, wheels: Sequence[str] | None) -> np.ndarray:
        """:meth:`jacobian` at checked steering angles ``steer`` (:meth:`_steer_array`)."""
        by = self._steer_of(steer)
        chosen = self.rolling if wheels is None else [self.wheel(n) for n in wheels]
        rows = [w.rolling_row(by.get(w.name, 0.0)) for w in chosen]
        if not rows:  # no wheel asked for: an empty (..., 0, 3) matrix, not a stacking error
            return np.zeros(steer.shape[:-1] + (0, 3))
        shape = np.broadcast_shapes(*[r.shape for r in rows])
        return np.stack([np.broadcast_to(r, shape) for r in rows], axis=-2)

    def _constant_at(self, steer) -> bool:
        """True when the matrices do not depend on ``steer``: no steerable wheel, no angles given."""
        return not self.steerable and (steer is None or not np.size(steer))

    @cached_property
    def _jacobian_constant(self) -> np.ndarray:
        return frozen(np.stack([w.rolling_row() for w in self.rolling]))

    @property
    def ik_matrix(self) -> np.ndarray:
        """``J`` at zero steering ``(n, 3)``."""
        return self.jacobian()

    @cached_property
    def fixed_constraints(self) -> np.ndarray:
        """Sliding rows ``C_f`` ``(n_fixed, 3)`` of the fixed standard wheels (read-only for good)."""
        return frozen(np.array([w.sliding_row() for w in self.fixed]).reshape(-1, 3))

    @cached_property
    def admissible_basis(self) -> np.ndarray:
        """Orthonormal basis ``N`` ``(3, k)`` of twists the fixed wheels allow (read-only for good)."""
        return frozen(null_space(self.fixed_constraints, 3))

    def fk_rows(self, steer=None, wheels: Sequence[str] | None = None) -> np.ndarray:
        """Rows ``A = [J; S/r]`` ``(..., n_rows, 3)`` that forward kinematics fits (module docstring).

        ``J``: rolling rows of the chosen wheels; ``S/r``: sliding rows of the chosen steerable
        wheels over their radii (:meth:`omnikin.kinematics.wheels.Wheel.swivel_row`). ``steer``
        ``(..., n_steer)`` [rad].

        Parameters
        ----------
        steer : array_like, shape (..., n_steer), optional
            Steering angles [rad] relative to each wheel's drive direction; default zero.
        wheels : sequence of str, optional
            Rolling wheels read, in that order; default all, file order.

        Returns
        -------
        ndarray, shape (..., n_rows, 3)
            ``n_rows = len(wheels)`` rolling rows [rad/s per twist], then one sliding row per
            chosen steerable wheel [rad/s per twist].

        Raises
        ------
        InputError
            Bad steering angles (as :meth:`jacobian`) or an unknown wheel name.
        """
        return self._fk_rows(self._steer_array(steer), wheels)

    def _fk_rows(self, steer: np.ndarray, wheels: Sequence[str] | None) -> np.ndarray:
        """:meth:`fk_rows` at checked steering angles ``steer`` (:meth:`_steer_array`)."""
        jac = self._jacobian(steer, wheels)
        chosen = {w.name for w in (self.rolling if wheels is None else [self.wheel(n) for n in wheels])}
        by = self._steer_of(steer)
        extra = [w.swivel_row(by[w.name]) / w.radius for w in self.steerable if w.name in chosen]
        if not extra:
            return jac
        shape = np.broadcast_shapes(jac.shape[:-2], *[e.shape[:-1] for e in extra])
        sliding = np.stack([np.broadcast_to(e, shape + (3,)) for e in extra], axis=-2)
        return np.concatenate([np.broadcast_to(jac, shape + jac.shape[-2:]), sliding], axis=-2)

    def fk_matrix(self, steer=None, wheels: Sequence[str] | None = None) -> np.ndarray:
        """Forward-kinematics operator ``(..., 3, n_rows)``: ``twist = F [omega; 0]``.

        Without steerable wheels the operator is constant: it is computed once per wheel
        subset and returned read-only for good (:func:`~omnikin.common.arrays.frozen`; copy it to
        modify it).

        Parameters
        ----------
        steer : array_like, shape (..., n_steer), optional
            Steering angles [rad] relative to each wheel's drive direction; default zero.
        wheels : sequence of str, optional
            Rolling wheels read, in that order; default all, file order.

        Returns
        -------
        ndarray, shape (..., 3, n_rows)
            ``F = N pinv(A N)`` (:meth:`fk_rows` ``A``, :attr:`admissible_basis` ``N``): body
            twist [m/s, m/s, rad/s] per wheel speed [rad/s], the sliding rows' inputs zero.

        Raises
        ------
        InputError
            Bad steering angles (as :meth:`jacobian`) or an unknown wheel name.
        """
        constant = self._constant_at(steer)
        key = wheels = None if wheels is None else tuple(wheels)
        if constant and key in self._fk_cache:
            return self._fk_cache[key]
        f = self._fk_operator(self._fk_rows(self._steer_array(steer), wheels))
        if constant:
            f = self._fk_cache[key] = frozen(f)
        return f

    @cached_property
    def _fk_cache(self) -> dict:
        return {}

    _CACHES = (
        "_jacobian_constant",
        "_fk_cache",
        "_by_name",
        "_rolling_index",
        "steer_limits",
        "fixed_constraints",
        "admissible_basis",
        "generic_configuration",
    )

    def __getstate__(self):
        """Pickle and deepcopy without the read-only caches (NumPy does not keep the read-only
        flag through them); a copy rebuilds its own."""
        return {k: v for k, v in self.__dict__.items() if k not in self._CACHES}

    def _fk_operator(self, a: np.ndarray) -> np.ndarray:
        """``N pinv(A N)`` for fitted rows ``A`` ``(..., n_rows, 3)`` (module docstring)."""
        n = self.admissible_basis
        return n @ np.linalg.pinv(a @ n, rcond=RANK_TOL)

    def fk_rank(self, steer=None, wheels: Sequence[str] | None = None) -> int:
        """How many independent motion components the wheels determine at ``steer``.

        Parameters
        ----------
        steer : array_like, shape (n_steer,), optional
            Steering angles [rad]; default zero.
        wheels : sequence of str, optional
            Rolling wheels read; default all.

        Returns
        -------
        int
            Rank (0 .. 3) of the fitted rows over the admissible motions.
        """
        a = self._fk_rows(self._steer_array(steer), wheels)
        return rank(a @ self.admissible_basis)

    # --- analysis ------------------------------------------------------------------
    @cached_property
    def generic_configuration(self) -> Configuration:
        """A generic admissible configuration (:func:`omnikin.kinematics.mobility.generic_configuration`),
        its arrays read-only for good (the robot's mobility is computed from it)."""
        config = generic_configuration(self.wheels)
        return Configuration(*(frozen(getattr(config, f.name)) for f in fields(config)))

    @cached_property
    def mobility(self) -> Mobility:
        """Rank, Campion type, holonomy and conditioning (:mod:`omnikin.kinematics.mobility`)."""
        return analyse(self.wheels, self.generic_configuration)

    def _check_layout(self) -> None:
        config = self.generic_configuration
        if config.admissible.shape[1] == 0:
            names = [w.name for w in self.fixed] + [w.name for w in self.steerable if w.is_centred_steerable]
            raise SingularLayoutError(
                f"robot {self.name!r}: immobile layout: the no-side-slip constraints of wheels "
                f"{shorten(names)} admit no motion (degree of mobility 0)"
            )
        if not self.steerable:
            # with steerable wheels some motions are made by steering alone (e.g. spinning about a
            # centred steered wheel): observability is then checked where it matters, by odometry
            self._check_observable(None, config)

    def _check_observable(self, wheels: Sequence[str] | None, config: Configuration) -> None:
        """Every admissible motion must turn at least one of ``wheels``."""
        a = self._fk_rows(np.asarray(config.steer, dtype=float), wheels)
        basis = config.admissible
        m = a @ basis
        if rank(m) == basis.shape[1]:
            return
        z = np.linalg.svd(m)[2][-1]
        eta = basis @ z
        used = self.rolling_names if wheels is None else list(wheels)
        if abs(eta[2]) > 1e-9:
            cx, cy = (0.0 if abs(c) < 1e-12 else c for c in (-eta[1] / eta[2], eta[0] / eta[2]))
            why = (
                f"a rotation about the point ({cx:.6g}, {cy:.6g}) m turns none of them: "
                f"every drive line passes through it"
            )
        else:
            d = [0.0 if abs(c) < 1e-12 else c for c in eta[:2] / np.hypot(eta[0], eta[1])]
            why = (
                f"a translation along ({d[0]:.6g}, {d[1]:.6g}) turns none of them: "
                f"every rolling direction is perpendicular to it"
            )
        hint = ""
        if any(w.is_centred_steerable for w in self.steerable):
            hint = " (that motion is made by steering alone; wheel speeds cannot measure it)"
        raise SingularLayoutError(
            f"robot {self.name!r}: singular layout: wheels {shorten(used)} cannot realise or measure "
            f"every motion the robot can make; {why}{hint} (wheel Jacobian rank {rank(m)} < {basis.shape[1]})"
        )

    def check_observable(self, wheels: Sequence[str]) -> None:
        """Raise unless the wheels ``wheels`` (e.g. the encoded ones) observe every motion.

        Parameters
        ----------
        wheels : sequence of str
            Rolling wheel names.

        Raises
        ------
        SingularLayoutError
            An admissible motion turns none of ``wheels`` (the message names it: a rotation
            about a point [m] or a translation direction, body frame).
        """
        self._check_observable(list(wheels), self.generic_configuration)

    # --- kinematics ------------------------------------------------------------------
    def body_twist(self, velocity, heading) -> np.ndarray:
        """World-frame rates ``(xdot, ydot, thetadot)`` at ``heading`` [rad] -> body twist.

        ``(vx, vy) = R(theta)^T (xdot, ydot)``, ``omega = thetadot`` (docs/conventions.md,
        "Frames and units").

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            World-frame (``odom``) rates ``(xdot, ydot, thetadot)`` [m/s, m/s, rad/s].
        heading : array_like, shape (...)
            Heading ``theta`` [rad] of the body in the world frame: real, finite, at most
            :data:`~omnikin.kinematics.se2.MAX_ANGLE` in size; broadcasts with ``velocity``'s leading
            axes.

        Returns
        -------
        ndarray, shape (..., 3)
            Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] in body axes.

        Raises
        ------
        InputError
            Not three components, a bad heading, or a result that overflows.
        """
        v = as_components(velocity, 3, "velocity")
        th = heading_array(heading)
        c, s = np.cos(th), np.sin(th)
        out = np.empty(np.broadcast_shapes(v.shape, th.shape + (3,)))
        with _checked_after():
            out[..., 0] = c * v[..., 0] + s * v[..., 1]
            out[..., 1] = -s * v[..., 0] + c * v[..., 1]
        out[..., 2] = v[..., 2]
        _refuse_overflow(out, "body twist", "velocity", v)
        return out

    def ik(self, twist, *, heading=None, steer_hint=None, on_infeasible: str = "raise") -> IKResult:
        """Inverse kinematics: body twist ``(..., 3)`` -> wheel speeds and steering.

        With ``heading`` [rad] the input is the world-frame velocity
        ``(xdot, ydot, thetadot)``. Steerable wheels are aligned with the motion of
        their hub (off-centred ones at their steady swivel angle, where
        ``n . v_p = offset * omega``), choosing the branch within the steering limits
        closest to ``steer_hint`` (default: zero). ``on_infeasible``: ``"raise"``
        (default) raises :class:`InfeasibleTwistError` naming the wheel and the
        side-slip speed; ``"return"`` reports it in ``IKResult.violation``.

        Parameters
        ----------
        twist : array_like, shape (..., 3)
            Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] in body axes, or with ``heading``
            the world-frame rates ``(xdot, ydot, thetadot)``.
        heading : array_like, shape (...), optional
            Heading [rad] at which ``twist`` is a world-frame velocity (:meth:`body_twist`).
        steer_hint : array_like, shape (..., n_steer), optional
            Preferred steering angles [rad] for choosing between the two alignments of each
            steerable wheel; default zero.
        on_infeasible : {"raise", "return"}, default "raise"
            What a twist the wheels cannot make does.

        Returns
        -------
        IKResult
            Wheel speeds ``(..., n)`` [rad/s], steering angles ``(..., n_steer)`` [rad], side-slip
            speeds ``(..., n_fixed)`` [m/s] and the steering-limit flags.

        Raises
        ------
        InfeasibleTwistError
            With ``on_infeasible="raise"``: a fixed wheel would slide or a steering would leave
            its limits (the first such wheel is named).
        InputError
            A twist or hint of the wrong shape, not finite, or overflowing.
        """
        if on_infeasible not in ("raise", "return"):
            raise InputError(f"on_infeasible must be 'raise' or 'return', got {shorten(on_infeasible)}")
        t = as_components(twist, 3, "twist")
        require_finite(t, "twist")
        if heading is not None:
            t = self.body_twist(t, heading)
        hint = self._steer_array(steer_hint, "steer_hint", within_limits=False)
        if hint.ndim > 1 and np.broadcast_shapes(hint.shape[:-1], t.shape[:-1]) != t.shape[:-1]:
            raise InputError(f"steer_hint: shape {hint.shape} does not fit twists of shape {t.shape}")
        with _checked_after():
            steer, limited = self._steer_for(t, hint, strict=on_infeasible == "raise")
            speeds = np.einsum("...ij,...j->...i", self._jacobian(steer, None), t)
            violation = t @ self.fixed_constraints.T
        given = np.asarray(twist, dtype=float)
        for values, what in ((speeds, "wheel speeds"), (steer, "steering angles"), (violation, "side-slip speeds")):
            _refuse_overflow(values, what, "twist", given)
        result = IKResult(speeds, steer, violation, limited)
        if on_infeasible == "raise" and not np.all(result.feasible):
            detail = self._infeasible_detail(t, violation, limited)
            raise InfeasibleTwistError(
                f"{detail} (on_infeasible='return' reports the violation instead)", detail=detail
            )
        return result

    def _infeasible_detail(self, t, violation, limited) -> str:
        """What makes the twist infeasible (first wheel), without the way out."""
        scale = 1e-9
        bad = np.argwhere(np.abs(violation) > scale)
        if bad.size:
            idx = tuple(bad[0][:-1])
            w = self.fixed[int(bad[0][-1])]
            return (
                f"robot {self.name!r}: twist {np.round(t[idx], 9).tolist()} is infeasible: fixed wheel "
                f"{w.name!r} would slide sideways at {violation[tuple(bad[0])]:.6g} m/s"
            )
        idx = np.argwhere(limited)[0]
        w = self.steerable[int(idx[-1])]
        lo, hi = (w.steer.lower, w.steer.upper) if w.steer is not None else (-np.pi, np.pi)
        return (
            f"robot {self.name!r}: twist {np.round(t[tuple(idx[:-1])], 9).tolist()} needs wheel {w.name!r} "
            f"steered outside its limits [{np.degrees(lo):.6g}, {np.degrees(hi):.6g}] deg"
        )

    def _steer_for(self, t: np.ndarray, hint: np.ndarray, strict: bool = True):
        """Steering angles ``(..., n_steer)`` aligning each steerable wheel with the motion."""
        shape = t.shape[:-1] + (len(self.steerable),)
        steer = np.zeros(shape)
        limited = np.zeros(shape, dtype=bool)
        for i, w in enumerate(self.steerable):
            steer[..., i], limited[..., i] = w.align(t, np.broadcast_to(hint[..., i], t.shape[:-1]), strict)
        return steer, limited

    def wheel_speeds(self, twist) -> np.ndarray:
        """Fast inverse kinematics ``(..., n)`` [rad/s] for layouts without steering.

        Parameters
        ----------
        twist : array_like, shape (..., 3)
            Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] in body axes.

        Returns
        -------
        ndarray, shape (..., n)
            Speeds [rad/s] of the rolling wheels, file order: ``J twist`` (:meth:`jacobian`).
            With steerable wheels the same as ``ik(twist).wheel_speeds``.

        Raises
        ------
        InputError
            Not three components or an overflowing result (with steerable wheels: as :meth:`ik`,
            which also raises :class:`InfeasibleTwistError`).
        """
        if self.steerable:
            return self.ik(twist).wheel_speeds
        t = as_components(twist, 3, "twist")
        with _checked_after():
            speeds = t @ self.ik_matrix.T
        _refuse_overflow(speeds, "wheel speeds", "twist", t)
        return speeds

    def fk(self, wheel_speeds, steer=None, wheels: Sequence[str] | None = None) -> FKResult:
        """Forward kinematics: wheel speeds ``(..., n)`` [rad/s] -> body twist.

        ``steer`` ``(..., n_steer)`` [rad] is required when the robot has steerable
        wheels. ``wheels`` names a subset of rolling wheels (e.g. the encoded ones)
        that ``wheel_speeds`` refers to; default all rolling wheels.

        The twist is the unweighted least-squares fit over the admissible motions,
        ``twist = N pinv(A N) [omega; 0]`` with ``A`` the rows of :meth:`fk_rows` and ``N`` the
        :attr:`admissible_basis` (docs/conventions.md, "Forward kinematics").

        Parameters
        ----------
        wheel_speeds : array_like, shape (..., len(wheels))
            Wheel speeds [rad/s] of ``wheels`` in that order.
        steer : array_like, shape (..., n_steer), optional
            Steering angles [rad] of the steerable wheels; required when the robot has any.
        wheels : sequence of str, optional
            The rolling wheels ``wheel_speeds`` refers to; default all, file order.

        Returns
        -------
        FKResult
            Body twist ``(..., 3)`` [m/s, m/s, rad/s] and residual ``(..., n_rows)`` [rad/s].

        Raises
        ------
        InputError
            Speeds or steering angles of the wrong shape, not finite or overflowing; missing
            steering angles; an unknown wheel name.
        """
        names = self.rolling_names if wheels is None else list(wheels)
        w = as_components(wheel_speeds, len(names), "wheel_speeds")
        require_finite(w, "wheel_speeds")
        if self.steerable and steer is None:
            raise InputError(
                f"robot {self.name!r}: steerable wheels {shorten(self.steer_names)} need their steering angles "
                f"(steer=...)"
            )
        steer = self._steer_array(steer)
        a = self._fk_rows(steer, wheels)
        n_extra = a.shape[-2] - len(names)
        b = np.concatenate([w, np.zeros(w.shape[:-1] + (n_extra,))], axis=-1) if n_extra else w
        f = self._fk_operator(a) if self.steerable else self.fk_matrix(None, wheels)
        with _checked_after():
            twist = np.einsum("...ij,...j->...i", f, b)
            residual = b - np.einsum("...ij,...j->...i", a, twist)
        _refuse_overflow(twist, "twist", "wheel_speeds", w)
        _refuse_overflow(residual, "residuals", "wheel_speeds", w)
        return FKResult(twist, residual)

    def roller_speeds(self, twist) -> np.ndarray:
        """Roller surface speeds ``(..., n_swedish)`` [m/s] of the Swedish wheels.

        Positive along ``n = (-sin(delta+gamma), cos(delta+gamma))``; divide by the
        roller radius for its spin rate [rad/s].

        Parameters
        ----------
        twist : array_like, shape (..., 3)
            Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] in body axes.

        Returns
        -------
        ndarray, shape (..., n_swedish)
            Roller surface speed [m/s] of each Swedish wheel (:attr:`swedish_names`), file order.

        Raises
        ------
        InputError
            Not three components or an overflowing result.
        """
        t = as_components(twist, 3, "twist")
        rows = np.array([w.roller_row() for w in self.wheels if w.is_swedish]).reshape(-1, 3)
        with _checked_after():
            speeds = t @ rows.T
        _refuse_overflow(speeds, "roller speeds", "twist", t)
        return speeds

    @property
    def swedish_names(self) -> list[str]:
        return [w.name for w in self.wheels if w.is_swedish]
