"""Code generation of the streaming-odometry hot path (used by :class:`omnikin.odometry.Odometry`).

Why generated: a CPython update that loops over wheels or calls NumPy costs
3-10 us; unrolled float arithmetic for the robot's own wheel count costs under
2 us (``docs/performance.md``). Like :func:`collections.namedtuple` and
:mod:`dataclasses`, the source is built from one template and compiled once per
estimator. The template does, per sample (conventions, Odometry):

1. tick increments ``d_j = ticks_j - prev_j`` (wrapped modulo ``2**bits`` when the
   counters wrap);
2. a type check and a single comparison per wheel against its jump limit (a finite
   bound also traps NaN and infinity); anything doubtful goes to the owner's general
   path, which integrates the sample the same way or raises naming sample and wheel;
3. body increment ``(a, b, phi) = F d`` (``F`` = forward kinematics in rad/tick);
4. the pose update of :mod:`omnikin.integration` (``ADVANCE`` below, shared with
   the general path so both integrate identically).
"""

from __future__ import annotations

import math
from math import cos, floor, pi, sin

from .encoders import QUANTISATION_SLACK, jump_limit
from .geometry import SCALAR_TAYLOR_LIMIT, TWO_PI

ADVANCE = {
    "exact": (
        "    x = 0.5 * phi\n"
        "    h = th + x\n"
        "    k = 1.0 - x * x / 6.0 if -SMALL < x < SMALL else sin(x) / x  # as geometry.sinc_scalar\n"),
    "midpoint": "    h = th + 0.5 * phi\n    k = 1.0\n",
    "euler": "    h = th\n    k = 1.0\n",
}
"""Heading ``h`` and chord factor ``k`` of one step, per method (see integration.py)."""

_MOVE = (
    "    c = cos(h)\n"
    "    s = sin(h)\n"
    "    o._x += k * (c * a - s * b)\n"
    "    o._y += k * (s * a + c * b)\n"
    "    th += phi\n"
    "    if th >= PI or th < -PI:\n"
    "        th -= TWO_PI * floor((th + PI) / TWO_PI)  # as geometry.wrap_angle\n"
    "    o._th = th\n"
    "    o._t = t\n"
    "    o.twist = (a / dt, b / dt, phi / dt)\n"
    "    o.samples += 1\n"
    "    return (o._x, o._y, th)\n")


def _namespace() -> dict:
    return {"cos": cos, "sin": sin, "floor": floor, "PI": pi, "TWO_PI": TWO_PI, "SMALL": SCALAR_TAYLOR_LIMIT}


def compile_advance(owner, method: str):
    """``advance(t, dt, a, b, phi)`` moving ``owner``'s pose by one body increment."""
    src = "def advance(t, dt, a, b, phi):\n    o = OWNER\n    th = o._th\n" + ADVANCE[method] + _MOVE
    ns = _namespace()
    ns["OWNER"] = owner
    exec(compile(src, f"<omnikin advance {method}>", "exec"), ns)
    return ns["advance"]


def compile_update(owner, n: int, fk_rows, method: str, bits: int | None, max_jump: float | None, rates,
                   general, not_later, residual):
    """Specialised ``update(t, ticks, steer=None)`` for ``n`` wheels.

    ``fk_rows``: 3 rows of n floats [m or rad per tick]; ``bits``: counter width or None;
    ``max_jump`` [ticks] and ``rates`` (per wheel ticks/s bound or None): the jump rules of
    :func:`omnikin.encoders.jump_limit`; ``general(t, ticks, steer)`` handles every case
    the fast path doubts (and raises where needed), ``not_later(t, dt, ticks, steer)``
    repeated or earlier timestamps, ``residual(deltas, a, b, phi, dt)`` (or None) the
    residual of redundant layouts.
    """
    d = [f"d{j}" for j in range(n)]
    tk = [f"t{j}" for j in range(n)]
    lines = [
        "def update(t, ticks, steer=None):",
        "    o = OWNER",
        "    p = o._ticks",
        "    if p is None or steer is not None:",
        "        return general(t, ticks, steer)",
        "    try:",
        "        dt = t - o._t",
        f"        {', '.join(tk)}, = ticks",
        f"        {', '.join(f'p{j}' for j in range(n))}, = p",
    ]
    if bits is None:
        # Python ints and floats only: numpy scalars could overflow in their own type, bools
        # are no readings; both take the general path
        lines += [f"        if {' or '.join(f'{v}.__class__ not in NUMBER' for v in tk)}:",
                  "            return general(t, ticks, steer)"]
        lines += [f"        d{j} = t{j} - p{j}" for j in range(n)]
    else:
        # wrapping counters: Python ints only (floats and numpy scalars take the general path)
        half = 1 << (bits - 1)
        lines += [f"        if {' or '.join(f'{v}.__class__ is not int' for v in tk)}:",
                  "            return general(t, ticks, steer)"]
        lines += [f"        d{j} = ((t{j} - p{j} + {half}) & {2 * half - 1}) - {half}" for j in range(n)]
    lines += [
        "    except (TypeError, ValueError):",
        "        return general(t, ticks, steer)  # names what is wrong",
        "    if not 0.0 < dt < INF:",
        "        return not_later(t, dt, ticks, steer)",
    ]
    if bits is not None:
        inside = " and ".join(f"{-half} <= t{j} < {2 * half}" for j in range(n))
        lines += [f"    if not ({inside}):", "        return general(t, ticks, steer)"]
    bounds = []
    for j in range(n):
        if rates[j] is not None:
            bounds.append(f"abs(d{j}) <= {rates[j]!r} * dt + {QUANTISATION_SLACK!r}")
            if bits is not None:
                bounds.append(f"abs(d{j}) <= {jump_limit(None, None, 0.0, bits)!r}")
        else:
            limit = jump_limit(max_jump, None, 0.0, bits)
            bounds.append(f"abs(d{j}) <= {limit if math.isfinite(limit) else 1e300!r}")
    lines += [f"    if not ({' and '.join(bounds)}):", "        return general(t, ticks, steer)  # raises, naming it"]
    for name, row in zip(("a", "b", "phi"), fk_rows):
        lines.append(f"    {name} = " + " + ".join(f"{v!r} * d{j}" for j, v in enumerate(row)))
    if residual is not None:
        lines.append(f"    residual([{', '.join(d)}], a, b, phi, dt)")
    lines += [f"    o._ticks = ({', '.join(tk)},)", "    th = o._th"]
    body = "\n".join(lines) + "\n" + ADVANCE[method] + _MOVE
    # compiled inside a factory so that every constant is a fast closure variable
    names = ["OWNER", "general", "not_later", "residual", "INF", "NUMBER", "cos", "sin", "floor", "PI", "TWO_PI",
             "SMALL"]
    src = f"def factory({', '.join(names)}):\n" + "".join(f"    {ln}\n" for ln in body.splitlines()) + \
        "    return update\n"
    ns = {}
    exec(compile(src, f"<omnikin update n={n} {method}>", "exec"), ns)
    consts = _namespace()
    consts.update(OWNER=owner, general=general, not_later=not_later, residual=residual, INF=math.inf,
                  NUMBER=frozenset({int, float}))
    return ns["factory"](*[consts[k] for k in names])
