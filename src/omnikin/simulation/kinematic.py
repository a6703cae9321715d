"""Simulated runs: the robot as built drives a plan commanded by its (nominal) model.

One run, for every trial at once (leading trial axis):

1. the plan is timed and sampled for the *command* robot (:func:`~omnikin.motion.timing.sample_plan`);
   its inverse kinematics gives every encoded wheel's commanded angle at each sample;
2. each wheel turns by its motor (:func:`wheel_motion`): a stepper turns the commanded angle
   and its encoder counts that angle over the *true* angle per tick; a dc motor's controller
   holds its encoder at the commanded count, the commanded angle over the command model's angle
   per tick; rounded when quantised.
   Its counter outputs the counts as such a counter does: a wheel whose ``encoder.counter_bits``
   (of the command robot) is ``b`` reads ``ticks mod 2**b``, unsigned in ``[0, 2**b)`` like the
   count register of a quadrature decoder or the AS5600's 12-bit angle (:func:`counter_output`;
   unquantised counts, an idealisation, wrap to the signed range instead, exactly).
   They are the same in every trial, and so is the odometry computed from those readings;
3. the true wheel angle is the commanded angle (stepper) or the ticks times the *true* angle
   per tick (dc; encoder errors); in
   each sample each wheel's rolling distance gets its slip error and the true robot's
   forward kinematics (:meth:`omnikin.kinematics.robot.Robot.fk_matrix`) turns the wheel increments
   into a body increment; the floor adds its heading error; exact SE(2) integration gives
   the ground truth;
4. the end pose is "measured" with the measurement noise.

The encoded wheels are taken as the driven ones: passive wheels (castors, unencoded
steered wheels) follow the motion and do not drive it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..common.rng import make_rng
from ..errors import InputError
from ..kinematics.robot import Robot, require_same_wheels
from ..kinematics.se2 import TAYLOR_LIMIT, between, wrap_angle
from ..kinematics.sensors import Imu, Lidar
from ..motion.limits import MotionLimits
from ..motion.plans import Plan
from ..motion.timing import SampledPlan, check_rate_range, estimated_samples, require_motion, sample_plan
from ..odometry.batch import batch_odometry, encoded_wheels
from ..odometry.integration import integrate_components, integrate_end
from ..sensors.readings import Readings, kinematic_readings, require_scan_room
from ..world.collision import Collider, Contact
from .error_models import NoiseModel

# Measured cost of one simulated run (one trial, ground truth kept): tracemalloc peaks of
# omnikin.simulate over 3e5-7e5 samples (CPython 3.11, NumPy 1.26) were 472, 504, 536, 792 and 1696
# bytes per sample for 2, 3, 4, 12 and 40 wheels (about 424 + 32 per wheel), with bag or tick log
# written after it 511 to 537 for 3 and 4 wheels; 1 to 2 us per sample on a loaded 2-core machine.
SAMPLE_BYTES = 480
"""Memory of a simulated run per sample, beside :data:`WHEEL_SAMPLE_BYTES` per wheel (rounded up)."""
WHEEL_SAMPLE_BYTES = 40
"""Memory of a simulated run per sample and wheel of the robot."""
SAMPLE_SECONDS = 0.5e-6
"""Time of a simulated run per sample (on the fast side: a run is refused for time only when
clearly too long)."""


@dataclass(frozen=True)
class SimulatedRun:
    """Result of :func:`simulate_kinematic`.

    ``t`` ``(N + 1,)`` [s]; ``ticks`` ``(N + 1, n_enc)`` encoder counts (the wheel turned
    ``ticks`` times the angle per tick since the start: they never wrap); ``readings`` the same
    counts as the counters output them (wrapped to each encoder's ``counter_bits``:
    :func:`counter_output`; what a tick log holds); ``steer`` ``(N + 1, n_steer)`` [rad] or None (the same in every
    trial); ``odometry`` ``(N + 1, 3)`` the odometry of ``odometry_robot`` from the readings; ``truth``
    ``(trials, N + 1, 3)`` ground truth (or only its end, ``(trials, 1, 3)``, when not
    kept); ``measured`` ``(trials, 3)`` the end pose as measured. In a world: ``contacts`` of each
    trial (:class:`~omnikin.world.collision.Contact`, world frame) and the world's ``start``
    pose (x, y, theta) [m, m, rad]: ``truth`` stays in the frame where the robot starts (that
    of the odometry), the world frame's pose is ``start (+) truth``.
    """

    sampled: SampledPlan
    t: np.ndarray
    ticks: np.ndarray
    steer: np.ndarray | None
    odometry: np.ndarray
    truth: np.ndarray
    measured: np.ndarray
    readings: np.ndarray
    contacts: tuple[tuple[Contact, ...], ...] = ()
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sensing: Readings | None = None

    @property
    def epsilon(self) -> np.ndarray:
        """Return errors ``(trials, 3)``: measured true end pose minus odometry end pose."""
        eps = self.measured - self.odometry[-1]
        eps[:, 2] = wrap_angle(eps[:, 2])
        return eps


def segment_rates(xi, robot: Robot, names) -> tuple[np.ndarray, np.ndarray]:
    """Per segment of a plan, what ``robot`` commands to drive it.

    ``xi`` ``(n_seg, 3)``: each segment's body twist per unit progress. Returns the wheel
    angle per unit progress ``(n_seg, n)`` [rad] of the wheels ``names`` (``J(steer) xi``)
    and the steering ``(n_seg, n_steer)`` [rad] of ``robot.steerable`` (each segment's
    alignment nearest the previous one). This is the one check of whether a robot can
    drive a plan: a twist its fixed wheels cannot roll along, or its steerable wheels
    cannot follow within their limits, raises :class:`~omnikin.errors.InfeasibleTwistError`
    naming the wheel (:meth:`omnikin.kinematics.robot.Robot.ik`).
    """
    xi = np.asarray(xi, dtype=float).reshape(-1, 3)
    per_segment = np.zeros((len(xi), len(names)))
    steer_seg = np.zeros((len(xi), len(robot.steerable)))
    hint = np.zeros(len(robot.steerable))
    for k, twist in enumerate(xi):
        if robot.steerable:
            res = robot.ik(twist, steer_hint=hint)
            hint = steer_seg[k] = res.steer_angles
        else:
            robot.ik(twist)  # refuses a plan the command model cannot drive, naming the wheel
        per_segment[k] = robot.jacobian(steer_seg[k], names) @ twist
    return per_segment, steer_seg


def commanded_angles(sampled: SampledPlan, robot: Robot, wheels) -> tuple[np.ndarray, np.ndarray | None]:
    """Commanded wheel angles ``(N + 1, n)`` [rad] of ``wheels`` and steering ``(N + 1, n_steer)``."""
    per_segment, steer_seg = segment_rates(sampled.xi, robot, [w.name for w in wheels])
    angles = np.zeros((len(sampled.progress) + 1, len(wheels)))
    np.cumsum(per_segment[sampled.segment] * sampled.progress[:, None], axis=0, out=angles[1:])
    steer = None
    if robot.steerable:
        idx = np.concatenate([sampled.segment, sampled.segment[-1:]])
        steer = steer_seg[idx]
    return angles, steer


@dataclass(frozen=True)
class RunCost:
    """What one simulated run (:func:`simulate_kinematic`, one trial) will take: ``samples``, ``bytes`` of
    memory at its peak, ``seconds`` of computing (:func:`run_cost`); ``simulated`` [s] the
    simulated time (the physics engine: its upper bound, :meth:`omnikin.physics.engines.PhysicsEngine.cost`)."""

    samples: float
    bytes: float
    seconds: float
    simulated: float = math.nan


def run_cost(plan: Plan, robot: Robot, rate: float = 100.0, limits: MotionLimits | None = None) -> RunCost:
    """The cost of simulating ``plan`` commanded by ``robot`` at ``rate`` [Hz], from the number
    of samples (:func:`~omnikin.motion.timing.estimated_samples`, computed without sampling)
    and the measured costs per sample (:data:`SAMPLE_BYTES`, :data:`WHEEL_SAMPLE_BYTES`,
    :data:`SAMPLE_SECONDS`): for sizing a job before starting it
    (:func:`omnikin.common.resource_limits.require_within`)."""
    samples = estimated_samples(plan, robot, rate, limits)
    per_sample = SAMPLE_BYTES + WHEEL_SAMPLE_BYTES * len(robot.wheels)
    return RunCost(samples, samples * per_sample, samples * SAMPLE_SECONDS, samples / rate)


def simulate_kinematic(
    plan: Plan | SampledPlan,
    true_robot: Robot,
    command_robot: Robot,
    *,
    rate: float = 100.0,
    limits: MotionLimits | None = None,
    noise: NoiseModel | None = None,
    trials: int = 1,
    rng=None,
    odometry_robot: Robot | None = None,
    keep_truth: bool = True,
    collider: Collider | None = None,
    sensor_rng=None,
) -> SimulatedRun:
    """Simulate ``trials`` runs of ``plan`` by ``true_robot`` commanded by ``command_robot``.

    ``rng``: a numpy Generator or a seed (None: fresh entropy), or a sequence of ``trials``
    of them, one per trial. Each trial draws its random numbers (slip and floor, then the
    measurement of its end pose) from its own entry, in trial order, so that trial ``k``
    does not depend on how many trials follow it; trials that share a generator draw from
    it one after the other. ``true_robot`` must have the wheels of ``command_robot``
    (:func:`~omnikin.kinematics.robot.require_same_wheels`). ``odometry_robot`` defaults to
    ``command_robot`` (the robot executes the path by its own model); it reads the counts as
    its own encoders' counters output them (their ``counter_bits``). ``rate`` [Hz] (or the
    rate ``plan`` was sampled at) must lie in :data:`~omnikin.motion.timing.RATE_RANGE`.
    ``collider``: the world the robot drives in (None: an empty floor): each trial's truth starts
    at the world's start pose and stops at first contact (:meth:`Collider.follow`).
    ``sensor_rng``: the stream of the sensors' errors (None: exact readings); a single run
    (``trials`` 1) of a robot as built with IMUs or lidars keeps their readings
    (:func:`omnikin.sensors.readings.kinematic_readings`).
    """
    check_rate_range(plan.rate if isinstance(plan, SampledPlan) else rate, "rate")
    noise = noise or NoiseModel()
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
        raise InputError(f"trials must be a whole number >= 1, got {trials!r}")
    gens = trial_generators(rng, int(trials))
    require_same_wheels(command_robot, true_robot)
    odometry_robot = odometry_robot or command_robot
    sampled = plan if isinstance(plan, SampledPlan) else sample_plan(plan, command_robot, rate, limits)
    require_motion(sampled)
    cmd_wheels = encoded_wheels(command_robot)
    names = [w.name for w in cmd_wheels]
    true_wheels = [true_robot.wheel(n) for n in names]
    missing = [w.name for w in true_wheels if w.encoder is None]
    if missing:
        raise InputError(f"true robot {true_robot.name!r}: wheels {missing} have no encoder")
    angles, steer = commanded_angles(sampled, command_robot, cmd_wheels)
    ticks, true_angles = wheel_motion(angles, true_robot, command_robot, names, noise.quantise)
    widths = [w.encoder.counter_bits for w in cmd_wheels]
    readings = counter_output(ticks, widths)
    dtrue = np.diff(true_angles, axis=0).T  # (n, N) true wheel increments [rad]
    # the plan's own speed steps are not checked: a plan timed without acceleration limits
    # changes speed at once (the readings still pass every counter and speed rule)
    odo_widths = [w.encoder.counter_bits for w in encoded_wheels(odometry_robot)]
    seen = readings if odo_widths == widths else counter_output(ticks, odo_widths)  # as its own counters read
    odometry = batch_odometry(odometry_robot, sampled.t, seen, steer=steer, max_wheel_accel=math.inf).poses
    sensed = trials == 1 and any(isinstance(s, (Imu, Lidar)) for s in true_robot.sensors)
    if sensed:
        require_scan_room(true_robot, float(sampled.t[-1] - sampled.t[0]))
    truth, z = _truth(true_robot, names, dtrue, steer, noise, gens, keep_truth or collider is not None or sensed)
    contacts: tuple[tuple[Contact, ...], ...] = ()
    start = (0.0, 0.0, 0.0)
    in_world = truth[0]
    if collider is not None:
        start = collider.world.start
        touched = []
        for k in range(len(truth)):
            seen_in_world, found = collider.follow(sampled.t, truth[k])
            if k == 0:
                in_world = seen_in_world
            truth[k] = between(np.asarray(start), seen_in_world)
            touched.append(tuple(found))
        contacts = tuple(touched)
    sensing = None
    if sensed:
        shapes = collider.shapes if collider is not None else None
        sensing = kinematic_readings(true_robot, sampled.t, in_world, shapes, sensor_rng)
    if not keep_truth and truth.shape[1] > 1:
        truth = truth[:, -1:, :].copy()
    measured = truth[:, -1, :].copy()
    if z is not None:
        measured += z * np.array([noise.measurement, noise.measurement, noise.measurement_theta])
    return SimulatedRun(sampled, sampled.t, ticks, steer, odometry, truth, measured, readings, contacts, start, sensing)


def wheel_motion(angles: np.ndarray, true_robot: Robot, command_robot: Robot, names, quantise: bool):
    """What the encoded wheels ``names`` of ``true_robot`` do when commanded the angles
    ``angles`` ``(N + 1, n)`` [rad] by ``command_robot``: their encoder counts ``(N + 1, n)``
    (whole, int64, when ``quantise``) and true angles ``(N + 1, n)`` [rad], by each wheel's
    motor (:attr:`omnikin.kinematics.wheels.Wheel.motor`, docs/conventions.md, "Motors"):

    * ``stepper`` (open loop): the wheel turns the commanded angle ``a``; its encoder, of scale
      ``rpt_true`` [rad/tick], counts ``a / rpt_true``;
    * ``dc`` (speed loop closed on the encoder): the controller holds the counts at the
      commanded angle over the command model's scale, ``a / rpt_cmd``; the wheel turns
      ``counts * rpt_true``.

    An encoder scale error (``rpt_true != rpt_cmd``) thus moves the odometry of a stepper's wheel
    and the truth of a dc motor's; the physics engine does the same
    (:class:`omnikin.physics.simulator.PhysicsSim`).

    Parameters
    ----------
    angles : numpy.ndarray
        The commanded wheel angles ``(N + 1, n)`` [rad], one column per wheel of ``names``.
    true_robot, command_robot : Robot
        The robot as built and the model that commands it.
    names : sequence of str
        The ``n`` encoded wheels, in the order of the columns.
    quantise : bool
        Round the counts to whole ticks (int64), as an encoder counts them.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ticks, true_angles)``: the encoder counts ``(N + 1, n)`` [ticks] and the angles the
        wheels truly turn ``(N + 1, n)`` [rad].
    """
    cmd_rpt = command_robot.rad_per_tick(names)
    true_rpt = true_robot.rad_per_tick(names)
    closed = np.array([true_robot.wheel(n).counts_close_loop for n in names], dtype=bool)
    ticks = np.where(closed, angles / cmd_rpt, angles / true_rpt)
    if quantise:
        ticks = np.round(ticks).astype(np.int64)
    return ticks, np.where(closed, ticks * true_rpt, angles)


def counter_output(ticks: np.ndarray, bits) -> np.ndarray:
    """What the counters output for the counts ``ticks`` ``(..., n)``: wheel ``j`` with a
    width ``bits[j]`` reads ``ticks mod 2**bits[j]``, the others ``ticks`` itself.

    Whole counts (int64) come out unsigned in ``[0, 2**bits)``, as a hardware count register
    holds them (uint64 when a 64-bit counter is among them). Unquantised counts (float), which
    no real counter outputs, come out as the nearest representative in
    ``[-2**(bits-1), 2**(bits-1)]``: ``x - 2**bits rint(x / 2**bits)`` is exact (the result is a
    multiple of the spacing of ``x`` and not larger), where ``x mod 2**bits`` would round a
    small negative count up. Returns ``ticks`` itself when no wheel has a width."""
    if all(b is None for b in bits):
        return ticks
    if ticks.dtype.kind == "f":
        out = ticks.copy()
        for j, b in enumerate(bits):
            if b is not None:
                full = 2.0**b
                out[..., j] = ticks[..., j] - full * np.rint(ticks[..., j] / full)
        return out
    wrapped = ticks.astype(np.int64).view(np.uint64)  # a fresh copy; two's complement: ticks mod 2**64
    for j, b in enumerate(bits):
        if b is not None and b < 64:
            wrapped[..., j] &= np.uint64((1 << b) - 1)
    cols = [j for j, b in enumerate(bits) if b is not None]
    if 64 not in bits:  # every reading fits int64
        out = ticks.astype(np.int64)
        out[..., cols] = wrapped[..., cols].astype(np.int64)
        return out
    if len(cols) == len(bits):
        return wrapped
    mixed = ticks.astype(object)  # uint64 readings beside negative counts: Python ints
    mixed[..., cols] = wrapped[..., cols].astype(object)
    return mixed


def trial_generators(rng, trials: int) -> list[np.random.Generator]:
    """One Generator per trial (:func:`simulate_kinematic`'s ``rng``): a sequence of ``trials`` entries,
    each made a Generator (:func:`omnikin.common.rng.make_rng`; a Generator given twice stays one
    generator), or one generator shared by every trial."""
    if isinstance(rng, (list, tuple)):
        if len(rng) != trials:
            raise InputError(f"rng: one generator per trial, {trials} expected, got {len(rng)}")
        return [make_rng(g) for g in rng]
    return [make_rng(rng)] * trials


TRIAL_BLOCK_SAMPLES = 1 << 15
"""Trials are simulated in blocks of about this many robot-samples, to stay in cache."""

_NEAR = 0.1
"""Largest heading deviation [rad] from the noise-free run for which :func:`_ends_near`
uses its series (truncation error below 3e-17); beyond it the exact trigonometry is used."""


def _truth(
    robot: Robot, names, dtrue, steer, noise: NoiseModel, gens: list, keep: bool
) -> tuple[np.ndarray, np.ndarray | None]:
    """Ground-truth poses ``(trials, N + 1, 3)`` (or ``(trials, 1, 3)``, the ends, if not ``keep``)
    and the standard normal variates ``(trials, 3)`` of the end-pose measurement (None without
    measurement noise). Trial ``k`` draws from ``gens[k]``: first its slip and floor variates,
    then its measurement's (:func:`simulate_kinematic`).

    The noise-free body increments ``base`` are computed once. Each trial's body
    increments are ``base + S_k z_k`` with ``z_k`` three standard normal variates per
    sample and ``S_k`` a square root of the per-sample covariance of the body increment,
    ``C_k = F_k diag(sigma_slip,k^2) F_k^T + diag(0, 0, sigma_floor,k^2)``: exactly the
    distribution of the wheel slip mapped through the true forward kinematics ``F_k`` plus
    the floor's heading error, drawn with one variate per body component instead of one
    per wheel and one for the floor. The floor's standard deviation per sample uses the
    noise-free path length of the sample. Trials go in blocks through preallocated buffers
    (:class:`_Work`): fresh arrays of this size cost more in page faults than the arithmetic.
    """
    trials = len(gens)
    n, m = dtrue.shape
    radius = np.array([robot.wheel(nm).radius for nm in names])
    mid = steer[:-1] + 0.5 * np.diff(steer, axis=0) if robot.steerable else None
    f = robot.fk_matrix(mid, names)[..., : len(names)]  # (N, 3, n), or (3, n) when no
    if f.ndim == 3:  # driven wheel steers
        base = np.einsum("kij,jk->ik", f, dtrue)
    else:
        base = f @ dtrue  # (3, N) noise-free increments
    reps = trials if not noise.is_zero else 1
    out = np.empty((trials, m + 1 if keep else 1, 3))
    measure = np.empty((trials, 3)) if noise.measurement or noise.measurement_theta else None
    root = _noise_root(f, dtrue, radius, base, noise) if reps > 1 or not noise.is_zero else None
    base_mid = np.cumsum(base[2]) - 0.5 * base[2]  # noise-free heading mid-sample
    cb, sb = np.cos(base_mid), np.sin(base_mid)
    block = max(1, TRIAL_BLOCK_SAMPLES // max(m, 1))
    work = _Work(min(block, reps), m)
    for r0 in range(0, reps, block):
        r1 = min(reps, r0 + block)
        w = work.view(r1 - r0)
        comps = w["comps"]
        if root is None:
            comps[...] = base
        else:
            z = w["z"]
            for r in range(r0, r1):  # trial by trial, each from its own generator
                gens[r].standard_normal(out=z[r - r0])
                if measure is not None:
                    measure[r] = gens[r].standard_normal(3)
            tmp = w["tmp"]
            for i in range(3):
                np.multiply(root[i, 0], z[:, 0], out=comps[:, i])
                comps[:, i] += base[i]
                for j in (1, 2):
                    np.multiply(root[i, j], z[:, j], out=tmp)
                    comps[:, i] += tmp
        if keep:
            integrate_components(comps[:, 0], comps[:, 1], comps[:, 2], out=out[r0:r1])
        else:
            out[r0:r1, 0] = _ends_near(comps, base_mid, cb, sb, w)
    if reps != trials:
        out[1:] = out[0]
    if measure is not None and root is None:  # no slip or floor noise: the measurement only
        for r in range(trials):
            measure[r] = gens[r].standard_normal(3)
    return out, measure


def _noise_root(f, dtrue, radius, base, noise: NoiseModel) -> np.ndarray:
    """``S`` ``(3, 3, N)`` with ``S_k S_k^T = C_k`` (see :func:`_truth`), by eigendecomposition
    (``C_k`` may be singular: a differential drive cannot slip sideways)."""
    m = dtrue.shape[1]
    var = (noise.slip**2) * np.abs(dtrue) * radius[:, None] / radius[:, None] ** 2  # (n, N) [rad^2]
    fk = f if f.ndim == 3 else np.broadcast_to(f, (m,) + f.shape)  # (N, 3, n)
    cov = np.einsum("kin,nk,kjn->kij", fk, var, fk)
    cov[:, 2, 2] += (noise.floor**2) * np.hypot(base[0], base[1])
    lam, vec = np.linalg.eigh(cov)
    root = vec * np.sqrt(np.clip(lam, 0.0, None))[:, None, :]
    return np.ascontiguousarray(np.moveaxis(root, 0, -1))  # (3, 3, N)


class _Work:
    """Buffers reused from block to block (trials x 3 x samples and trials x samples)."""

    ROWS = ("tmp", "mid", "half", "d", "d2", "cos_d", "sin_d", "c", "s", "k", "ka", "kb")

    def __init__(self, reps: int, m: int):
        self.buf = {"comps": np.empty((reps, 3, m)), "z": np.empty((reps, 3, m))}
        self.buf.update({k: np.empty((reps, m)) for k in self.ROWS})

    def view(self, r: int) -> dict:
        return {k: v[:r] for k, v in self.buf.items()}


def _ends_near(comps: np.ndarray, base_mid, cb, sb, w: dict) -> np.ndarray:
    """End poses ``(r, 3)`` of exact integration of ``comps`` ``(r, 3, N)`` from the origin.

    Same result as :func:`omnikin.odometry.integration.integrate_end` (to about 1e-14); faster for
    runs close to the noise-free one (heading ``base_mid``, with ``cb, sb`` its cosine and
    sine): the mid-sample heading is ``base_mid + d`` with a small ``d``, and
    ``cos(base + d) = cb cos d - sb sin d`` with the Taylor series of ``cos d`` and
    ``sin d`` replaces two trigonometric evaluations by a few multiplications; likewise the
    chord factor ``sinc(phi/2)`` by its series. ``w``: buffers of :class:`_Work`.
    """
    a, b, phi = comps[:, 0], comps[:, 1], comps[:, 2]
    half = np.multiply(phi, 0.5, out=w["half"])
    mid = np.cumsum(phi, axis=-1, out=w["mid"])
    mid -= half
    d = np.subtract(mid, base_mid, out=w["d"])
    if np.max(np.abs(d), initial=0.0) > _NEAR or np.max(np.abs(half), initial=0.0) >= TAYLOR_LIMIT:
        return integrate_end(a, b, phi)
    d2 = np.multiply(d, d, out=w["d2"])
    cos_d = _series(d2, _COS, w["cos_d"])
    sin_d = _series(d2, _SIN, w["sin_d"])
    sin_d *= d
    c = np.multiply(cb, cos_d, out=w["c"])
    s = np.multiply(sb, cos_d, out=w["s"])
    np.multiply(sb, sin_d, out=cos_d)
    c -= cos_d
    np.multiply(cb, sin_d, out=cos_d)
    s += cos_d
    np.multiply(half, half, out=d2)
    k = _series(d2, _SINC, w["k"])  # sinc(phi/2), |phi/2| < 0.1
    ka = np.multiply(k, a, out=w["ka"])
    kb = np.multiply(k, b, out=w["kb"])
    out = np.empty((len(comps), 3))
    out[:, 0] = np.einsum("ij,ij->i", c, ka) - np.einsum("ij,ij->i", s, kb)
    out[:, 1] = np.einsum("ij,ij->i", s, ka) + np.einsum("ij,ij->i", c, kb)
    out[:, 2] = wrap_angle(mid[:, -1] + half[:, -1])
    return out


_COS = [(-1) ** k / math.factorial(2 * k) for k in range(5)]  # cos d = sum c_k d^2k, to d^8
_SIN = [(-1) ** k / math.factorial(2 * k + 1) for k in range(5)]  # sin d / d = sum s_k d^2k
_SINC = _SIN[:5]  # sinc x to x^8 (geometry.sinc)


def _series(x2: np.ndarray, coef, out: np.ndarray) -> np.ndarray:
    """Horner evaluation of ``sum coef[k] x2**k`` into ``out``."""
    out.fill(coef[-1])
    for c in coef[-2::-1]:
        out *= x2
        out += c
    return out
