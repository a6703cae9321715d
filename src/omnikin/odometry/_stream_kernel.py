"""Generated kernels of the streaming odometry (:class:`omnikin.odometry.streaming.Odometry`).

Why generated: a CPython update that loops over wheels or calls NumPy costs 3-10 us; the
same arithmetic unrolled for the robot's own wheel count, with its constants written in,
costs well under 1 us (``docs/performance.md``). Like :func:`collections.namedtuple` and
:mod:`dataclasses`, the source is built from one template and compiled once per
configuration; it is registered with :mod:`linecache`, so tracebacks show its lines
(:attr:`Kernels.source` holds it too).

Every kernel is a pure function of an immutable state tuple (layout: the ``S_*`` indices
below) and one sample; it returns the new state, or None when it doubts anything, and the
estimator's general path then decides (integrates the sample the same way, or raises). So
an update that raises cannot have changed the estimator, and estimators copy and pickle
as plain data. Per sample, ``step_ticks`` does (conventions, Odometry):

1. accept lists and tuples of Python ints or NumPy integer scalars, and NumPy rows (converted
   exactly; bools, floats, iterators and anything else are left to the general path), the
   timestamp as a float; an interval longer than :func:`longest_interval` goes to the general
   path (its step might leave the bounds of :func:`omnikin.odometry.integration.step_problem`);
2. counter increments ``d_j = ticks_j - prev_j`` in exact arithmetic (wrapped modulo
   ``2**bits`` for counters of a known width, after checking the reading lies in the
   counter's range), rounded once to floats: the state keeps the previous readings as exact
   numbers (ints, or the Fraction a float reading holds), never as floats, so ``ticks_j -
   prev_j`` is exact (``int - float`` rounds the int first beyond 2**53);
3. every wheel's jump rule (:mod:`omnikin.odometry.plausibility`) ``|d_j| <= limit_j(dt)`` and, from the
   third sample on, a sufficient form of its change-of-speed rule ``|d_j - q_j| <= A_j dt
   dt_prev / 2 + 2 slack`` (``q_j`` the previous increment; :func:`_change_lines`), with the
   limits shrunk by :data:`SAFETY` so that float rounding never accepts what the exact rule
   refuses; a sample beyond them goes to the general path, which decides exactly;
4. body increment ``(a, b, phi) = F d`` (``F`` = forward kinematics per tick);
5. the pose update of :mod:`omnikin.odometry.integration` (:data:`ADVANCE`).

``step_angles`` is the same for wheel angles [rad] (floats, no counter). ``fk`` and
``move`` are steps 4 and 5 alone, compiled from the same lines, for the general path: both
paths integrate bit for bit alike.
"""

from __future__ import annotations

import hashlib
import linecache
import math
import operator
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from math import cos, floor, pi, sin

import numpy as np

from ..kinematics.se2 import SCALAR_TAYLOR_LIMIT, TWO_PI
from .integration import STEP_BOUNDS
from .plausibility import QUANTISATION_SLACK, SAFETY

# --- state layout ------------------------------------------------------------------------------
S_POSE, S_TIME_TICKS, S_TIME_ANGLES, S_COUNT, S_DT, S_READ = 0, 1, 2, 3, 4, 5
"""State = ``(pose, t_ticks, t_angles, samples, dt, reading_0..n-1, delta_0..n-1)``: the pose
tuple (x, y, theta) [m, m, rad]; the time [s] of the last accepted sample in the slot of its
kind (tick readings or wheel angles), the other slot NaN, both before the first sample, so that
a kernel fed the other kind (or nothing yet) fails its time test and declines; how many samples
were accepted; the last interval [s] (NaN after the first sample: no interval yet, so a kernel
with a change-of-speed test declines the second sample and the general path takes it); the
readings of the last sample (tick readings as exact numbers: Python ints, or Fractions;
wheel angles as floats) and the wheel increments over the last interval [ticks or rad,
floats]. The body increment of the last interval is not kept: it is ``fk(delta)``, recomputed
bit for bit when asked for. Pickles carry the version of this layout
(:data:`omnikin.odometry.streaming.STATE_FORMAT`)."""
KIND_NONE, KIND_TICKS, KIND_ANGLES = 0, 1, 2


def state_kind(state) -> int:
    """What the estimator was fed since its last reset (:data:`KIND_NONE` before the first sample)."""
    if state[S_TIME_TICKS] == state[S_TIME_TICKS]:
        return KIND_TICKS
    return KIND_ANGLES if state[S_TIME_ANGLES] == state[S_TIME_ANGLES] else KIND_NONE


def state_time(state) -> float:
    """Time [s] of the last accepted sample (NaN before the first)."""
    return state[S_TIME_ANGLES] if state_kind(state) == KIND_ANGLES else state[S_TIME_TICKS]


NUMPY_INTS = frozenset(
    {
        np.int8,
        np.int16,
        np.int32,
        np.int64,
        np.uint8,
        np.uint16,
        np.uint32,
        np.uint64,
        np.intc,
        np.uintc,
        np.longlong,
        np.ulonglong,
        np.intp,
        np.uintp,
    }
)
"""NumPy integer scalar types (bool excluded): converted exactly with ``operator.index``."""
NUMBERS = frozenset({int, np.float64, np.float32, np.float16}) | NUMPY_INTS
"""Other types converted to float for timestamps and wheel angles."""

ADVANCE = {
    "exact": (
        "x = 0.5 * phi\n"
        "h = th + x\n"
        "k = 1.0 - x * x / 6.0 if -SMALL < x < SMALL else sin(x) / x  # as geometry.sinc_scalar\n"
    ),
    "midpoint": "h = th + 0.5 * phi\nk = 1.0\n",
    "euler": "h = th\nk = 1.0\n",
}
"""Heading ``h`` and chord factor ``k`` of one step, per method (see integration.py)."""

_MOVE = (
    "c = cos(h)\n"
    "s = sin(h)\n"
    "x = px + k * (c * a - s * b)\n"
    "y = py + k * (s * a + c * b)\n"
    "th += phi\n"
    "if th >= PI or th < NEG_PI:\n"
    "    th -= TWO_PI * floor((th + PI) / TWO_PI)  # as geometry.wrap_angle\n"
)

_CONSTANTS = {
    "cos": cos,
    "sin": sin,
    "floor": floor,
    "PI": pi,
    "NEG_PI": -pi,
    "TWO_PI": TWO_PI,
    "SMALL": SCALAR_TAYLOR_LIMIT,
    "INF": math.inf,
    "NAN": math.nan,
    "INT": int,
    "FLOAT": float,
    "LIST": list,
    "TUPLE": tuple,
    "ARRAY": np.ndarray,
    "NUMPY_INTS": NUMPY_INTS,
    "NUMBERS": NUMBERS,
    "INDEX": operator.index,
}
"""Names the kernels use: the globals of their own namespace (one per compiled source)."""


@dataclass(frozen=True)
class WheelBound:
    """The jump rule of one wheel in the form the kernel tests: ``|d| <= slope * dt + offset``,
    and never above ``cap`` [ticks or rad]."""

    slope: float
    offset: float
    cap: float = math.inf


@dataclass(frozen=True)
class ChangeBound:
    """The change-of-speed rule of one wheel (:func:`omnikin.odometry.plausibility.change_limit`) as the
    kernel tests it (:func:`_change_lines`): ``half_accel`` is half the acceleration bound
    (inf: no rule) and ``slack`` the quantisation slack of one increment [ticks or rad]."""

    half_accel: float
    slack: float


@dataclass(frozen=True)
class Kernels:
    """The generated functions of one estimator configuration (all pure)."""

    step_ticks: Callable | None
    step_angles: Callable | None
    fk_ticks: Callable | None
    fk_angles: Callable | None
    move: Callable
    source: str


def _indent(text: str, level: int = 1) -> list[str]:
    return ["    " * level + line for line in text.splitlines()]


def _literal(x: float) -> str:
    """A float constant as source text (``INF`` for an infinite bound: ``repr`` gives ``inf``)."""
    if math.isinf(x):
        return "INF" if x > 0 else "-INF"
    return repr(x)


def _check_lines(d: list[str], bounds: list[WheelBound]) -> list[str]:
    """``|d_j| <= min(slope_j dt + offset_j, cap_j) * SAFETY`` for every wheel, one limit per
    distinct rule; a sample near or past a limit is left to the general path's exact rule."""
    names: dict[WheelBound, str] = {}
    lines, tests = [], []
    for v, b in zip(d, bounds, strict=True):
        if b not in names:
            names[b] = f"L{len(names)}"
            lim = names[b]
            if b.slope:
                lines.append(f"{lim} = {_literal(b.slope * SAFETY)} * dt + {_literal(b.offset * SAFETY)}")
                if math.isfinite(b.cap):
                    lines += [f"if {lim} > {_literal(b.cap * SAFETY)}:", f"    {lim} = {_literal(b.cap * SAFETY)}"]
            else:
                lines.append(f"{lim} = {_literal(min(b.offset, b.cap) * SAFETY)}")
            lines.append(f"M{lim[1:]} = -{lim}")
        lim = names[b]
        tests.append(f"M{lim[1:]} <= {v} <= {lim}")
    lines.append(f"if not ({' and '.join(tests)}):")
    lines.append("    return None  # near or past a limit: the general path decides")
    return lines


def _change_lines(d: list[str], bounds: list[ChangeBound]) -> list[str]:
    """The change-of-speed test of every wheel with a bound, in its cheap sufficient form:
    :func:`omnikin.odometry.plausibility.change_limit` is at least ``a min(dt, dtp) (dt + dtp) / 2 + 2 slack``
    (both of its terms are), and ``min(dt, dtp) (dt + dtp) >= dt dtp``, so an increment within
    ``a dt dtp / 2 + 2 slack`` (times :data:`SAFETY`) of the previous one passes; anything else
    (a wrap, a hard stop, very uneven intervals with a change of speed) goes to the general
    path, which evaluates the exact rule. ``dtp`` is NaN before the second interval, so the test
    fails there and the general path takes that sample (it has no previous speed to compare)."""
    active = [(v, b) for v, b in zip(d, bounds, strict=True) if math.isfinite(b.half_accel)]
    if not active:
        return []
    lines = []
    names: dict[ChangeBound, str] = {}
    tests = []
    for v, b in active:
        if b not in names:
            names[b] = f"C{len(names)}"
            lim = names[b]
            lines.append(f"{lim} = {_literal(b.half_accel * SAFETY)} * dt * dtp + {_literal(2.0 * b.slack * SAFETY)}")
            lines.append(f"N{lim[1:]} = -{lim}")
        lim = names[b]
        tests.append(f"N{lim[1:]} <= {v} - q{v[1:]} <= {lim}")
    lines.append(f"if not ({' and '.join(tests)}):")
    lines.append("    return None  # beyond the cheap bound: the general path decides exactly")
    return lines


def _fk_lines(fk_rows, d: list[str]) -> list[str]:
    """``(a, b, phi) = F d``; terms whose coefficient is exactly zero are left out (d is finite)."""
    lines = []
    for name, row in zip(("a", "b", "phi"), fk_rows, strict=True):
        terms = [f"{float(c)!r} * {v}" for c, v in zip(row, d, strict=True) if float(c) != 0.0]
        lines.append(f"{name} = " + (" + ".join(terms) if terms else "0.0"))
    return lines


def _unpack(n: int, angles: bool) -> str:
    times = "_, t_prev" if angles else "t_prev, _"
    return (
        f"(px, py, th), {times}, count, dtp, "
        + ", ".join(f"p{j}" for j in range(n))
        + ", "
        + ", ".join(f"q{j}" for j in range(n))
    )


def _step_source(
    name: str,
    n: int,
    fk_rows,
    bounds: list[WheelBound],
    changes: list[ChangeBound],
    bits: list,
    method: str,
    angles: bool,
) -> str:
    """Source of ``name(state, t, values)``: one sample of ticks (or wheel angles) -> state or None.
    Intervals longer than :func:`longest_interval` go to the general path."""
    v = [f"v{j}" for j in range(n)]
    d = [f"d{j}" for j in range(n)]
    body = [
        f"{_unpack(n, angles)} = state  # t_prev: NaN before the first sample or after the other kind",
        "try:",
        "    if t.__class__ is not FLOAT:",
        "        if t.__class__ not in NUMBERS:",
        "            return None",
        "        t = FLOAT(t)",
        "    if values.__class__ is not LIST and values.__class__ is not TUPLE:",
        "        if values.__class__ is not ARRAY:",
        "            return None  # an iterator would be used up here: the general path reads it",
        "        values = values.tolist()  # exact Python ints (or floats, bools: refused below)",
        f"    {', '.join(v)}, = values",
    ]
    for j in range(n):
        if angles:
            body += [
                f"    if {v[j]}.__class__ is not FLOAT:",
                f"        if {v[j]}.__class__ not in NUMBERS:",
                "            return None",
                f"        {v[j]} = FLOAT({v[j]})",
                f"    {d[j]} = {v[j]} - p{j}",
            ]
            continue
        body += [
            f"    if {v[j]}.__class__ is not INT:",
            f"        if {v[j]}.__class__ not in NUMPY_INTS:",
            "            return None  # floats, bools, anything else",
            f"        {v[j]} = INDEX({v[j]})",
        ]
        if bits[j] is None:
            body.append(f"    {d[j]} = {v[j]} - p{j} + 0.0")
        else:
            half = 1 << (bits[j] - 1)
            body += [
                f"    if not {-half} <= {v[j]} < {2 * half}:",
                f"        return None  # outside the {bits[j]}-bit counter: the general path raises",
                f"    {d[j]} = (({v[j]} - p{j} + {half}) & {2 * half - 1}) - {half} + 0.0",
            ]
    body += [
        "except (TypeError, ValueError, OverflowError):",
        "    return None  # the general path names what is wrong",
        "dt = t - t_prev",
        f"if not 0.0 < dt < {_literal(longest_interval(fk_rows, bounds))}:",
        "    return None  # not later, or so long that the step may be out of bounds: the general path decides",
    ]
    body += _check_lines(d, bounds)
    body += _change_lines(d, changes)
    body += _fk_lines(fk_rows, d)
    body += ADVANCE[method].splitlines() + _MOVE.splitlines()
    times = "NAN, t" if angles else "t, NAN"
    body.append(f"return ((x, y, th), {times}, count + 1, dt, {', '.join(v)}, {', '.join(d)})")
    doc = (
        f'"""One sample of {"wheel angles [rad]" if angles else "tick readings"} for {n} wheels, '
        f'{method} integration: the new state, or None."""'
    )
    return f"def {name}(state, t, values):\n    {doc}\n" + "\n".join(_indent("\n".join(body))) + "\n"


def longest_interval(fk_rows, bounds: list[WheelBound]) -> float:
    """Longest interval [s] (0: none, inf: any) over which every wheel increment the kernel's jump
    test passes (``|d_j| <= min(slope_j dt + offset_j, cap_j) SAFETY``) gives a body increment
    ``F d`` within the bounds of one step (:data:`omnikin.odometry.integration.STEP_BOUNDS`, shrunk by
    :data:`SAFETY`): ``|(F d)_r| <= sum_j |F_rj| |d_j|``. A longer interval goes to the general
    path, which applies :func:`omnikin.odometry.integration.step_problem` to the increment it computes,
    so the kernel never passes a step the general path refuses."""
    longest = math.inf
    for row, limit in zip(fk_rows, STEP_BOUNDS, strict=True):
        terms = [(abs(c), b) for c, b in zip(row, bounds, strict=True) if c != 0.0]
        room = float(limit) * SAFETY
        if sum(c * b.cap * SAFETY for c, b in terms) <= room:
            continue  # the caps alone keep it within bounds (inf caps: never)
        slope = sum(c * b.slope * SAFETY for c, b in terms)
        base = sum(c * min(b.offset, b.cap) * SAFETY for c, b in terms)
        if slope == 0.0:
            longest = longest if base <= room else 0.0
        else:
            longest = min(longest, max(0.0, (room - base) / slope))
    return longest


def _fk_source(name: str, fk_rows, n: int) -> str:
    d = [f"d{j}" for j in range(n)]
    body = _fk_lines(fk_rows, d) + ["return a, b, phi"]
    return (
        f'def {name}({", ".join(d)}):\n    """Body increment (a, b, phi) of wheel increments."""\n'
        + "\n".join(_indent("\n".join(body)))
        + "\n"
    )


def _move_source(method: str) -> str:
    body = "px, py, th = pose\n" + ADVANCE[method] + _MOVE + "return (x, y, th)\n"
    return (
        'def move(pose, a, b, phi):\n    """Pose after the body increment (a, b, phi)."""\n'
        + "\n".join(_indent(body))
        + "\n"
    )


CACHE_SIZE = 64
"""Most configurations whose kernels are kept compiled (least recently built dropped first, with
their :mod:`linecache` entry): a program that builds estimators for ever new robots (a
calibration sweep, a fuzzer) keeps at most this many (each about 30 kB). An estimator keeps its
own kernels; only a traceback through a dropped kernel shows no source lines."""

_COMPILED: OrderedDict[str, tuple[str, dict]] = OrderedDict()
"""Kernels compiled so far, by source (at most :data:`CACHE_SIZE`, most recently built last):
the linecache name and the pure functions, shared by every estimator that needs them."""
_LOCK = threading.Lock()


def _compile(source: str) -> dict:
    with _LOCK:
        found = _COMPILED.get(source)
        if found is not None:
            _COMPILED.move_to_end(source)
            return found[1]
    filename = f"<omnikin-kernel-{hashlib.sha1(source.encode()).hexdigest()[:12]}>"
    namespace = dict(_CONSTANTS)
    exec(compile(source, filename, "exec"), namespace)
    functions = {k: v for k, v in namespace.items() if k not in _CONSTANTS and callable(v) and k != "__builtins__"}
    with _LOCK:
        linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
        _COMPILED[source] = (filename, functions)
        _COMPILED.move_to_end(source)
        while len(_COMPILED) > CACHE_SIZE:
            _, (dropped, _) = _COMPILED.popitem(last=False)
            linecache.cache.pop(dropped, None)
    return functions


def build(
    n: int,
    fk_ticks,
    fk_angles,
    tick_bounds: list[WheelBound],
    angle_bounds: list[WheelBound],
    tick_changes: list[ChangeBound],
    angle_changes: list[ChangeBound],
    bits: list,
    method: str,
) -> Kernels:
    """Kernels for ``n`` encoded wheels. ``fk_ticks``/``fk_angles``: 3 rows of ``n``
    coefficients [m or rad per tick, per rad], or None for robots whose forward kinematics
    changes with steering (only ``move`` then); the jump and change-of-speed bounds in ticks
    and radians; ``bits``: counter width per wheel or None."""
    parts = [_move_source(method)]
    if fk_ticks is not None:
        parts += [
            _step_source("step_ticks", n, fk_ticks, tick_bounds, tick_changes, bits, method, angles=False),
            _step_source("step_angles", n, fk_angles, angle_bounds, angle_changes, bits, method, angles=True),
            _fk_source("fk_ticks", fk_ticks, n),
            _fk_source("fk_angles", fk_angles, n),
        ]
    source = "\n\n".join(parts)
    f = _compile(source)
    return Kernels(f.get("step_ticks"), f.get("step_angles"), f.get("fk_ticks"), f.get("fk_angles"), f["move"], source)


def tick_bounds(rules) -> list[WheelBound]:
    """The jump rule of each wheel in ticks (:meth:`omnikin.odometry.plausibility.CounterRule.limit`)."""
    if rules and rules[0].max_jump is not None:
        return [WheelBound(0.0, r.max_jump, r.half_limit) for r in rules]
    return [WheelBound(r.rate, QUANTISATION_SLACK, r.half_limit) for r in rules]


def angle_bounds(rules) -> list[WheelBound]:
    """The jump rule of each wheel in radians (:meth:`omnikin.odometry.plausibility.CounterRule.angle_limit`)."""
    if rules and rules[0].max_jump is not None:
        return [WheelBound(0.0, r.max_jump * abs(r.rad_per_tick)) for r in rules]
    return [WheelBound(r.speed, QUANTISATION_SLACK * abs(r.rad_per_tick)) for r in rules]


def change_bounds(rules, unit: str) -> list[ChangeBound]:
    """The change-of-speed rule of each wheel in ``unit`` (ticks or rad;
    :meth:`omnikin.odometry.plausibility.CounterRule.change_bounds`)."""
    out = []
    for r in rules:
        a, slack = r.change_bounds(unit)
        out.append(ChangeBound(a * 0.5, slack))
    return out
