"""Paths as constant-twist segments, their speed profiles and their sampling.

A :class:`Segment` moves the body along the one-parameter subgroup ``exp(s * xi)`` of
SE(2): ``xi`` is the body twist per unit of progress ``s`` (for a straight leg a unit
direction, s in metres; for a spin ``(0, 0, +-1)``, s in radians; for an arc
``(1, 0, 1/R)``, s the arc length) and the segment ends at ``s = length``. Any speed
profile ``s(t)`` then traces exactly the same path, so speed and acceleration limits,
and wheel-speed saturation, change only the timing (:mod:`omnikin.simulation.limits`).

Each segment starts and ends at rest with a trapezoidal (or triangular) progress profile
under the limits, and is padded with a dwell to a whole number of samples, so that no
sample interval spans two segments: the twist is constant in direction within every
sample, and exact integration of each sample is exact for the plan.

UMBmark squares follow ``docs/conventions.md``: the first leg runs along +x, ``cw`` turns
right, ``ccw`` turns left; ``rotate`` mode drives every leg along body x and turns in place
by -+90 deg at each corner (the last turn restores the start heading), ``translate`` mode
(holonomic robots) translates along +-x and +-y with the heading held.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import InputError, OmnikinError
from .limits import MotionLimits, speed_scale


@dataclass(frozen=True)
class Segment:
    """Move by ``exp(length * xi)``: ``xi`` body twist per unit progress, ``length`` >= 0."""

    xi: tuple[float, float, float]
    length: float
    label: str = ""

    def __post_init__(self):
        xi = tuple(float(v) for v in self.xi)
        if len(xi) != 3 or not all(math.isfinite(v) for v in xi) or xi == (0.0, 0.0, 0.0):
            raise InputError(f"segment {self.label!r}: xi must be a finite non-zero twist, got {self.xi!r}")
        if not (math.isfinite(self.length) and self.length >= 0):
            raise InputError(f"segment {self.label!r}: length must be finite and >= 0, got {self.length!r}")
        object.__setattr__(self, "xi", xi)


@dataclass(frozen=True)
class Plan:
    """A path: segments driven one after the other, each from rest to rest."""

    segments: tuple[Segment, ...]
    name: str = "plan"

    def __post_init__(self):
        object.__setattr__(self, "segments", tuple(self.segments))
        if not self.segments:
            raise InputError(f"plan {self.name!r} has no segment")

    def __add__(self, other: "Plan") -> "Plan":
        return Plan(self.segments + other.segments, f"{self.name}+{other.name}")

    def end_pose(self) -> np.ndarray:
        """Pose reached when every segment is driven exactly (from the origin)."""
        from ..geometry import compose, exp

        pose = np.zeros(3)
        for seg in self.segments:
            pose = compose(pose, exp(np.array(seg.xi) * seg.length))
        return pose


# --- path builders -----------------------------------------------------------------------------
def line(distance: float, heading: float = 0.0) -> Plan:
    """Straight translation by ``distance`` [m] along body direction ``heading`` [rad]."""
    sign = 1.0 if distance >= 0 else -1.0
    return Plan((Segment((sign * math.cos(heading), sign * math.sin(heading), 0.0), abs(distance), "line"),), "line")


def spin(angle: float) -> Plan:
    """Turn in place by ``angle`` [rad] (positive: counter-clockwise)."""
    return Plan((Segment((0.0, 0.0, 1.0 if angle >= 0 else -1.0), abs(angle), "spin"),), "spin")


def arc(radius: float, angle: float) -> Plan:
    """Drive forward on a circle of ``radius`` [m] (centre on the left if ``angle`` > 0) by ``angle`` [rad]."""
    if not radius > 0:
        raise InputError(f"arc radius must be > 0, got {radius!r}")
    sign = 1.0 if angle >= 0 else -1.0
    return Plan((Segment((1.0, 0.0, sign / radius), abs(angle) * radius, "arc"),), "arc")


def polyline(waypoints: Sequence[Sequence[float]], mode: str = "rotate") -> Plan:
    """Visit ``waypoints`` ``[(x, y), ...]`` [m] (world = start frame) from the origin.

    ``rotate``: turn in place towards each waypoint, then drive along body x (the heading
    at the end is that of the last leg); ``translate``: translate with the heading held.
    """
    check_mode(mode)
    segs, pos, heading = [], np.zeros(2), 0.0
    for k, wp in enumerate(waypoints):
        d = np.asarray(wp, dtype=float) - pos
        if d.shape != (2,) or not np.all(np.isfinite(d)):
            raise InputError(f"waypoint #{k + 1}: expected two finite numbers, got {wp!r}")
        dist = float(np.hypot(*d))
        if dist == 0.0:
            continue
        bearing = math.atan2(d[1], d[0])
        if mode == "rotate":
            turn = (bearing - heading + math.pi) % (2 * math.pi) - math.pi
            if abs(turn) > 1e-12:
                segs.append(Segment((0.0, 0.0, math.copysign(1.0, turn)), abs(turn), f"turn {k + 1}"))
            heading = bearing
            segs.append(Segment((1.0, 0.0, 0.0), dist, f"leg {k + 1}"))
        else:
            segs.append(Segment((math.cos(bearing), math.sin(bearing), 0.0), dist, f"leg {k + 1}"))
        pos = pos + d
    if not segs:
        raise InputError("polyline: no waypoint away from the start")
    return Plan(tuple(segs), "polyline")


def check_mode(mode: str) -> str:
    if mode not in ("rotate", "translate"):
        raise InputError(f"unknown path mode {mode!r}; one of ['rotate', 'translate']")
    return mode


def check_direction(direction: str) -> str:
    if direction not in ("cw", "ccw"):
        raise InputError(f"unknown UMBmark direction {direction!r}; one of ['cw', 'ccw']")
    return direction


def umbmark_square(direction: str = "cw", side: float = 4.0, mode: str = "rotate") -> Plan:
    """The UMBmark square (``docs/conventions.md``): first leg along +x; ``cw`` turns right."""
    check_direction(direction)
    check_mode(mode)
    if not (math.isfinite(side) and side > 0):
        raise InputError(f"UMBmark side must be > 0, got {side!r}")
    turn = -1.0 if direction == "cw" else 1.0
    segs = []
    for k in range(4):
        if mode == "rotate":
            segs.append(Segment((1.0, 0.0, 0.0), side, f"leg {k + 1}"))
            segs.append(Segment((0.0, 0.0, turn), math.pi / 2, f"corner {k + 1}"))
        else:
            bearing = turn * k * math.pi / 2
            segs.append(Segment((math.cos(bearing), math.sin(bearing), 0.0), side, f"leg {k + 1}"))
    return Plan(tuple(segs), f"umbmark-{direction}-{mode}")


# --- timing ----------------------------------------------------------------------------------------
MAX_SAMPLES = 50_000_000
"""Largest number of samples one run may have (about 1.2 GB of increments)."""

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
    if amax * t_acc * t_acc >= length:           # triangular: never reaches vmax
        t_acc = math.sqrt(length / amax)
        vmax = amax * t_acc
        t_flat = 0.0
    else:
        t_flat = (length - amax * t_acc * t_acc) / vmax
    duration = 2 * t_acc + t_flat
    n = max(1, math.ceil(duration / dt - 1e-9))
    tk = np.minimum(np.arange(n + 1) * dt, duration)
    t1, t2 = t_acc, t_acc + t_flat
    s = np.where(tk <= t1, 0.5 * amax * tk ** 2,
                 np.where(tk <= t2, 0.5 * amax * t1 ** 2 + vmax * (tk - t1),
                          length - 0.5 * amax * (duration - tk) ** 2))
    s[-1] = length
    return s


def sample_plan(plan: Plan, robot, rate: float = 100.0, limits: MotionLimits | None = None) -> SampledPlan:
    """Time a plan for ``robot`` under ``limits`` and sample it at ``rate`` [Hz].

    Each segment's progress rate is the largest that keeps every speed limit (body and
    wheels of ``robot``, which is the model that commands the motion), and its progress
    acceleration the largest that keeps the acceleration limits.
    """
    limits = limits or MotionLimits()
    if not (math.isfinite(rate) and rate > 0):
        raise InputError(f"rate must be a positive number of samples per second, got {rate!r}")
    dt = 1.0 / rate
    xi = np.array([seg.xi for seg in plan.segments])
    vmax = speed_scale(robot, xi, limits)
    estimate = 0.0
    for k, seg in enumerate(plan.segments):
        if not np.isfinite(vmax[k]):
            raise InputError(f"plan {plan.name!r}, segment {seg.label!r}: no speed limit bounds its pace; "
                               f"set MotionLimits.linear/angular or wheel max_speed")
        amax = _accel_scale(seg.xi, limits)
        estimate += (seg.length / vmax[k] + (vmax[k] / amax if amax else 0.0)) * rate + 1
    if not estimate <= MAX_SAMPLES:
        raise InputError(f"plan {plan.name!r} would take about {estimate:.3g} samples at {rate:g} Hz; the most "
                           f"omnikin samples in one run is {MAX_SAMPLES:.0e} (shorten the path or lower the rate)")
    progress, segment = [], []
    for k, seg in enumerate(plan.segments):
        amax = _accel_scale(seg.xi, limits)
        s = _profile(seg.length, float(vmax[k]), amax, dt)
        ds = np.diff(s)
        progress.append(ds)
        segment.append(np.full(len(ds), k))
    progress = np.concatenate(progress)
    segment = np.concatenate(segment)
    t = np.arange(len(progress) + 1) * dt
    return SampledPlan(plan, rate, t, progress, segment, xi)


def _accel_scale(xi, limits: MotionLimits) -> float | None:
    bounds = []
    v = math.hypot(xi[0], xi[1])
    if limits.linear_accel is not None and v > 0:
        bounds.append(limits.linear_accel / v)
    if limits.angular_accel is not None and xi[2] != 0:
        bounds.append(limits.angular_accel / abs(xi[2]))
    return min(bounds) if bounds else None
