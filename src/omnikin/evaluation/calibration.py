"""Calibration of the kinematic model from runs with measured end poses.

Two methods:

* :func:`borenstein_calibrate`: differential drives, Borenstein and Feng (1996): the
  UMBmark result's ``c_L``, ``c_R`` scale the left/right wheel radii and ``E_b`` the track
  (both wheels moved symmetrically about the axle midpoint). Iterating it (UMBmark again
  with the corrected model) removes what the first-order formulas leave.
* :func:`least_squares_calibration`: any layout. The robot drives known plans by its nominal model; the
  end poses are measured (weights: :func:`_weights`). Unknowns per driven (encoded) wheel (:func:`wheel_parameters`):
  Swedish wheels: relative radius error, ``lever`` (hub displacement [m] normal to the
  roller axis; along the axis it changes nothing) and drive direction error [rad];
  fixed standard wheels: radius and ``axle`` (displacement along the axle [m]; a toe or
  fore-aft error would make two rigid fixed wheels immobile, so it is not a kinematic
  parameter); steerable wheels: radius, ``dx, dy`` [m] and the steering offset ``drive``
  [rad] (the angle the steering reads when the wheel rolls along body x). For a candidate the
  true end pose of a plan is predicted in closed form: within a segment the commanded
  wheel angles grow in fixed proportion, so the true robot moves along
  ``exp(s * F_true J_cmd xi)`` (:mod:`omnikin.motion.timing`). SciPy's
  ``least_squares`` fits the predicted to the measured end poses (x, y in metres over the
  measurement sigma; heading, where measured, in radians over its sigma), with a weak
  Gaussian prior (``PRIOR``) that keeps combinations the runs cannot see at zero. The
  :class:`Identifiability` report names those combinations.

Encoder tick-count errors act exactly like radius errors on a wheel and are not
separable from them: the fitted radius absorbs both.

A run the robot cannot drive (a sideways line for a differential drive, a turn in place
for a car) is refused before fitting, by the check :func:`omnikin.simulation.kinematic.simulate_kinematic`
uses (:func:`~omnikin.simulation.kinematic.segment_rates`), naming the run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..common.messages import shorten
from ..errors import CalibrationFitError, InfeasibleRunError, InfeasibleTwistError, InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import compose, exp, wrap_angle
from ..motion.plans import UMBMARK_SIDE, CalibrationRun, Plan, parse_plan
from ..odometry.batch import encoded_wheels
from ..simulation.error_models import SystematicErrors, WheelErrors
from ..simulation.kinematic import segment_rates
from .umbmark import UMBmarkResult, check_side, differential_pair

BLIND = 2.0
"""A parameter direction whose data singular value (residuals in measurement sigmas per
prior sigma) is below this is reported as not observable: the runs pin it down less than
half as well as the prior does."""

PRIOR = {"radius": 0.05, "dx": 0.01, "dy": 0.01, "lever": 0.01, "axle": 0.01, "drive": math.radians(5.0)}
"""Prior standard deviations of the fitted parameters (units :data:`PARAMETER_UNITS`): ten
times the ``typical`` as-built profile, weak enough never to pull an observable parameter."""

PARAMETER_UNITS = {"radius": "relative", "dx": "m", "dy": "m", "lever": "m", "axle": "m", "drive": "rad"}
"""Unit of each fitted parameter: ``radius`` is relative (r_true = r (1 + radius)), hub
displacements in metres, the drive direction in radians."""

ERROR_UNITS = {"radius": "relative", "dx": "m", "dy": "m", "drive": "rad", "roller": "rad", "ticks": "relative"}
"""Unit of each per-wheel systematic error (:class:`~omnikin.simulation.error_models.WheelErrors`)."""

FIT_LIMIT = 3.0
"""Residual RMS [measurement sigmas] above which a calibration is reported as not fitting
its runs: the model cannot explain the measurements (a wrong robot file, a mislabelled run,
or errors the parameters do not cover); the calibrated robot should not be used."""

RECOMMENDED_REPEATS = 5
"""How often to drive each recommended calibration run (:func:`recommended_runs`)."""


class PlanSet:
    """Plans driven by a command model, prepared for fast closed-form end poses.

    Per segment ``s`` of every plan the commanded wheel angles per unit progress
    ``w_s = J_cmd(steer_s) xi_s`` over the encoded (driven) wheels do not depend on the
    true robot; :meth:`ends` then needs one forward-kinematics operator of the true
    robot, one matrix product, one vectorised exponential and a few compositions.
    """

    def __init__(self, plans: Sequence[Plan], command_robot: Robot):
        self.command = command_robot
        self.names = command_robot.encoded_names
        w: list[np.ndarray] = []
        steer: list[np.ndarray] = []
        length: list[float] = []
        owner: list[int] = []
        slot: list[int] = []
        for p, plan in enumerate(plans):
            rates, steering = segment_rates([seg.xi for seg in plan.segments], command_robot, self.names)
            w.extend(rates)
            steer.extend(steering)
            length.extend(seg.length for seg in plan.segments)
            owner.extend([p] * len(plan.segments))
            slot.extend(range(len(plan.segments)))
        self.w = np.array(w)
        self.steer = np.array(steer) if command_robot.steerable else None
        self.length = np.array(length)
        self.owner = np.array(owner)
        self.slot = np.array(slot)
        self.n_plans = len(plans)

    def ends(self, true_robot: Robot) -> np.ndarray:
        """End poses ``(n_plans, 3)`` of ``true_robot`` driving the plans (noise-free, exact)."""
        ratio = true_robot.rad_per_tick(self.names) / self.command.rad_per_tick(self.names)
        f = true_robot.fk_matrix(self.steer, self.names)[..., : len(self.names)]
        rates = self.w * ratio
        twist = np.einsum("ij,sj->si", f, rates) if f.ndim == 2 else np.einsum("sij,sj->si", f, rates)
        steps = exp(twist * self.length[:, None])
        pose = np.zeros((self.n_plans, 3))
        for k in range(int(self.slot.max()) + 1):
            sel = self.slot == k
            pose[self.owner[sel]] = compose(pose[self.owner[sel]], steps[sel])
        return pose


def predicted_end(plan: Plan, true_robot: Robot, command_robot: Robot) -> np.ndarray:
    """End pose ``(3,)`` of ``true_robot`` driving ``plan`` as commanded by ``command_robot``.

    Noise-free and exact: per segment the true body twist per unit progress is
    ``F_true (J_cmd xi * rpt_true / rpt_cmd)`` over the encoded (driven) wheels. A plan
    ``command_robot`` cannot drive raises :class:`~omnikin.errors.InfeasibleTwistError`.
    """
    return PlanSet([plan], command_robot).ends(true_robot)[0]


def _driven(robot: Robot):
    wheels = list(robot.encoded)
    if not wheels:
        raise InputError(f"robot {robot.name!r}: calibration needs the driven wheels' encoders")
    return wheels


def wheel_parameters(wheel) -> tuple[str, ...]:
    """Names of the fitted parameters of one driven wheel (module docstring)."""
    if wheel.is_fixed:
        return ("radius", "axle")
    if wheel.is_swedish:
        return ("radius", "lever", "drive")
    return ("radius", "dx", "dy", "drive")


def parameter_names(robot: Robot) -> list[str]:
    return [f"{w.name}.{p}" for w in _driven(robot) for p in wheel_parameters(w)]


def errors_from_vector(robot: Robot, p: np.ndarray) -> SystematicErrors:
    """Systematic errors of the parameter vector ``p`` (order of :func:`parameter_names`)."""
    out, k = {}, 0
    for w in _driven(robot):
        names = wheel_parameters(w)
        values = dict(zip(names, map(float, p[k : k + len(names)]), strict=True))
        k += len(names)
        dx, dy = values.get("dx", 0.0), values.get("dy", 0.0)
        if "axle" in values:  # along (-sin delta, cos delta)
            dx, dy = -math.sin(w.drive) * values["axle"], math.cos(w.drive) * values["axle"]
        if "lever" in values:  # normal to the roller axis delta + gamma
            a = w.drive + w.roller
            dx, dy = -math.sin(a) * values["lever"], math.cos(a) * values["lever"]
        out[w.name] = WheelErrors(radius=values["radius"], dx=dx, dy=dy, drive=values.get("drive", 0.0))
    return SystematicErrors(out)


@dataclass(frozen=True)
class Identifiability:
    """What the runs can see: singular values of the scaled Jacobian and the blind spots.

    ``blind`` lists, per unobservable direction (singular value below :data:`BLIND`),
    the parameters that make it up with their weights; ``sigma`` the posterior standard
    deviation of each parameter (prior included) in its unit.
    """

    parameters: list
    singular_values: list
    blind: list
    sigma: dict

    def as_dict(self) -> dict:
        return {
            "parameters": self.parameters,
            "singular_values": self.singular_values,
            "blind": self.blind,
            "sigma": self.sigma,
        }


@dataclass(frozen=True)
class CalibrationResult:
    """Fitted errors, the calibrated robot, residuals and the identifiability report.

    ``values``: the fitted parameters by name (``"w1.radius"``, order of
    :func:`parameter_names`), in the units of :data:`PARAMETER_UNITS`; ``errors``: the same
    as per-wheel systematic errors (:data:`ERROR_UNITS`); residuals as RMS of the weighted
    residuals [measurement sigmas].
    """

    nominal: Robot
    errors: SystematicErrors
    robot: Robot
    residual_before: float
    residual_after: float
    identifiability: Identifiability
    method: str = "least-squares"
    details: dict = field(default_factory=dict)
    values: dict = field(default_factory=dict)

    @property
    def fits(self) -> bool:
        """Whether the calibrated model explains the runs (residual RMS at most :data:`FIT_LIMIT`)."""
        return self.residual_after <= FIT_LIMIT

    def parameters(self) -> list[dict]:
        """The fitted parameters: ``[{"name", "value", "sigma", "unit"}, ...]``."""
        sigma = self.identifiability.sigma
        return [
            {"name": n, "value": float(v), "sigma": float(sigma[n]), "unit": PARAMETER_UNITS[n.rsplit(".", 1)[1]]}
            for n, v in self.values.items()
        ]

    def as_dict(self) -> dict:
        return {
            "method": self.method,
            "parameters": self.parameters(),
            "errors": self.errors.as_dict(),
            "residual_rms_before": self.residual_before,
            "residual_rms_after": self.residual_after,
            "fits": self.fits,
            "identifiability": self.identifiability.as_dict(),
            **self.details,
        }


def _weights(runs: Sequence[CalibrationRun], index: np.ndarray) -> np.ndarray:
    """Standard deviation ``(n_runs, 3)`` of each run's measured x, y, theta.

    The measurement sigma, combined with the run-to-run scatter of repeats of the same
    plan where there are at least three (wheel slip makes a 16 m square scatter far more
    than a half turn; weighting every run by the tape measure alone would let the
    noisiest runs dominate the fit).
    """
    sig = np.array([[r.sigma[0], r.sigma[0], r.sigma[1]] for r in runs], dtype=float)
    meas = np.array([r.measured for r in runs], dtype=float)
    for k in np.unique(index):
        sel = index == k
        if sel.sum() >= 3:
            m = meas[sel]
            m[:, 2] = np.unwrap(m[:, 2])
            spread = np.nanstd(m, axis=0, ddof=1)
            spread = np.where(np.isfinite(spread), spread, 0.0)
            sig[sel] = np.sqrt(sig[sel] ** 2 + spread**2)
    return sig


def _residuals(
    nominal: Robot, runs: Sequence[CalibrationRun], plans: PlanSet, index: np.ndarray, sigma: np.ndarray, p: np.ndarray
) -> np.ndarray:
    """Weighted residuals of all runs for the parameter vector ``p``."""
    ends = plans.ends(errors_from_vector(nominal, p).apply(nominal))[index]
    meas = np.array([r.measured for r in runs])
    res = (ends - meas) / sigma
    res[:, 2] = wrap_angle(ends[:, 2] - meas[:, 2]) / sigma[:, 2]
    return res[np.isfinite(res)]


def least_squares_calibration(
    nominal: Robot, runs: Sequence[CalibrationRun], command_robot: Robot | None = None
) -> CalibrationResult:
    """Least-squares calibration of ``nominal`` from ``runs`` (module docstring).

    ``command_robot``: the model the runs were driven by (default ``nominal``). A run it
    cannot drive raises :class:`InfeasibleRunError` naming the run.
    Returns the calibrated robot (``result.robot``): ``nominal`` with the fitted errors.
    """
    try:
        from scipy.optimize import least_squares
    except ImportError:
        raise ImportError("calibration needs SciPy: pip install scipy") from None
    if not runs:
        raise InputError("calibration needs at least one run with a measured end pose")
    command = command_robot or nominal
    names = parameter_names(nominal)
    scale = np.array([PRIOR[n.rsplit(".", 1)[1]] for n in names])

    unique = list(dict.fromkeys(r.plan for r in runs))
    check_drivable(runs, command)
    plans = PlanSet(unique, command)
    slot = {plan: k for k, plan in enumerate(unique)}
    index = np.array([slot[r.plan] for r in runs])

    sigma = _weights(runs, index)

    def fun(q):
        return np.concatenate([_residuals(nominal, runs, plans, index, sigma, q * scale), q])  # prior: q ~ N(0, 1)

    q0 = np.zeros(len(names))
    r0 = fun(q0)[: -len(names)]
    try:
        sol = least_squares(fun, q0, method="trf", x_scale=1.0, xtol=1e-12, ftol=1e-12, gtol=1e-12)
    except InputError as e:  # the fit left the robot file's ranges: no robot of this layout drove these runs
        raise CalibrationFitError(
            f"calibration: no robot of this layout explains the runs (the least-squares fit of radii, hub positions "
            f"and drive directions went out of range: {e}); check the measured end poses and that the robot drove "
            "as commanded"
        ) from None
    p = sol.x * scale
    r1 = sol.fun[: -len(names)]
    ident = _identifiability(names, sol.jac[: -len(names)], sol.jac, scale)
    errors = errors_from_vector(nominal, p)
    robot = errors.apply(nominal)
    robot = replace(nominal, wheels=robot.wheels, description=nominal.description + " (calibrated by omnikin)")
    return CalibrationResult(
        nominal,
        errors,
        robot,
        float(np.sqrt(np.mean(r0**2))),
        float(np.sqrt(np.mean(r1**2))),
        ident,
        details={"runs": len(runs), "cost": float(sol.cost), "nfev": int(sol.nfev)},
        values=dict(zip(names, map(float, p), strict=True)),
    )


def run_name(run: CalibrationRun, index: int) -> str:
    """How messages name a run: where it was read from, or its number, with its path."""
    where = run.source or f"run {index + 1}"
    return f"{where} ({shorten(run.label, 40)})" if run.label else where


def check_drivable(runs: Sequence[CalibrationRun], robot: Robot) -> None:
    """Refuse (:class:`InfeasibleRunError`, naming the first such run) a run ``robot`` cannot
    drive: the check :func:`~omnikin.simulation.kinematic.simulate_kinematic` makes
    (:func:`~omnikin.simulation.kinematic.segment_rates`)."""
    seen = set()
    for k, run in enumerate(runs):
        if run.plan in seen:
            continue
        seen.add(run.plan)
        try:
            segment_rates([seg.xi for seg in run.plan.segments], robot, robot.encoded_names)
        except InfeasibleTwistError as exc:
            reason = str(exc).split(" (on_infeasible=")[0].removeprefix(f"robot {robot.name!r}: ")
            raise InfeasibleRunError(
                f"{run_name(run, k)}: robot {robot.name!r} cannot drive this path: {reason}", run=k
            ) from None


def can_drive(plan: Plan, robot: Robot) -> bool:
    """Whether ``robot`` can drive ``plan`` (the check of :func:`check_drivable`)."""
    try:
        segment_rates([seg.xi for seg in plan.segments], robot, robot.encoded_names)
    except InfeasibleTwistError:
        return False
    return True


def _identifiability(names, jac_data, jac_full, scale) -> Identifiability:
    """Singular values of the data Jacobian (scaled: residual sigmas per prior sigma), blind
    directions (below :data:`BLIND`) and posterior sigmas of the parameters."""
    _, s, vt = np.linalg.svd(jac_data, full_matrices=True)
    s_all = np.concatenate([s, np.zeros(vt.shape[0] - s.size)])
    blind = []
    for k in np.flatnonzero(s_all < BLIND):
        v = vt[k]
        blind.append(
            [{"parameter": names[j], "weight": float(v[j])} for j in np.argsort(-np.abs(v)) if abs(v[j]) > 0.2]
        )
    cov = np.linalg.pinv(jac_full.T @ jac_full)
    sigma = {n: float(np.sqrt(max(cov[j, j], 0.0)) * scale[j]) for j, n in enumerate(names)}
    return Identifiability(names, [float(v) for v in s], blind, sigma)


def recommended_runs(robot: Robot, side: float = UMBMARK_SIDE) -> list[tuple[str, Plan]]:
    """A calibration protocol that sees every parameter it can for this layout.

    ``[(path, plan), ...]``, ``path`` in the runs-file grammar (:func:`omnikin.motion.plans.parse_plan`)
    and ``plan`` parsed from it; drive each :data:`RECOMMENDED_REPEATS` times and measure x,
    y and the heading at the end. The candidates, one rule for every robot: both UMBmark
    squares in ``rotate`` mode and in ``translate`` mode, straight lines of ``side`` along body
    x and y, half turns in place both ways, five full turns in place both ways, and half
    circles of radius ``side / 2`` left and right; the runs the robot cannot drive (the
    check of :func:`check_drivable`) are left out.
    The half turns see where the robot really turns about: a closed square hides an offset
    of that centre (its four corner shifts cancel), a half turn moves the origin by twice
    the offset. The five turns see the rotation scale (track over radius) ten times more
    sharply than a half turn against the same heading measurement error. The half circles
    stand in for the turns in place on robots that cannot turn in place (cars).
    """
    encoded_wheels(robot)  # the runs are measured through the encoders: refuse a robot without them
    side = check_side(side)  # the UMBmark square's bounds (squares and lines of this length)
    L, half = _number_text(side), _number_text(side / 2)
    candidates = [
        f"square cw rotate {L}",
        f"square ccw rotate {L}",
        f"line {L} 0",
        "spin 180",
        "spin -180",
        "spin 1800",
        "spin -1800",
        f"square cw translate {L}",
        f"square ccw translate {L}",
        f"line {L} 90",
    ]
    out = [(text, parse_plan(text)) for text in candidates]
    out = [(text, plan) for text, plan in out if can_drive(plan, robot)]
    if not any(text.startswith("spin") for text, _ in out):
        arcs = [(text, parse_plan(text)) for text in (f"arc {half} 180", f"arc {half} -180")]
        out += [(text, plan) for text, plan in arcs if can_drive(plan, robot)]
    if not out:
        raise InputError(f"robot {robot.name!r} can drive none of the calibration runs (squares, lines, turns, arcs)")
    return out


def _number_text(x: float) -> str:
    """``x`` as short as it reads back exactly (``4`` rather than ``4.0``; ``repr`` otherwise)."""
    short = f"{x:g}"
    return short if float(short) == x else repr(float(x))


def borenstein_calibrate(robot: Robot, result: UMBmarkResult) -> Robot:
    """Apply Borenstein's corrections of a differential-drive UMBmark ``result`` to ``robot``."""
    pair = differential_pair(robot)
    if pair is None or result.borenstein is None:
        raise InputError(
            f"robot {robot.name!r} is not a differential drive (two coaxial fixed encoded wheels): "
            f"Borenstein's correction does not apply; use the least-squares calibration"
        )
    left, right, track = pair
    b = result.borenstein
    mid = 0.5 * (left.y + right.y)
    wheels = []
    for w in robot.wheels:
        if w.name == left.name:
            w = replace(w, radius=w.radius * b.c_L, y=mid + b.b_new / 2)
        elif w.name == right.name:
            w = replace(w, radius=w.radius * b.c_R, y=mid - b.b_new / 2)
        wheels.append(w)
    return replace(robot, wheels=tuple(wheels))
