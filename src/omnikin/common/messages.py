"""Text for messages: the helpers that keep every error and warning omnikin prints one short line.

:func:`one_line` flattens and bounds a text (another library's message, or any error the command
line prints), :func:`shorten` quotes a user's value within a bound, :func:`did_you_mean` names
the choices close to an unknown name, and :func:`digits_apart` picks the digits at which a value
and the bound it breaks print apart. The exception types themselves are in :mod:`omnikin.errors`.
"""

from __future__ import annotations


def one_line(text: object, limit: int = 300) -> str:
    """``text`` as one line of at most ``limit`` characters: runs of white space (newlines
    included) become one space, and a longer text keeps its beginning and its end (where a
    message says what is wrong), with a note of its length in between.

    For messages of other libraries that span several lines (a YAML parser's, a bag
    reader's), quoted inside omnikin's one-line errors, and the last bound of every error the
    command line prints: a message that quotes a long value in full still ends with its reason.
    """
    flat = " ".join(str(text).split())
    if len(flat) <= limit:
        return flat
    note = f" ... ({len(flat)} chars) ... "
    keep = max(limit - len(note), 2)
    head = keep // 2
    return flat[:head] + note + flat[len(flat) - (keep - head) :]


def did_you_mean(word: str, choices) -> str:
    """``"; did you mean 'x'?"`` naming the choices closest to ``word`` (difflib ratio >= 0.6,
    at most three), or ``""`` when none is close. For messages about unknown names: presets,
    sub-commands, options."""
    import difflib

    names = [str(c) for c in choices]
    close = difflib.get_close_matches(str(word), names, n=3, cutoff=0.6)
    if not close:
        return ""
    return "; did you mean " + " or ".join(repr(c) for c in close) + "?"


def shorten(value: object, limit: int = 60) -> str:
    """``repr(value)`` cut to ``limit`` characters, for error messages that quote user input.

    Messages never print an unbounded value: a 10 MB field or a list of a million numbers
    would make the one-line error useless (and slow).
    """
    try:
        text = repr(value)
    except ValueError:  # holds an int beyond Python's digit limit for str(int) (4300 digits)
        return f"<{type(value).__name__} too large to print>"
    if len(text) <= limit:
        return text
    return text[: limit - 15] + f"... ({len(text)} chars)"


def digits_apart(x: float, bound: float, least: int = 6) -> int:
    """The fewest significant digits, at least ``least``, at which ``x`` and ``bound`` print apart
    with ``f"{x:.{p}g}"`` (17, enough for any two doubles, if they are equal).

    A message that prints a value against a bound it breaks formats the value with these digits
    and the bound with these or more: rounding keeps order, so a value above the bound prints
    above it. ``:g`` alone (6 digits) printed 4.9999999999 as 5 against ``[5, 10000]``, and a
    float32 ``1e-4`` (9.9999997e-05 as a double) as 0.0001.
    """
    x, bound = float(x), float(bound)
    for p in range(least, 17):
        if f"{x:.{p}g}" != f"{bound:.{p}g}":
            return p
    return 17
