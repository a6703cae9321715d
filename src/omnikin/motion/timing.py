"""Timing and sampling of motion plans (:mod:`omnikin.motion.plans`) under motion limits.

Each segment starts and ends at rest with a trapezoidal (or triangular) progress profile
under the limits, and is padded with a dwell to a whole number of samples, so that no
sample interval spans two segments: the twist is constant in direction within every
sample, and exact integration of each sample is exact for the plan. Speed and
acceleration limits, and wheel-speed saturation, change only the timing
(:mod:`omnikin.motion.limits`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..common.messages import digits_apart, shorten
from ..errors import InputError
from ..kinematics.wheels import range_problem
from .limits import MotionLimits, speed_scale
from .plans import Plan

# --- timing ----------------------------------------------------------------------------------------
MAX_SAMPLES = 50_000_000
"""Largest number of samples one run may have (about 1.2 GB of increments)."""

RATE_RANGE = (5.0, 10_000.0)
"""Sample rate [Hz] of every simulated run: checked where a simulation starts
(:func:`omnikin.simulation.kinematic.simulate_kinematic`, so also ``omnikin simulate``, ``omnikin umbmark``,
:func:`omnikin.simulate`, :func:`omnikin.run_umbmark`; :func:`check_rate_range`): at least 5
samples per second (a UMBmark leg then still spans several samples; at 1e-9 Hz a run is one
sample and the result is noise of the sampling, not odometry), at most 10 kHz (beyond any
odometry loop; the cost grows with it). :func:`sample_plan` alone (timing, no simulation) takes
any positive rate."""


@dataclass(frozen=True)
class SampledPlan:
    """A plan sampled at ``rate`` [Hz] under limits.

    ``t`` ``(N + 1,)`` [s]; ``progress`` ``(N,)`` progress increments per sample;
    ``segment`` ``(N,)`` index of the segment each sample belongs to;
    ``xi`` ``(n_segments, 3)``. The body increment of sample k is ``xi[segment[k]] * progress[k]``.
    """

    plan: Plan
    rate: float
    t: np.ndarray
    progress: np.ndarray
    segment: np.ndarray
    xi: np.ndarray

    @property
    def increments(self) -> np.ndarray:
        """Body increments ``(N, 3)`` of the plan as driven exactly."""
        return self.xi[self.segment] * self.progress[:, None]


def _profile(length: float, vmax: float, amax: float | None, dt: float) -> np.ndarray:
    """Progress at the sample instants of a rest-to-rest trapezoid, padded to whole samples."""
    if length == 0.0:
        return np.zeros(1)
    if amax is None or not math.isfinite(amax):
        duration = length / vmax
        n = max(1, math.ceil(duration / dt - 1e-9))
        tk = np.arange(n + 1) * dt
        return np.minimum(tk * vmax, length)
    t_acc = vmax / amax
    if amax * t_acc * t_acc >= length:  # triangular: never reaches vmax
        t_acc = math.sqrt(length / amax)
        vmax = amax * t_acc
        t_flat = 0.0
    else:
        t_flat = (length - amax * t_acc * t_acc) / vmax
    duration = 2 * t_acc + t_flat
    n = max(1, math.ceil(duration / dt - 1e-9))
    tk = np.minimum(np.arange(n + 1) * dt, duration)
    t1, t2 = t_acc, t_acc + t_flat
    s = np.where(
        tk <= t1,
        0.5 * amax * tk**2,
        np.where(tk <= t2, 0.5 * amax * t1**2 + vmax * (tk - t1), length - 0.5 * amax * (duration - tk) ** 2),
    )
    s[-1] = length
    return s


def sample_plan(plan: Plan, robot, rate: float = 100.0, limits: MotionLimits | None = None) -> SampledPlan:
    """Time a plan for ``robot`` under ``limits`` and sample it at ``rate`` [Hz].

    Each segment's progress rate is the largest that keeps every speed limit (body and
    wheels of ``robot``, which is the model that commands the motion), and its progress
    acceleration the largest that keeps the acceleration limits.
    """
    limits = limits or MotionLimits()
    dt = 1.0 / _check_rate(rate)
    xi = np.array([seg.xi for seg in plan.segments])
    vmax = speed_scale(robot, xi, limits)
    estimate = _estimate(plan, vmax, limits, rate)
    if not estimate <= MAX_SAMPLES:
        raise InputError(
            f"plan {plan.name!r} would take about {estimate:.3g} samples at {rate:g} Hz; the most "
            f"omnikin samples in one run is {MAX_SAMPLES:.0e} (shorten the path or lower the rate)"
        )
    pieces, labels = [], []
    for k, seg in enumerate(plan.segments):
        amax = _accel_scale(seg.xi, limits)
        ds = np.diff(_profile(seg.length, float(vmax[k]), amax, dt))
        pieces.append(ds)
        labels.append(np.full(len(ds), k))
    progress = np.concatenate(pieces)
    segment = np.concatenate(labels)
    t = np.arange(len(progress) + 1) * dt
    return SampledPlan(plan, rate, t, progress, segment, xi)


def require_motion(sampled: SampledPlan) -> None:
    """Refuse (one line) a sampled plan that lasts 0 s (``line 0``, ``spin 0``, ``arc 0 0``):
    nothing to simulate, and odometry needs two samples."""
    if len(sampled.t) < 2:
        raise InputError(
            "the path does not move the robot (it lasts 0 s): nothing to simulate; give a length or angle other than 0"
        )


def estimated_samples(plan: Plan, robot, rate: float = 100.0, limits: MotionLimits | None = None) -> float:
    """Number of samples :func:`sample_plan` would make (an upper bound, within one sample per
    segment), computed without sampling: for sizing a job before starting it."""
    limits = limits or MotionLimits()
    _check_rate(rate)
    xi = np.array([seg.xi for seg in plan.segments])
    return _estimate(plan, speed_scale(robot, xi, limits), limits, rate)


def check_rate_range(rate, name: str) -> float:
    """``rate`` [Hz] if it lies in :data:`RATE_RANGE`, else an :class:`~omnikin.errors.InputError`
    in one line naming ``name`` (the option or argument: ``--rate``) and the range."""
    problem = range_problem(rate, *RATE_RANGE, "Hz")
    if problem:
        span = f"[{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}] Hz"
        raise InputError(f"{name}: the sample rate {problem}" + ("" if span in problem else f"; it must lie in {span}"))
    return float(rate)


# --- stamps ------------------------------------------------------------------------------------------
STAMP_RESOLUTION = 1e-3
"""Coarsest rounding of a sample's time [share of the sample interval] an output may make. A time
kept as a float (a tick log read back) is rounded to the float spacing at its size, 2.2e-16 of
it: at ``--start 1e16`` every stamp of a 100 Hz run was 1e16 or 1e16 + 2 (64 samples on one
time), which the odometry refuses; a thousandth of the interval leaves the stamps distinct and
the speeds computed from them true to 0.1 %."""


def check_start_time(
    start,
    duration: float,
    rate: float,
    name: str = "start",
    *,
    output: str = "the output",
    span: tuple[float, float] = (-math.inf, math.inf),
    step: float | None = None,
) -> float:
    """``start`` [s] as a float if the stamps ``start + k / rate`` of a run of ``duration`` [s]
    fit ``output``, else an :class:`~omnikin.errors.InputError` naming ``name`` (``--start``)
    and ``output``: the one check of a run's start time, for every output that stamps its samples.

    The stamps must lie in ``span`` [s] (what the output holds: a ROS 2 time runs from 0 to
    2**31 - 1 s) and the output's rounding of a stamp, ``step`` [s] (1e-9 for integer
    nanoseconds; None: a float, rounded to its spacing at the largest stamp), must be at most
    :data:`STAMP_RESOLUTION` of the sample interval ``1 / rate``, so the stamps stay distinct.
    """
    problem = range_problem(start, -math.inf, math.inf, "s")
    if problem:
        raise InputError(f"{name}: the start time {problem}")
    first, last = float(start), float(start) + float(duration)
    low, high = span
    if not (low <= first and last <= high):
        p = max(digits_apart(first, low), digits_apart(last, high))  # printed apart from the bounds they break
        raise InputError(
            f"{name}: stamps from {first:.{p}g} s to {last:.{p}g} s do not fit {output}, whose times run "
            f"from {low:.10g} to {high:.10g} s"
        )
    rounding = float(np.spacing(max(abs(first), abs(last)))) if step is None else step
    interval = 1.0 / rate
    if rounding > STAMP_RESOLUTION * interval:
        reach = 2.0 ** (math.floor(math.log2(STAMP_RESOLUTION * interval)) + 53)  # doubles below: fine enough
        raise InputError(
            f"{name}: {output} holds a time near {max(abs(first), abs(last)):.6g} s only to {rounding:.3g} s, "
            f"more than {STAMP_RESOLUTION:g} of the sample interval {interval:.3g} s at {rate:g} Hz: the "
            f"stamps would collapse; keep them within +-{reach:.3g} s of 0 (or lower the rate)"
        )
    return first


def _check_rate(rate) -> float:
    """``rate`` [Hz] as a float if it is a real positive finite number (not a bool: ``True`` is
    no rate), else an InputError."""
    problem = range_problem(rate, 0.0, math.inf, "Hz")
    if problem or not rate > 0:
        raise InputError(f"rate must be a positive number of samples per second, got {shorten(rate)}")
    return float(rate)


def _estimate(plan: Plan, vmax, limits: MotionLimits, rate: float) -> float:
    """Samples of the timed plan: per segment its duration (cruise plus the time lost to the
    acceleration ramps) times ``rate``, plus one."""
    estimate = 0.0
    for k, seg in enumerate(plan.segments):
        if not np.isfinite(vmax[k]):
            raise InputError(
                f"plan {plan.name!r}, segment {seg.label!r}: no speed limit bounds its pace; "
                f"set MotionLimits.linear/angular or wheel max_speed"
            )
        amax = _accel_scale(seg.xi, limits)
        estimate += (seg.length / vmax[k] + (vmax[k] / amax if amax else 0.0)) * rate + 1
    return estimate


def _accel_scale(xi, limits: MotionLimits) -> float | None:
    bounds = []
    v = math.hypot(xi[0], xi[1])
    if limits.linear_accel is not None and v > 0:
        bounds.append(limits.linear_accel / v)
    if limits.angular_accel is not None and xi[2] != 0:
        bounds.append(limits.angular_accel / abs(xi[2]))
    return min(bounds) if bounds else None
