"""Motion plans: paths as constant-twist segments, and measured runs of them.

A :class:`Segment` moves the body along the one-parameter subgroup ``exp(s * xi)`` of
SE(2): ``xi`` is the body twist per unit of progress ``s`` (for a straight leg a unit
direction, s in metres; for a spin ``(0, 0, +-1)``, s in radians; for an arc
``(1, 0, 1/R)``, s the arc length) and the segment ends at ``s = length``. Any speed
profile ``s(t)`` then traces exactly the same path; timing and sampling under limits are
:mod:`omnikin.motion.timing`.

UMBmark squares follow ``docs/conventions.md`` (Borenstein and Feng, "Measurement and
correction of systematic odometry errors in mobile robots", IEEE Trans. Robotics and
Automation 12(6), 1996): the first leg runs along +x, ``cw`` turns right, ``ccw`` turns
left; ``rotate`` mode drives every leg along body x and turns in place by -+90 deg at each
corner (the last turn restores the start heading), ``translate`` mode (holonomic robots)
translates along +-x and +-y with the heading held.

Text form of a plan (:func:`parse_plan`, the ``path`` column of calibration-run files)::

    square cw|ccw rotate|translate [SIDE]    (default side 4 m)
    line LENGTH [HEADING_DEG]                 straight, along body direction HEADING_DEG
    spin ANGLE_DEG                            turn in place (positive: counter-clockwise)
    arc RADIUS ANGLE_DEG                      forward on a circle

:class:`CalibrationRun` is a plan driven on a robot with its measured end pose: what the
calibration fits and what measurement files hold.
"""

from __future__ import annotations

import math
import re
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..common.arrays import range_problem
from ..common.messages import shorten
from ..common.number_text import plain_number
from ..errors import InputError
from ..kinematics.se2 import MAX_DIRECTION_DEG, wrap_angle

UMBMARK_SIDE = 4.0
"""Side of the UMBmark square [m]: Borenstein & Feng's 4 m x 4 m (UMBmark, 1996), the default
of every square, calibration run and study that does not give its own."""

MAX_SEGMENT = 1e5
"""Longest segment [m or rad]: 100 km of travel, or about 16,000 turns in place. Beyond it a
plan is a typo (``line 1e308``), not a robot's path: refused before anything is sampled."""

MAX_HEADING = math.radians(MAX_DIRECTION_DEG)
"""Largest ``|heading|`` [rad] of a :func:`line`: a direction, bounded like every direction a
person writes (:data:`omnikin.kinematics.se2.MAX_DIRECTION_DEG`, two turns)."""

MAX_TURN_DEG = math.degrees(MAX_SEGMENT)
"""Largest ``|ANGLE_DEG|`` [deg] of a ``spin`` or an ``arc`` in the text form: the longest
segment, :data:`MAX_SEGMENT` rad (about 5.7e6 deg)."""

PATH_BLANKS = " \t"
"""The characters that separate the words of a path (ASCII blanks); any other white space
(a newline, U+3000, U+001C, ...) is refused, where :meth:`str.split` would take it."""


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
        if not (math.isfinite(self.length) and 0 <= self.length <= MAX_SEGMENT):
            raise InputError(
                f"segment {self.label!r}: length must be from 0 to {MAX_SEGMENT:g} [m or rad], got {self.length!r}"
            )
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

    def __add__(self, other: Plan) -> Plan:
        return Plan(self.segments + other.segments, f"{self.name}+{other.name}")

    def end_pose(self) -> np.ndarray:
        """Pose reached when every segment is driven exactly (from the origin)."""
        from ..kinematics.se2 import compose, exp

        pose = np.zeros(3)
        for seg in self.segments:
            pose = compose(pose, exp(np.array(seg.xi) * seg.length))
        return pose


# --- path builders -----------------------------------------------------------------------------
def line(distance: float, heading: float = 0.0) -> Plan:
    """Straight translation by ``distance`` [m] along body direction ``heading`` [rad],
    ``|heading| <=`` :data:`MAX_HEADING`."""
    problem = range_problem(heading, -MAX_HEADING, MAX_HEADING, "rad")
    if problem:
        raise InputError(f"line heading {problem} (a direction: two turns either way)")
    sign = 1.0 if distance >= 0 else -1.0
    return Plan((Segment((sign * math.cos(heading), sign * math.sin(heading), 0.0), abs(distance), "line"),), "line")


def spin(angle: float) -> Plan:
    """Turn in place by ``angle`` [rad] (positive: counter-clockwise)."""
    return Plan((Segment((0.0, 0.0, 1.0 if angle >= 0 else -1.0), abs(angle), "spin"),), "spin")


def arc(radius: float, angle: float) -> Plan:
    """Drive forward on a circle of ``radius`` [m] (centre on the left if ``angle`` > 0) by
    ``angle`` [rad], a turn of at most :data:`MAX_SEGMENT` rad."""
    problem = range_problem(radius, 0.0, math.inf, "m")
    if problem or not (radius > 0 and math.isfinite(1.0 / radius)):
        raise InputError(f"arc radius must be > 0 with a finite curvature 1/radius, got {shorten(radius)} m")
    problem = range_problem(angle, -MAX_SEGMENT, MAX_SEGMENT, "rad")
    if problem:
        raise InputError(f"arc angle {problem} (the longest turn)")
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
            turn = wrap_angle(bearing - heading)
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
        raise InputError(f"unknown path mode {shorten(mode)}; one of ['rotate', 'translate']")
    return mode


def check_direction(direction: str) -> str:
    if direction not in ("cw", "ccw"):
        raise InputError(f"unknown UMBmark direction {shorten(direction)}; one of ['cw', 'ccw']")
    return direction


def umbmark_square(direction: str = "cw", side: float = UMBMARK_SIDE, mode: str = "rotate") -> Plan:
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


PATH_KINDS = ("square", "line", "spin", "arc")
"""The first words of the paths of the text form (module docstring)."""

PATH_GRAMMAR = (
    "'square cw|ccw rotate|translate [SIDE]', 'line LENGTH [HEADING_DEG]', 'spin ANGLE_DEG' or 'arc RADIUS ANGLE_DEG'"
)
"""The text form of a path, as messages give it."""


def parse_plan(text: str) -> Plan:
    """A plan from its text form (module docstring): ``square cw|ccw rotate|translate [SIDE]``,
    ``line LENGTH [HEADING_DEG]``, ``spin ANGLE_DEG`` or ``arc RADIUS ANGLE_DEG``.

    Its words are separated by ASCII blanks (:data:`PATH_BLANKS`); its numbers are plain
    decimals, as in every table (:data:`omnikin.common.number_text.PLAIN_NUMBER`: not ``nan``, ``inf``,
    ``1_0``, non-ASCII digits), whether the path comes from a runs file, ``--path`` or Python.
    ``HEADING_DEG`` is a direction within +-:data:`~omnikin.kinematics.se2.MAX_DIRECTION_DEG`,
    ``ANGLE_DEG`` a turn within +-:data:`MAX_TURN_DEG`. Anything else is an
    :class:`~omnikin.errors.InputError` in one line naming the path and what is wrong, in the
    units it was written in."""
    if not isinstance(text, str):
        raise InputError(f"path must be text ({PATH_GRAMMAR}), got {shorten(text)}")
    where = f"path {shorten(text)}"
    words = path_words(text, where)
    if not words:
        raise InputError("empty path")
    kind, args = words[0].lower(), words[1:]
    if kind not in PATH_KINDS:
        raise InputError(
            f"{where}: unknown kind of path {shorten(words[0])}; one of {list(PATH_KINDS)} ({PATH_GRAMMAR})"
        )
    if kind == "square":
        if len(args) not in (2, 3):
            raise InputError(f"{where}: expected 'square cw|ccw rotate|translate [SIDE]'")
        side = _path_numbers(args[2:], where)
        try:
            return umbmark_square(args[0].lower(), side[0] if side else UMBMARK_SIDE, args[1].lower())
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
    nums = _path_numbers(args, where)
    try:
        if kind == "line" and len(nums) in (1, 2):
            heading = nums[1] if len(nums) == 2 else 0.0
            _require_degrees(heading, MAX_DIRECTION_DEG, "heading", "a direction: two turns either way")
            return line(nums[0], math.radians(heading))
        if kind == "spin" and len(nums) == 1:
            _require_degrees(nums[0], MAX_TURN_DEG, "angle", f"the longest turn, {MAX_SEGMENT:g} rad")
            return spin(math.radians(nums[0]))
        if kind == "arc" and len(nums) == 2:
            _require_degrees(nums[1], MAX_TURN_DEG, "angle", f"the longest turn, {MAX_SEGMENT:g} rad")
            return arc(nums[0], math.radians(nums[1]))
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    raise InputError(f"{where}: expected {PATH_GRAMMAR}")


def path_words(text: str, where: str = "path") -> list[str]:
    """The words of a path: ``text`` split at runs of :data:`PATH_BLANKS`; other white space
    is an InputError naming ``where`` and the character."""
    odd = next((c for c in text if c.isspace() and c not in PATH_BLANKS), None)
    if odd is not None:
        raise InputError(
            f"{where}: white space U+{ord(odd):04X} {unicodedata.name(odd, '')}".rstrip()
            + "; separate the words with spaces"
        )
    return [w for w in re.split(f"[{PATH_BLANKS}]+", text) if w]


def _require_degrees(value: float, limit: float, what: str, why: str) -> None:
    """Refuse ``|value| > limit`` [deg] with a message in degrees, as the path was written."""
    problem = range_problem(value, -limit, limit, "deg")
    if problem:
        raise InputError(f"{what} {problem} ({why})")


def _path_numbers(words: list[str], where: str) -> list[float]:
    """The numbers of a path (:func:`omnikin.common.number_text.plain_number`); the first bad one is
    an InputError naming the path."""
    return [plain_number(w, where) for w in words]


@dataclass(frozen=True)
class CalibrationRun:
    """A plan driven by the nominal model and its measured end pose ``(x, y, theta)``.

    ``theta`` may be NaN when the heading was not measured. ``sigma`` is the measurement
    standard deviation ``(m, rad)``. ``source`` says where the run was read from (e.g.
    ``"runs.csv: line 5"``), so that an error about the run can name it.
    """

    plan: Plan
    measured: tuple
    label: str = ""
    sigma: tuple = (0.001, math.radians(0.2))
    source: str = ""

    def __post_init__(self):
        m = tuple(float(v) for v in self.measured)
        if len(m) != 3 or not (math.isfinite(m[0]) and math.isfinite(m[1])) or math.isinf(m[2]):
            raise InputError(
                f"calibration run {self.label!r}: measured end pose needs finite x and y "
                f"(theta may be NaN when not measured), got {self.measured!r}"
            )
        if not all(s > 0 for s in self.sigma):
            raise InputError(f"calibration run {self.label!r}: sigma must be positive, got {self.sigma!r}")
        object.__setattr__(self, "measured", m)
