"""Geometric paths in the plane with a heading: :class:`Path`, sampled densely by a path length.

A path is a curve ``q(s) = (x(s), y(s), theta(s))`` in the world frame (``odom``; metres and
radians, docs/conventions.md) with no time in it: :func:`omnikin.control.time_optimal.time_optimal`
gives it its timing. The parameter ``s`` [m] is the length of the curve in the metric

    ds^2 = dx^2 + dy^2 + (rho dtheta)^2,

``rho`` [m] (:data:`HEADING_RADIUS`) turning a heading change into a length, so that a turn in
place (no travel) has a length too and every path is parametrised the same way.

A :class:`Path` holds its samples ``(n, 3)`` and the first and second derivatives ``dq/ds``,
``d^2q/ds^2`` at them, by second-order finite differences on the samples (``numpy.gradient``);
the builders sample their curves finely enough (:data:`SPACING`) that the differences are
accurate to well below a millimetre of the curve.

Builders: :func:`circle`, :func:`figure8`, :func:`square`, :func:`polyline` (corners blended
by arcs, or stopped at), :func:`spline` (a smooth curve through points), :func:`from_samples`
(any curve sampled densely), and the text form :func:`parse_path`. Headings are set by a mode
(:data:`HEADINGS`) or given per point (:func:`given_headings`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..common.messages import shorten
from ..common.number_text import plain_number
from ..errors import InputError
from ..kinematics.se2 import apply, rotate, wrap_angle

HEADING_RADIUS = 0.2
"""``rho`` [m]: the length one radian of heading counts for in the path length ``s``."""

SPACING = 0.002
"""Largest distance [m of ``s``] between the samples of a built path (2 mm)."""

MAX_SAMPLES = 500_000
"""Most samples a path may have (a 1 km path at :data:`SPACING`): a longer one is refused, so a
typo (``circle 1e5``) costs a line, not the machine's memory."""

MAX_COORDINATE = 1e7
"""Largest ``|x|`` or ``|y|`` [m] of a point (map coordinates such as UTM stay below it)."""

MAX_HEADING = 1e4
"""Largest ``|theta|`` [rad] of a heading given (some 1600 turns: beyond it the headings' own
rounding is centimetres of turn)."""

HEADINGS = ("tangent", "fixed", "free")
"""How a path's heading is set when the points do not give one: along the direction of travel
(``tangent``, the only choice of a robot that cannot strafe), held at the start's (``fixed``), or
left to the planner (``free``: held fixed, the heading costing nothing to keep)."""


@dataclass(frozen=True, eq=False)
class Path:
    """A path ``q(s)`` sampled at ``s`` (module docstring).

    Attributes
    ----------
    s : ndarray, shape (n,)
        Path length [m] at the samples, increasing from 0.
    pose : ndarray, shape (n, 3)
        ``(x, y, theta)`` [m, m, rad] at the samples, world frame; ``theta`` unwrapped
        (continuous).
    d1, d2 : ndarray, shape (n, 3)
        ``dq/ds`` [m/m, rad/m] and ``d^2q/ds^2`` [1/m, rad/m^2] at the samples.
    stops : ndarray, shape (n,), bool
        Samples where the robot must be at rest (corners stopped at, the ends).
    name : str
        What the path is, for messages and plots (``"circle 1"``).
    """

    s: np.ndarray
    pose: np.ndarray
    d1: np.ndarray
    d2: np.ndarray
    stops: np.ndarray
    name: str = "path"
    closed: bool = field(default=False)

    @property
    def length(self) -> float:
        """Total path length [m] (``s`` at the end)."""
        return float(self.s[-1])

    @property
    def travel(self) -> float:
        """Distance [m] the centre travels (the ``x, y`` part of the path, heading not counted)."""
        return float(np.sum(np.hypot(*np.diff(self.pose[:, :2], axis=0).T)))


def moved(path: Path, by) -> Path:
    """``path`` moved rigidly by the pose ``by`` ``(x, y, theta)`` [m, m, rad]: each sample
    ``q`` becomes ``by (+) q`` (:func:`omnikin.kinematics.se2.compose`, the heading kept
    unwrapped), its derivatives turned with it. Lengths, stops and timings are unchanged; to
    move a path so that it starts at the origin heading along +x, ``by`` is the inverse of its
    first pose."""
    x, y, theta = (float(v) for v in by)
    pose = np.column_stack((apply((x, y, theta), path.pose[:, :2]), path.pose[:, 2] + theta))
    d1 = np.column_stack((rotate(theta, path.d1[:, :2]), path.d1[:, 2]))
    d2 = np.column_stack((rotate(theta, path.d2[:, :2]), path.d2[:, 2]))
    return Path(path.s, pose, d1, d2, path.stops, path.name, path.closed)


def _checked_points(points, name: str, width: int) -> np.ndarray:
    try:
        arr = np.asarray(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: not numbers ({exc})") from None
    if arr.ndim != 2 or arr.shape[1] not in (2, width):
        raise InputError(f"{name}: expected rows of x, y (or x, y, theta), got shape {arr.shape}")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        raise InputError(f"{name}: point {int(bad[0][0])} is not finite")
    far = np.argwhere(np.abs(arr[:, :2]) > MAX_COORDINATE)
    if far.size:
        raise InputError(f"{name}: point {int(far[0][0])} is more than {MAX_COORDINATE:g} m from the origin")
    return arr


def from_samples(
    xy, theta, *, name: str, stops=None, breaks=None, closed: bool = False, rho: float = HEADING_RADIUS
) -> Path:
    """A :class:`Path` from dense samples of a curve: positions ``(n, 2)`` [m] and headings
    ``(n,)`` [rad], in order along the path.

    Samples that repeat the one before (no travel, no turn) are dropped. The derivatives are
    second-order finite differences in ``s`` (module docstring), taken piece by piece between
    ``stops`` and ``breaks`` (``(n,)`` bool: samples where the curvature jumps, a line meeting an
    arc, where a difference across would tilt the tangent by a quarter of the jump times the
    spacing and the heading along it would no longer be the direction of travel).

    Raises
    ------
    InputError
        Fewer than two distinct samples, or non-finite values.
    """
    xy = np.asarray(xy, dtype=float)
    if len(xy) > MAX_SAMPLES:
        raise InputError(f"path {name!r}: {len(xy)} samples is too many (at most {MAX_SAMPLES})")
    th = np.unwrap(np.asarray(theta, dtype=float))
    stop = np.zeros(len(th), dtype=bool) if stops is None else np.asarray(stops, dtype=bool).copy()
    cut = np.zeros(len(th), dtype=bool) if breaks is None else np.asarray(breaks, dtype=bool).copy()
    step = np.hypot(np.hypot(*np.diff(xy, axis=0).T), rho * np.diff(th))
    keep = np.concatenate(([True], step > 1e-12))
    # a dropped repeat keeps its stop (and break) on the sample it repeats
    idx = np.cumsum(keep) - 1
    merged = np.zeros(int(keep.sum()), dtype=bool)
    np.logical_or.at(merged, idx, stop)
    merged_cut = np.zeros(int(keep.sum()), dtype=bool)
    np.logical_or.at(merged_cut, idx, cut)
    xy, th, stop, cut = xy[keep], th[keep], merged, merged_cut
    if len(th) < 2:
        raise InputError(f"path {name!r}: it does not go anywhere (fewer than two distinct points)")
    s = np.concatenate(([0.0], np.cumsum(step[keep[1:]])))
    pose = np.column_stack((xy, th))
    stop[0] = stop[-1] = True
    # derivatives piece by piece between stops and breaks: a corner stopped at is a kink, and
    # differences across it would be spikes; the sample that ends one piece and starts the next
    # takes the derivatives of the piece it starts
    ends = np.flatnonzero(stop | cut)
    short = np.flatnonzero(np.diff(ends) < 2)
    if short.size:
        at = s[ends[short[0]]]
        raise InputError(f"path {name!r}: a piece between two stops at s = {at:.6g} m has no inner point")
    d1 = _piecewise_gradient(pose, s, ends)
    d2 = _piecewise_gradient(d1, s, ends, split=True)
    return Path(s, pose, d1, d2, stop, name, closed)


def _piecewise_gradient(values: np.ndarray, s: np.ndarray, ends: np.ndarray, *, split: bool = False) -> np.ndarray:
    """``d values / ds`` ``(n, ...)`` by second-order differences piece by piece between the
    sample indices ``ends`` (never across one: a stop or a join); the sample that ends one piece
    and starts the next takes the derivative of the piece it starts. ``split``: the values
    themselves are a piece's (derived from the derivatives, such as the direction of travel), so
    the sample that ends a piece holds the next piece's value and each piece but the last is
    differentiated without it; otherwise (positions, continuous across the joins) with it."""
    out = np.zeros_like(values, dtype=float)
    last = len(ends) - 2
    for k, (a, b) in enumerate(zip(ends[:-1], ends[1:], strict=True)):
        stop = b + 1 if not split or k == last else b
        piece = slice(a, stop)
        out[piece] = np.gradient(values[piece], s[piece], axis=0, edge_order=2 if stop - a >= 3 else 1)
    return out


def derivative(path: Path, values) -> np.ndarray:
    """``d values / ds`` along ``path`` of values at its samples ``(n, k)`` that belong to the
    pieces between its stops (a corner stopped at is a kink: the stop's sample holds the value of
    the piece it starts, such as the wheel speeds per unit path speed along its direction)."""
    return _piecewise_gradient(np.asarray(values, dtype=float), path.s, np.flatnonzero(path.stops), split=True)


def body_rates(path: Path) -> np.ndarray:
    """The body twist per unit path speed ``(n, 3)``: ``(R(theta)^T (x', y'), theta')`` [m/m,
    m/m, rad/m] at the samples, what any limit of the body's or the wheels' motion sees."""
    th = path.pose[:, 2]
    c, sn = np.cos(th), np.sin(th)
    d = path.d1
    return np.column_stack((c * d[:, 0] + sn * d[:, 1], -sn * d[:, 0] + c * d[:, 1], d[:, 2]))


def _count(length: float, name: str) -> int:
    if not length <= MAX_SAMPLES * SPACING:  # (NaN and inf too)
        raise InputError(f"path {name!r}: {length:.6g} m is too long (at most {MAX_SAMPLES * SPACING:.6g} m of path)")
    n = int(math.ceil(length / SPACING)) + 1
    if n > MAX_SAMPLES:
        raise InputError(f"path {name!r}: {length:.6g} m is too long (at most {MAX_SAMPLES * SPACING:.6g} m of path)")
    return max(n, 3)


def _heading(xy_d: np.ndarray, heading, name: str, start: float = 0.0) -> np.ndarray:
    """Headings ``(n,)`` for the tangent ``xy_d`` ``(n, 2)`` by ``heading`` (:data:`HEADINGS` or a
    number [rad], fixed)."""
    n = len(xy_d)
    if isinstance(heading, str):
        if heading == "tangent":
            return np.unwrap(np.arctan2(xy_d[:, 1], xy_d[:, 0]))
        if heading in ("fixed", "free"):
            return np.full(n, start)
        raise InputError(f"path {name!r}: unknown heading {heading!r}; one of {list(HEADINGS)} or an angle [rad]")
    if isinstance(heading, bool) or not isinstance(heading, (int, float, np.integer, np.floating)):
        raise InputError(
            f"path {name!r}: heading must be one of {list(HEADINGS)} or an angle [rad], got {shorten(heading)}"
        )
    value = float(heading)
    if not (math.isfinite(value) and abs(value) <= MAX_HEADING):
        raise InputError(f"path {name!r}: heading must be an angle within {MAX_HEADING:g} rad, got {heading!r}")
    return np.full(n, value)


def _radius(value, what: str) -> float:
    r = float(value)
    if not (math.isfinite(r) and 0.0 < r <= 1e3):
        raise InputError(f"{what} must be in (0, 1000] m, got {value!r}")
    return r


def circle(radius: float, *, heading="fixed", turns: float = 1.0) -> Path:
    """A circle of ``radius`` [m] started at the origin heading along +x, counter-clockwise
    (centre ``(0, radius)``), ``turns`` times round."""
    r = _radius(radius, "circle radius")
    name = f"circle {radius:g}"
    n = _count(2 * math.pi * r * turns, name)
    phi = np.linspace(0.0, 2 * math.pi * turns, n)
    xy = np.column_stack((r * np.sin(phi), r * (1 - np.cos(phi))))
    tangent = np.column_stack((np.cos(phi), np.sin(phi)))
    return from_samples(xy, _heading(tangent, heading, name), name=name, closed=True)


def figure8(size: float, *, heading="fixed") -> Path:
    """A figure-eight: Gerono's lemniscate ``(u, v) = (size sin(phi), size sin(2 phi) / 2)``
    [m] turned by -45 deg about its crossing, so that it starts at the origin along +x (where a
    robot at rest heading 0 stands), first into the loop on the right of the start."""
    a = _radius(size, "figure-eight size")
    name = f"figure8 {size:g}"
    coarse = np.linspace(0.0, 2 * math.pi, 4001)
    n = _count(float(np.sum(np.hypot(np.diff(a * np.sin(coarse)), np.diff(0.5 * a * np.sin(2 * coarse))))), name)
    phi = np.linspace(0.0, 2 * math.pi, n)
    # Gerono's lemniscate leaves its crossing at 45 deg: turned by -45 deg, it leaves along +x
    c = math.sqrt(0.5)
    u, v = a * np.sin(phi), 0.5 * a * np.sin(2 * phi)
    du, dv = a * np.cos(phi), a * np.cos(2 * phi)
    xy = np.column_stack((c * (u + v), c * (v - u)))
    tangent = np.column_stack((c * (du + dv), c * (dv - du)))
    return from_samples(xy, _heading(tangent, heading, name), name=name, closed=True)


def polyline(
    points,
    *,
    blend: float = 0.0,
    heading="tangent",
    closed: bool = False,
    name: str = "polyline",
    theta=None,
) -> Path:
    """Straight segments through points; each corner either stopped at (``blend`` 0: the robot
    comes to rest and turns there if the heading changes) or cut by a circular arc tangent to
    both segments, of radius ``blend`` or less where the segments are too short for it.

    Parameters
    ----------
    points : array_like, shape (n, 2)
        The corners ``(x, y)`` [m] in the world frame, in order, ``n >= 2``.
    blend : float, default 0
        Radius [m] of the arcs that cut the corners (0: stop at each corner).
    heading : str or float, default "tangent"
        :data:`HEADINGS` or a fixed angle [rad]; not with ``theta``.
    closed : bool, default False
        Go back to the first point at the end.
    name : str
        What the path is called in messages.
    theta : array_like, shape (n,), optional
        A heading [rad] per point, world frame: the heading turns evenly along each segment
        from one point's to the next's, the shorter way round (:func:`given_headings`); on a
        blending arc it turns evenly from where the arc leaves one segment to where it joins
        the next.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        Fewer than two points, two consecutive points the same, a non-finite point, a bad
        blend or heading, or a path longer than :data:`MAX_SAMPLES` samples allow.
    """
    pts = _checked_points(points, name, 2)[:, :2]
    if len(pts) < 2:
        raise InputError(f"path {name!r}: it does not go anywhere (fewer than two points)")
    given = None if theta is None else given_headings(theta, len(pts), name, closed)
    if given is not None:
        if heading != "tangent" and heading is not None:
            raise InputError(f"path {name!r}: headings are given per point; a heading mode ({heading!r}) cannot be too")
        heading = "fixed"
    if closed:
        pts = np.vstack((pts, pts[:1]))
    seg = np.diff(pts, axis=0)
    lens = np.hypot(seg[:, 0], seg[:, 1])
    if np.any(lens <= 1e-9):
        k = int(np.argmax(lens <= 1e-9))
        raise InputError(f"path {name!r}: points {k} and {(k + 1) % (len(pts) - closed)} are the same")
    dirs = seg / lens[:, None]
    _count(float(lens.sum()), name)
    if isinstance(blend, bool) or not isinstance(blend, (int, float, np.integer, np.floating)):
        raise InputError(f"path {name!r}: blend must be a radius >= 0 [m], got {shorten(blend)}")
    blend = float(blend)
    if not (math.isfinite(blend) and blend >= 0):
        raise InputError(f"path {name!r}: blend must be a radius >= 0 [m], got {blend!r}")
    pieces: list[np.ndarray] = []
    headings: list[np.ndarray] = []
    stops: list[np.ndarray] = []
    progress: list[np.ndarray] = []  # where each sample is, in points: k + the fraction of segment k
    start = float(np.arctan2(dirs[0, 1], dirs[0, 0])) if heading == "tangent" else 0.0
    cut_in = np.zeros(len(seg))  # length cut at each segment's start and end by the blends
    cut_out = np.zeros(len(seg))
    arcs = {}
    for k in range(1, len(seg)):
        turn = math.atan2(dirs[k - 1, 0] * dirs[k, 1] - dirs[k - 1, 1] * dirs[k, 0], float(dirs[k - 1] @ dirs[k]))
        if blend == 0 or abs(turn) < 1e-9 or abs(abs(turn) - math.pi) < 1e-9:
            continue
        r = blend
        cut = r * math.tan(abs(turn) / 2)
        room = min(lens[k - 1] / 2, lens[k] / 2)
        if cut > room:
            cut, r = room, room / math.tan(abs(turn) / 2)
        cut_out[k - 1], cut_in[k] = cut, cut
        arcs[k] = (r, turn)
    theta = start
    for k in range(len(seg)):
        a = pts[k] + dirs[k] * cut_in[k]
        b = pts[k + 1] - dirs[k] * cut_out[k]
        m = _count(float(np.hypot(*(b - a))), name)
        t = np.linspace(0.0, 1.0, m)[:, None]
        line = a + (b - a) * t
        tang = np.repeat(dirs[k][None], m, axis=0)
        hd = _heading(tang, heading, name, start)
        if heading == "tangent":
            hd = hd + (theta - hd[0])  # continuous with what came before
        pieces.append(line)
        headings.append(hd)
        progress.append(k + (cut_in[k] + t[:, 0] * (lens[k] - cut_in[k] - cut_out[k])) / lens[k])
        st = np.zeros(m, dtype=bool)
        if k + 1 < len(seg) and k + 1 not in arcs:
            st[-1] = True
        stops.append(st)
        theta = float(hd[-1])
        if k + 1 in arcs:
            r, turn = arcs[k + 1]
            normal = np.array([-dirs[k, 1], dirs[k, 0]]) * math.copysign(1.0, turn)
            centre = b + normal * r
            m = _count(r * abs(turn), name)
            ang = np.linspace(0.0, turn, m)
            rel = b - centre
            c, s = np.cos(ang), np.sin(ang)
            arc = centre + np.column_stack((c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]))
            if heading == "tangent":
                hd = theta + ang
            else:
                hd = np.full(m, theta)
            pieces.append(arc)
            headings.append(hd)
            u0, u1 = k + 1 - cut_out[k] / lens[k], k + 1 + cut_in[k + 1] / lens[k + 1]
            progress.append(np.linspace(u0, u1, m))
            stops.append(np.zeros(m, dtype=bool))
            theta = float(hd[-1])
        elif k + 1 < len(seg) and heading == "tangent":
            # stopped at a corner: turn in place to the next segment's direction
            turn = math.atan2(dirs[k, 0] * dirs[k + 1, 1] - dirs[k, 1] * dirs[k + 1, 0], float(dirs[k] @ dirs[k + 1]))
            m = _count(HEADING_RADIUS * abs(turn), name)
            pieces.append(np.repeat(pts[k + 1][None], m, axis=0))
            headings.append(theta + np.linspace(0.0, turn, m))
            progress.append(np.full(m, k + 1.0))
            st = np.zeros(m, dtype=bool)
            st[-1] = True
            stops.append(st)
            theta += turn
    xy = np.concatenate(pieces)
    th = np.concatenate(headings)
    if given is not None:
        th = np.interp(np.concatenate(progress), np.arange(len(given)), given)
    breaks = np.zeros(len(xy), dtype=bool)  # where a line meets an arc: the curvature jumps
    breaks[np.cumsum([len(piece) for piece in pieces])[:-1]] = True
    return from_samples(xy, th, name=name, stops=np.concatenate(stops), breaks=breaks, closed=closed)


def given_headings(theta, n: int, name: str, closed: bool) -> np.ndarray:
    """Headings given per point, ``(n,)`` [rad], made continuous: each one follows the one before
    by the shorter way round (a difference of exactly half a turn goes counter-clockwise); on
    a closed path one more, back to the first point's heading. ``(n + closed,)``."""
    try:
        th = np.asarray(theta, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise InputError(f"path {name!r}: headings are not numbers ({exc})") from None
    if th.shape != (n,):
        raise InputError(f"path {name!r}: {th.size} headings for {n} points")
    bad = np.flatnonzero(~np.isfinite(th))
    if bad.size:
        raise InputError(f"path {name!r}: the heading of point {int(bad[0])} is not finite")
    far = np.flatnonzero(np.abs(th) > MAX_HEADING)
    if far.size:
        raise InputError(f"path {name!r}: the heading of point {int(far[0])} is beyond {MAX_HEADING:g} rad")
    if closed:
        th = np.append(th, th[0])
    steps = wrap_angle(np.diff(th))
    steps[np.isclose(steps, -math.pi)] = math.pi
    return np.concatenate(([th[0]], th[0] + np.cumsum(steps)))


def spline(
    points, *, heading="tangent", closed: bool = False, name: str = "spline", theta=None, start_direction=None
) -> Path:
    """A smooth curve through points: the cubic spline ``(x(u), y(u))`` through them, ``u`` the
    distance along the straight segments between them (chord length), with zero curvature at
    the ends (natural) or, ``closed``, periodic back to the first point (SciPy's
    :class:`~scipy.interpolate.CubicSpline`). Unlike :func:`polyline` it has no corners, so
    the robot need not slow down at the points; it can bulge between points far apart.

    Parameters
    ----------
    points : array_like, shape (n, 2)
        ``(x, y)`` [m], world frame, in order; ``n >= 2`` (two points: the straight line),
        no two consecutive ones the same.
    heading : str or float, default "tangent"
        :data:`HEADINGS` or a fixed angle [rad]; not with ``theta``.
    closed : bool, default False
        Periodic, back to the first point at the end.
    name : str
        What the path is called in messages.
    theta : array_like, shape (n,), optional
        A heading [rad] per point (:func:`given_headings`), splined the same way.
    start_direction : float, optional
        The direction [rad] in which the curve leaves the first point (a clamped start: a robot
        with fixed wheels leaves along its heading); default free (natural). Not with ``closed``.

    Returns
    -------
    Path
    """
    from scipy.interpolate import CubicSpline

    pts = _checked_points(points, name, 2)[:, :2]
    if len(pts) < 2:
        raise InputError(f"path {name!r}: it does not go anywhere (fewer than two points)")
    given = None if theta is None else given_headings(theta, len(pts), name, closed)
    if given is not None and heading != "tangent" and heading is not None:
        raise InputError(f"path {name!r}: headings are given per point; a heading mode ({heading!r}) cannot be too")
    if closed:
        pts = np.vstack((pts, pts[:1]))
    chord = np.hypot(*np.diff(pts, axis=0).T)
    if np.any(chord <= 1e-9):
        k = int(np.argmax(chord <= 1e-9))
        raise InputError(f"path {name!r}: points {k} and {(k + 1) % (len(pts) - closed)} are the same")
    _count(float(chord.sum()), name)
    u = np.concatenate(([0.0], np.cumsum(chord)))
    bc: object
    if start_direction is not None:
        if closed:
            raise InputError(f"path {name!r}: a closed curve has no start direction of its own")
        lead = np.array([math.cos(float(start_direction)), math.sin(float(start_direction))])
        bc = ((1, lead), (2, np.zeros(2)))  # (u is the chord length: |q'(u)| is about 1)
    elif len(pts) == 2:
        bc = "not-a-knot"
    else:
        bc = "periodic" if closed else "natural"
    curve = CubicSpline(u, pts, bc_type=bc)
    # the spline's own length, on a grid ten times finer than the samples, then samples evenly
    # spaced in it
    fine_u = np.linspace(0.0, u[-1], 10 * _count(float(u[-1]), name))
    fine_len = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(curve(fine_u), axis=0).T))))
    n = _count(float(fine_len[-1]), name)
    at = np.interp(np.linspace(0.0, fine_len[-1], n), fine_len, fine_u)
    xy = curve(at)
    if given is not None:
        turn_bc = "periodic" if closed and len(pts) > 2 and math.isclose(given[-1], given[0]) else "not-a-knot"
        th = CubicSpline(u, given, bc_type=turn_bc if len(pts) > 2 else "not-a-knot")(at)
    else:
        th = _heading(curve(at, 1), heading, name)
    return from_samples(xy, th, name=name, closed=closed)


def square(side: float, *, blend: float = 0.0, heading="tangent") -> Path:
    """The square of ``side`` [m], first leg along +x, counter-clockwise, closed."""
    a = _radius(side, "square side")
    pts = [(0.0, 0.0), (a, 0.0), (a, a), (0.0, a)]
    named = isinstance(blend, (int, float)) and not isinstance(blend, bool) and blend > 0
    name = f"square {side:g}" + (f" {blend:g}" if named else "")
    return polyline(pts, blend=blend, heading=heading, closed=True, name=name)


def heading_error(a, b) -> np.ndarray:
    """``wrap(a - b)`` [rad], elementwise: the signed heading difference."""
    return wrap_angle(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


PATH_SPECS = {
    "circle": ("RADIUS", "a circle of RADIUS [m], counter-clockwise"),
    "figure8": ("SIZE", "a figure-eight SIZE [m] across each loop"),
    "square": ("SIDE [BLEND]", "a square of SIDE [m], corners stopped at or blended by arcs of BLEND [m]"),
}
"""The built-in paths of the text form: name -> (arguments, what it is)."""

SPEC_GRAMMAR = "; ".join(f"'{name} {args}'" for name, (args, _) in PATH_SPECS.items())
"""The text form, as messages give it."""


def parse_path(text: str, *, heading=None) -> Path:
    """A built-in path from its text form (:data:`PATH_SPECS`), e.g. ``"figure8 1"``,
    ``"square 2 0.3"``; every path starts at the origin along +x.

    Parameters
    ----------
    text : str
        The name and its numbers [m], separated by blanks.
    heading : str or float, optional
        :data:`HEADINGS` or a fixed angle [rad]; default ``fixed`` for the circle and the
        figure-eight (a robot that translates keeps its heading) and ``tangent`` for the square.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        An unknown name, a missing or extra number, a number out of range; one line with the
        grammar.
    """
    if not isinstance(text, str):
        raise InputError(f"path must be text like 'figure8 1', got {shorten(text)}")
    words = text.split()
    if not words or words[0].lower() not in PATH_SPECS:
        raise InputError(f"unknown path {shorten(text)}; one of {SPEC_GRAMMAR}, or a path file (.csv, .yaml)")
    name = words[0].lower()
    args = PATH_SPECS[name][0].split()
    optional = sum(a.startswith("[") for a in args)
    if not (len(args) - optional <= len(words) - 1 <= len(args)):
        raise InputError(f"path {shorten(text)}: expected '{name} {PATH_SPECS[name][0]}'")
    nums = [plain_number(w, f"path {shorten(text)}: {a.strip('[]')}") for w, a in zip(words[1:], args, strict=False)]
    if name == "circle":
        return circle(nums[0], heading="fixed" if heading is None else heading)
    if name == "figure8":
        return figure8(nums[0], heading="fixed" if heading is None else heading)
    return square(nums[0], blend=nums[1] if len(nums) > 1 else 0.0, heading="tangent" if heading is None else heading)
