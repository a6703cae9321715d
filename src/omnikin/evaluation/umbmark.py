"""UMBmark (Borenstein and Feng, "Measurement and correction of systematic odometry errors
in mobile robots", 1996) as fixed in ``docs/conventions.md``.

Per run the return error is ``eps = abs - calc``: the true end pose minus the odometry
end pose [m, m, rad] (Tomasi and Todt, "Three wheeled omnidirectional mobile robot",
eq. 1-2). Per direction the centre of gravity of the n runs (eq. 3-4) and its distance
from the origin ``r_cg`` (eq. 5-6); ``E_max,syst = max(r_cg_cw, r_cg_ccw)``.

Confidence interval of ``E_max,syst`` (:meth:`UMBmarkResult.e_max_interval`): the quantity
estimated is ``max_d |mu_d|``, ``mu_d`` the expected return position of direction ``d``
(the systematic error; the centre of gravity estimates it). With run-to-run errors
independent and Gaussian, ``n (cg - mu)^T S^-1 (cg - mu)`` follows Hotelling's ``T^2(2, n - 1)``
distribution (``S`` the sample covariance of the n runs), so ``{mu : n (cg - mu)^T S^-1
(cg - mu) <= 2 (n - 1) / (n - 2) F_{2, n-2}(g)}`` is an exact confidence region of level ``g``
for ``mu_d``. Each direction's region at level ``g = sqrt(level)`` (the directions are
independent) bounds ``|mu_d|`` between its nearest and farthest point from the origin, and
``E_max,syst`` between the larger of the two nearest and the larger of the two farthest
distances: a conservative interval (coverage at least ``level``; projections of a region
are wider than an interval for one number). It needs at least 3 runs per direction.

For a differential drive (two coaxial fixed wheels; :func:`differential_pair`) Borenstein's
correction: ``alpha = (x_cw + x_ccw) / (-4L)``, ``beta = (x_cw - x_ccw) / (-4L)`` [rad],
``R = (L/2) / sin(beta/2)``, ``E_d = (R + b/2) / (R - b/2)`` (= D_R / D_L),
``E_b = 90 deg / (90 deg - alpha)``, ``c_L = 2 / (E_d + 1)``, ``c_R = 2 / (1/E_d + 1)``,
``b_new = E_b b``; ``x_cw``, ``x_ccw`` are the x coordinates of the centres of gravity.
``alpha > 0``: under-rotation at every corner; ``beta > 0``: straight legs curve left.
With the first leg along +x and cw turning right, a corner under-rotation alpha gives
``x_cw = x_ccw = -2 L alpha`` and a leg curvature beta gives ``x_cw = -x_ccw = -2 L beta``
to first order, which is what the two formulas invert (checked by simulation in the tests).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..common.arrays import as_real_array
from ..common.rng import make_rng
from ..errors import InfeasibleTwistError, InputError
from ..kinematics.robot import Robot
from ..kinematics.wheels import range_problem
from ..motion.limits import MotionLimits
from ..motion.plans import UMBMARK_SIDE, check_mode, umbmark_square
from ..simulation.error_models import NoiseModel
from ..simulation.kinematic import segment_rates, simulate_kinematic

UNITS = {
    "side": "m",
    "epsilon": "[m, m, rad]",
    "cg": "m",
    "r_cg": "m",
    "e_max_syst": "m",
    "e_max_syst_interval": "m",
    "alpha": "rad",
    "beta": "rad",
    "R": "m (null: straight legs, beta = 0)",
    "E_d": "1",
    "E_b": "1",
    "c_L": "1",
    "c_R": "1",
    "b_new": "m",
}
"""Unit of each key of :meth:`UMBmarkResult.as_dict` (``[m, m, rad]``: per component)."""

SIDE_RANGE = (0.05, 100.0)
"""Side of a UMBmark square [m], simulated or measured: from 5 cm (a robot of a few centimetres)
to 100 m (Borenstein and Feng used 4 m; beyond 100 m the floor, not the odometry, is measured)."""

LEVEL = 0.95
"""Default confidence level of the intervals."""

BOUNDARY_POINTS = 4096
"""Points on the boundary of a confidence ellipse when finding its nearest and farthest
point from the origin (relative accuracy of the distances about 1e-6)."""


@dataclass(frozen=True)
class Borenstein:
    """Borenstein's differential-drive correction (module docstring).

    ``R`` [m] is ``inf`` when the legs are straight (``beta = 0``: then ``E_d = 1`` exactly);
    :meth:`as_dict` gives it as None (JSON null) and :meth:`describe` as ``straight``.
    """

    alpha: float
    beta: float
    R: float
    E_d: float
    E_b: float
    c_L: float
    c_R: float
    b_new: float

    FIELDS = ("alpha", "beta", "R", "E_d", "E_b", "c_L", "c_R", "b_new")

    @property
    def straight(self) -> bool:
        """True when the legs do not curve (``beta = 0``, ``R`` infinite)."""
        return math.isinf(self.R)

    def as_dict(self) -> dict:
        """The figures by name; ``R`` None for straight legs (JSON has no infinity)."""
        return {k: None if k == "R" and self.straight else float(getattr(self, k)) for k in self.FIELDS}

    def describe(self) -> str:
        """One line of the figures, as the command line and report print them."""
        radius = "straight legs (beta = 0)" if self.straight else f"{self.R:.5g} m"
        return (
            f"alpha {self.alpha:.5g} rad, beta {self.beta:.5g} rad, R {radius}, E_d {self.E_d:.6f}, "
            f"E_b {self.E_b:.6f}, c_L {self.c_L:.6f}, c_R {self.c_R:.6f}, b_new {self.b_new:.6f} m"
        )


def borenstein(x_cw: float, x_ccw: float, side: float, track: float) -> Borenstein:
    """Borenstein's E_d, E_b and corrections from the x of the two centres of gravity [m].

    Computed through the curvature of the legs ``k = 1 / R = 2 sin(beta / 2) / L``, so that
    ``E_d = (1 + k b/2) / (1 - k b/2)`` is exactly 1 for straight legs (``beta = 0``, ``R``
    infinite) and never inf/inf. Signed zeros are returned as 0.
    """
    alpha = (x_cw + x_ccw) / (-4.0 * side) + 0.0  # + 0.0: -0.0 becomes 0.0
    beta = (x_cw - x_ccw) / (-4.0 * side) + 0.0
    if abs(alpha) >= math.pi / 2 or abs(beta) >= math.pi:
        raise InputError(
            f"Borenstein's correction is undefined here: alpha = {alpha:.6g} rad, beta = {beta:.6g} "
            f"rad from x_cw = {x_cw:.6g} m, x_ccw = {x_ccw:.6g} m and side {side:.6g} m (the "
            f"errors are not small against the square)"
        )
    curvature = 2.0 * math.sin(beta / 2.0) / side  # 1 / R [1/m]
    half = curvature * track / 2.0
    if abs(half) >= 1.0:
        raise InputError(
            f"Borenstein's correction is undefined here: the legs curve with radius {1.0 / curvature:.6g} m, "
            f"within half the track ({track / 2:.6g} m)"
        )
    radius = 1.0 / curvature if curvature != 0.0 else math.inf
    e_d = (1.0 + half) / (1.0 - half)
    e_b = (math.pi / 2) / (math.pi / 2 - alpha)
    return Borenstein(alpha, beta, radius, e_d, e_b, 2.0 / (e_d + 1.0), 2.0 / (1.0 / e_d + 1.0), e_b * track)


@dataclass(frozen=True)
class DirectionResult:
    """The runs of one direction: ``epsilon`` ``(n, 3)``, centre of gravity, ``r_cg``."""

    direction: str
    epsilon: np.ndarray

    @property
    def cg(self) -> np.ndarray:
        """Centre of gravity ``(x, y)`` [m] of the return errors (eq. 3-4)."""
        return self.epsilon[:, :2].mean(axis=0)

    @property
    def r_cg(self) -> float:
        """Distance of the centre of gravity from the origin [m] (eq. 5-6)."""
        return float(np.hypot(*self.cg))

    def distance_range(self, level: float) -> tuple[float, float] | None:
        """Nearest and farthest distance [m] from the origin of the Hotelling ``T^2``
        confidence region of level ``level`` for the expected return position (module
        docstring); None with fewer than 3 runs."""
        n = len(self.epsilon)
        if n < 3:
            return None
        from scipy.stats import f as f_dist

        c = 2.0 * (n - 1) / (n - 2) * float(f_dist.ppf(level, 2, n - 2))
        lam, vec = np.linalg.eigh(np.cov(self.epsilon[:, :2], rowvar=False))
        a = vec * np.sqrt(np.clip(lam, 0.0, None) * c / n)  # region: cg + a u, |u| <= 1
        phi = np.linspace(0.0, 2.0 * np.pi, BOUNDARY_POINTS, endpoint=False)
        edge = self.cg[:, None] + a @ np.vstack([np.cos(phi), np.sin(phi)])
        dist = np.hypot(edge[0], edge[1])
        near = float(dist.min())
        if np.linalg.matrix_rank(a) == 2 and np.linalg.norm(np.linalg.solve(a, -self.cg)) <= 1.0:
            near = 0.0  # the origin lies inside
        return near, float(dist.max())

    def as_dict(self) -> dict:
        return {
            "runs": [{"epsilon": [float(v) if np.isfinite(v) else None for v in e]} for e in self.epsilon],
            "cg": [float(v) for v in self.cg],
            "r_cg": self.r_cg,
        }


@dataclass(frozen=True)
class UMBmarkResult:
    """One UMBmark procedure: n runs clockwise and n counter-clockwise."""

    cw: DirectionResult
    ccw: DirectionResult
    side: float
    mode: str = "rotate"
    borenstein: Borenstein | None = None

    @property
    def e_max_syst(self) -> float:
        """``max(r_cg_cw, r_cg_ccw)`` [m]."""
        return max(self.cw.r_cg, self.ccw.r_cg)

    def e_max_interval(self, level: float = LEVEL) -> tuple[float, float] | None:
        """Confidence interval ``(low, high)`` [m] of ``E_max,syst`` at ``level`` (module
        docstring: Hotelling's ``T^2`` per direction, conservative); None with fewer than 3
        runs in a direction."""
        _check_level(level)
        cw, ccw = (d.distance_range(math.sqrt(level)) for d in (self.cw, self.ccw))
        if cw is None or ccw is None:
            return None
        return max(cw[0], ccw[0]), max(cw[1], ccw[1])

    def as_dict(self, level: float = LEVEL) -> dict:
        interval = self.e_max_interval(level)
        out = {
            "side": self.side,
            "mode": self.mode,
            "cw": self.cw.as_dict(),
            "ccw": self.ccw.as_dict(),
            "e_max_syst": self.e_max_syst,
            "e_max_syst_interval": list(interval) if interval else None,
        }
        if self.borenstein is not None:
            out["borenstein"] = self.borenstein.as_dict()
        return out


def _check_level(level: float) -> None:
    if not (isinstance(level, (int, float)) and 0.0 < level < 1.0):
        raise InputError(f"confidence level must lie between 0 and 1, got {level!r}")


def reduction_interval(before: UMBmarkResult, after: UMBmarkResult, level: float = LEVEL) -> tuple[float, float] | None:
    """Confidence interval of the reduction factor ``E_max,syst(before) / E_max,syst(after)``.

    With ``before`` and ``after`` independent procedures, each ``E_max,syst`` interval at
    level ``sqrt(level)`` (:meth:`UMBmarkResult.e_max_interval`) bounds the ratio between
    ``low_before / high_after`` and ``high_before / low_after`` with probability at least
    ``level``; the upper bound is ``inf`` when ``after`` is consistent with zero (the
    calibration left nothing UMBmark can see). None with fewer than 3 runs per direction.
    """
    _check_level(level)
    b, a = before.e_max_interval(math.sqrt(level)), after.e_max_interval(math.sqrt(level))
    if b is None or a is None:
        return None
    low = b[0] / a[1] if a[1] > 0 else (math.inf if b[0] > 0 else math.nan)
    high = b[1] / a[0] if a[0] > 0 else math.inf
    return low, high


@dataclass(frozen=True, kw_only=True)
class NoiseFloor:
    """What UMBmark shows of a perfectly calibrated robot: ``E_max,syst`` [m] of ``values``
    procedures in which the robot as built is commanded by its own exact model, under the
    same random errors, runs, square and rate. A measured ``E_max,syst`` at or below the
    floor's 95th percentile (:attr:`limit`) cannot be told from a perfect calibration."""

    values: np.ndarray

    @property
    def limit(self) -> float:
        """95th percentile of ``E_max,syst`` of the perfectly calibrated robot [m]."""
        return float(np.percentile(self.values, 95))

    @property
    def median(self) -> float:
        return float(np.median(self.values))

    def reaches(self, e_max_syst: float) -> bool:
        """Whether ``e_max_syst`` [m] is at the noise floor (at most :attr:`limit`)."""
        return e_max_syst <= self.limit

    def as_dict(self) -> dict:
        return {"procedures": int(len(self.values)), "e_max_syst_median": self.median, "e_max_syst_p95": self.limit}


@dataclass(frozen=True, kw_only=True)
class PhysicsFloor(NoiseFloor):
    """The floor of the physics study: ``values`` E_max,syst [m] of the nominal robot's
    procedures (the physics engine: UMBmark of the robot without systematic errors commanded by
    itself, :mod:`omnikin.evaluation.pipeline`) and ``interval`` the confidence interval [m] of the first
    one's E_max,syst from the spread of its runs over roller phases
    (:meth:`~omnikin.evaluation.umbmark.UMBmarkResult.e_max_interval`; None with fewer than 3
    runs per direction). :attr:`limit`, the largest E_max,syst that cannot be told from the
    nominal robot's, is the larger of the 95th percentile of ``values`` and the interval's upper
    end."""

    interval: tuple[float, float] | None = None

    @property
    def p95(self) -> float:
        """95th percentile of ``values`` [m]."""
        return float(np.percentile(self.values, 95))

    @property
    def limit(self) -> float:
        """The larger of :attr:`p95` and the interval's upper end [m]."""
        return max(self.p95, self.interval[1]) if self.interval is not None else self.p95

    def as_dict(self) -> dict:
        return {
            **NoiseFloor.as_dict(self),
            "e_max_syst_p95": self.p95,
            "e_max_syst_limit": self.limit,
            "e_max_syst_interval": list(self.interval) if self.interval is not None else None,
        }


def noise_floor(robot: Robot, *, procedures: int, rng=None, **options) -> NoiseFloor:
    """The :class:`NoiseFloor` of ``robot`` (the robot as built): ``procedures`` UMBmark
    procedures of ``robot`` commanded by itself; ``options`` as :func:`simulate_umbmark`."""
    results = simulate_umbmark(robot, robot, trials=procedures, rng=rng, **options)
    return NoiseFloor(values=np.array([r.e_max_syst for r in results]))


def differential_pair(robot: Robot):
    """``(left, right, track)`` of a differential drive, or None.

    A differential drive here: exactly two encoded rolling wheels, both fixed standard
    wheels on one axle (same x, drive directions along +-body x), one on each side.
    """
    enc = list(robot.encoded)
    if len(enc) != 2 or not all(w.is_fixed for w in enc):
        return None
    a, b = enc
    if abs(a.x - b.x) > 1e-9 or any(abs(math.sin(w.drive)) > 1e-9 for w in enc) or a.y * b.y >= 0:
        return None
    left, right = (a, b) if a.y > b.y else (b, a)
    return left, right, left.y - right.y


def analyze(
    eps_cw, eps_ccw, side: float = UMBMARK_SIDE, robot: Robot | None = None, mode: str = "rotate"
) -> UMBmarkResult:
    """UMBmark from return errors ``(n, 2)`` or ``(n, 3)`` per direction [m, m(, rad)].

    The heading column may be NaN where it was not measured.

    With a differential-drive ``robot`` Borenstein's correction is added.
    """
    check_mode(mode)
    side = check_side(side)
    dirs = []
    for name, eps in (("cw", eps_cw), ("ccw", eps_ccw)):
        e = as_real_array(eps, name)
        if e.ndim != 2 or e.shape[1] not in (2, 3):
            raise InputError(f"{name}: expected return errors of shape (n, 2) or (n, 3), got {e.shape}")
        if len(e) == 0:
            raise InputError(f"{name}: no runs; UMBmark needs at least one run in each direction")
        if not np.all(np.isfinite(e[:, :2])):
            raise InputError(
                f"{name}: non-finite return error in run {int(np.argwhere(~np.isfinite(e[:, :2]))[0, 0]) + 1}"
            )
        if e.shape[1] == 2:
            e = np.column_stack([e, np.zeros(len(e))])
        dirs.append(DirectionResult(name, e))
    cw, ccw = dirs
    bor = None
    if robot is not None and mode == "rotate":
        pair = differential_pair(robot)
        if pair is not None:
            bor = borenstein(float(cw.cg[0]), float(ccw.cg[0]), side, pair[2])
    return UMBmarkResult(cw, ccw, side, mode, bor)


def check_side(side, option: str = "side (--side)") -> float:
    """``side`` [m] as a float within :data:`SIDE_RANGE`, else an InputError naming ``option``."""
    problem = range_problem(side, *SIDE_RANGE, "m")
    if problem:
        raise InputError(f"{option}: the side of the UMBmark square {problem}")
    return float(side)


def procedure_generators(rng, count: int) -> list[np.random.Generator]:
    """One Generator for each of ``count`` procedures: the ``k``-th child of the seed sequence
    of ``rng`` (a SeedSequence, an integer seed, None for fresh entropy, or a Generator, which
    gives one seed for the children). Child ``k`` depends only on ``rng`` and ``k``, not on
    ``count``, and deriving them leaves a SeedSequence unchanged (unlike ``spawn``)."""
    if isinstance(rng, np.random.SeedSequence):
        seq = rng
    elif isinstance(rng, np.random.Generator):
        seq = np.random.SeedSequence(int(rng.integers(2**63)))
    elif rng is None:
        seq = np.random.SeedSequence()
    else:
        seq = np.random.SeedSequence(_seed(rng))
    return [
        make_rng(np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, k), pool_size=seq.pool_size))
        for k in range(count)
    ]


def _seed(rng) -> int:
    if isinstance(rng, bool) or not isinstance(rng, (int, np.integer)) or rng < 0:
        raise InputError(f"rng must be a numpy Generator, a SeedSequence, an integer seed >= 0 or None, got {rng!r}")
    return int(rng)


def square_refusal(robot: Robot, side: float, mode: str) -> str | None:
    """Why ``robot`` cannot drive the UMBmark squares of ``mode`` (the check ``simulate``
    makes: :func:`~omnikin.simulation.kinematic.segment_rates`), or None if it can."""
    for direction in ("cw", "ccw"):
        square = umbmark_square(direction, side, mode)
        try:
            segment_rates([seg.xi for seg in square.segments], robot, robot.encoded_names)
        except InfeasibleTwistError as exc:
            return str(exc).split(" (on_infeasible=")[0].removeprefix(f"robot {robot.name!r}: ")
    return None


def require_square(robot: Robot, side: float, mode: str) -> None:
    """Refuse (one line, :class:`~omnikin.errors.InputError`) a ``mode`` the robot cannot drive
    the UMBmark square of ``side`` [m] in (:func:`square_refusal`), saying whether the other
    mode would do."""
    check_mode(mode)
    refusal = square_refusal(robot, side, mode)
    if refusal is not None:
        other = {"rotate": "translate", "translate": "rotate"}[mode]
        hint = (
            f"the other mode is {other!r}"
            if square_refusal(robot, side, other) is None
            else "nor in the other mode: UMBmark does not apply to it"
        )
        raise InputError(f"robot {robot.name!r} cannot drive the UMBmark square in {mode!r} mode ({refusal}); {hint}")


def simulate_umbmark(
    true_robot: Robot,
    command_robot: Robot,
    *,
    side: float = UMBMARK_SIDE,
    mode: str = "rotate",
    runs: int = 5,
    noise: NoiseModel | None = None,
    rate: float = 100.0,
    limits: MotionLimits | None = None,
    trials: int = 1,
    rng=None,
    keep_runs: bool = False,
):
    """Simulate ``trials`` UMBmark procedures of ``runs`` runs per direction.

    ``command_robot`` is the model the robot executes the path by and computes its
    odometry with; ``true_robot`` the robot as built. Procedure ``k`` draws every random
    number from its own stream, the ``k``-th child of ``rng``
    (:func:`procedure_generators`): it is the same whatever ``trials``. Returns a list of
    :class:`UMBmarkResult` (one per trial) and, with ``keep_runs``, also the
    :class:`~omnikin.simulation.kinematic.SimulatedRun` of each direction (its ``truth``
    holds the first trial's runs).
    """
    if not isinstance(runs, (int, np.integer)) or runs < 1:
        raise InputError(f"runs must be a whole number >= 1, got {runs!r}")
    require_square(command_robot, side, mode)
    gens = procedure_generators(rng, trials)
    per_run = [g for g in gens for _ in range(runs)]  # procedure k's runs share its generator
    sims = {}
    for direction in ("cw", "ccw"):
        sims[direction] = simulate_kinematic(
            umbmark_square(direction, side, mode),
            true_robot,
            command_robot,
            rate=rate,
            limits=limits,
            noise=noise,
            trials=trials * runs,
            rng=per_run,
            keep_truth=keep_runs,
        )
    results = []
    for k in range(trials):
        eps = {d: sims[d].epsilon[k * runs : (k + 1) * runs] for d in sims}
        results.append(analyze(eps["cw"], eps["ccw"], side, command_robot, mode))
    return (results, sims) if keep_runs else results
