"""Numbers written as text: the one grammar of every number omnikin reads from text.

Tables (tick logs, runs and measurement files, trajectories: :mod:`omnikin.io.csvfile`) and
the paths of plans (:func:`omnikin.plans.parse_plan`, whether from a runs file, ``--path`` or
Python) spell a number the same way: an optional sign, ASCII digits with an optional decimal
point, an optional exponent (:data:`PLAIN_NUMBER`), and its value must be finite. Python's
:class:`float` reads much more (``nan``, ``inf``, ``1_000``, Arabic-Indic or full-width
digits, blanks around the number); here those are refused, with the reason.

The other way, numbers written for people in reports and summaries: :func:`mm_text` (metres as
millimetres) and :func:`ratio_text` (a ratio such as a reduction factor), shared by every
report (``omnikin umbmark``, ``omnikin sweep``).
"""

from __future__ import annotations

import math
import re

from .errors import InputError, shorten

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
