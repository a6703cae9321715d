"""Numbers written as text: the one grammar of every number omnikin reads from text.

Tables (tick logs, runs and measurement files, trajectories: :mod:`omnikin.io.csvfile`) and
the paths of plans (:func:`omnikin.motion.plans.parse_plan`, whether from a runs file, ``--path`` or
Python) spell a number the same way: an optional sign, ASCII digits with an optional decimal
point, an optional exponent (:data:`PLAIN_NUMBER`), and its value must be finite. Python's
:class:`float` reads much more (``nan``, ``inf``, ``1_000``, Arabic-Indic or full-width
digits, blanks around the number); here those are refused, with the reason.

The other way, numbers written for people in reports and summaries: :func:`mm_text` (metres as
millimetres), :func:`ratio_text` (a ratio) and :func:`reduction_text` (a reduction factor of
E_max,syst, a bound past what the data resolve), shared by every report (``omnikin umbmark``,
``omnikin sweep``).
"""

from __future__ import annotations

import math
import re

from ..errors import InputError
from .messages import shorten

PLAIN_NUMBER = re.compile(r"[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?")
"""A number as the project's tables spell it: optional sign, ASCII digits with an optional
decimal point, optional exponent (``-1.5``, ``.5``, ``2e-3``). Not ``nan``/``inf``, not
Python's other spellings (``0_1``, non-ASCII digits such as ``\\u0661``, ``0x1p3``), which
:class:`float` would read."""

PLAIN_NUMBER_HELP = "plain decimal: sign, ASCII digits, '.', exponent, e.g. -1.5e-3"
"""How :data:`PLAIN_NUMBER` is described in messages."""


def number_problem(text: str) -> str | None:
    """None if ``text`` spells a finite plain number (:data:`PLAIN_NUMBER`), else what is wrong
    with it, in a phrase that quotes it shortened: ``non-finite value 'nan'``, ``not a number:
    '1_0' (plain decimal: ...)``, ``'1e999' is too large (not a finite number)``."""
    if not isinstance(text, str):
        return f"not a number: {shorten(text)} (text expected)"
    if not PLAIN_NUMBER.fullmatch(text):
        if text.strip().lstrip("+-").lower() in ("nan", "inf", "infinity"):
            return f"non-finite value {shorten(text)}"
        return f"not a number: {shorten(text)} ({PLAIN_NUMBER_HELP})"
    if not math.isfinite(float(text)):
        return f"{shorten(text)} is too large (not a finite number)"
    return None


def plain_number(text: str, what: str) -> float:
    """The finite number ``text`` spells (:data:`PLAIN_NUMBER`), or an
    :class:`~omnikin.errors.InputError` ``"{what}: {problem}"`` (:func:`number_problem`)."""
    problem = number_problem(text)
    if problem:
        raise InputError(f"{what}: {problem}")
    return float(text)


def mm_text(x) -> str:
    """Metres as millimetres to 0.01 mm for tables and summaries: ``0.00``, never ``-0.00``;
    ``unbounded`` for None (an open interval end), ``-`` for a non-finite number."""
    if x is None:
        return "unbounded"
    return f"{x * 1000 + 0.0:.2f}".replace("-0.00", "0.00") if math.isfinite(x) else "-"


def ratio_text(x) -> str:
    """A ratio for the text: three significant digits, whole numbers from 100 on; ``unbounded``
    for None (an open interval end)."""
    if x is None:
        return "unbounded"
    return f"{x:.0f}" if x >= 100 else f"{x:.3g}"


RESOLUTION = 1e-5
"""The smallest E_max,syst the reports resolve [m]: 0.01 mm, the step of :func:`mm_text` (a value
below it prints as 0.00 mm, and a ratio over it says nothing the report can show)."""


def round_down(x: float, digits: int = 2) -> float:
    """``x > 0`` rounded down to ``digits`` significant digits (a lower bound stays one)."""
    step = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    return math.floor(x / step * (1 + 1e-12)) * step


def reduction_bounded(after: float, floor: float = 0.0) -> bool:
    """Whether the after-value ``after`` [m] is past what the data resolve: at or below a noise
    ``floor`` [m] (there it cannot be told from a perfect calibration), or below
    :data:`RESOLUTION`. A reduction factor over such a value is only known from below."""
    return (floor > 0 and after <= floor) or after < RESOLUTION


def reduction_text(before: float, after: float, floor: float = 0.0) -> str:
    """The reduction factor ``before / after`` of E_max,syst [m / m] for the text.

    Rule: an ``after`` that the data resolve (:func:`reduction_bounded` false) gives the ratio
    (:func:`ratio_text`); an ``after`` at or below the noise ``floor`` or below
    :data:`RESOLUTION` gives the bound ``at least N``, ``N = before / max(floor, RESOLUTION)``
    rounded down to two significant digits: the after-value may be anything from zero to that
    limit, so the factor is anything from N up (e.g. ``at least 140000``, never ``78781730``).
    ``-`` when ``before`` or ``after`` is not a finite number."""
    if not (math.isfinite(before) and math.isfinite(after)):
        return "-"
    if not reduction_bounded(after, floor):
        return ratio_text(before / after) if after > 0 else "-"
    bound = before / max(floor, RESOLUTION)
    return f"at least {ratio_text(round_down(bound))}" if bound > 0 else "-"
