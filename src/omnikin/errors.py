"""Exception types of omnikin.

The hierarchy is rooted at :class:`Exception`, and each branch also derives from the
built-in exception that says what kind of failure it is, so that callers can catch what
they mean:

- :class:`OmnikinError` (``Exception``): every error omnikin raises on purpose.
- :class:`InputError` (also ``ValueError``): bad input: an argument, a file, a sample. Its
  message names what is wrong and where (file, line, wheel, field, sample index), in one
  line, and never quotes an unbounded value.
- :class:`LinkError` (also ``RuntimeError``): a link to hardware failed while running
  (a wheel controller fell silent, a port closed). Not the caller's fault; retrying may help.

Errors may carry where they happened as attributes (``sample``, ``line``, ``wheel``, ...),
so that an edge (the command line) can add its own context without parsing the message.
"""

from __future__ import annotations


class OmnikinError(Exception):
    """Base class of every error omnikin raises on purpose."""


class InputError(OmnikinError, ValueError):
    """Bad input: the message names what is wrong and where."""


class RobotFileError(InputError):
    """A robot file (or dict) breaks schema version 1 of ``docs/conventions.md``."""


class StudyFileError(InputError):
    """A study file of ``omnikin sweep`` (:mod:`omnikin.sweep.spec`) is bad. The message names
    the file, the line and the field; ``line`` (1-based) and ``field`` (``factors.scale.count``)
    say the same for an edge, None when the problem is not tied to one (an unreadable file)."""

    def __init__(self, message: str, *, line: int | None = None, field: str | None = None):
        super().__init__(message)
        self.line = line
        self.field = field


class SingularLayoutError(InputError):
    """The wheel layout cannot realise or observe the motion its type promises."""


class InfeasibleTwistError(InputError):
    """A commanded twist violates a no-side-slip constraint or a steering limit.

    ``detail``: the message without the library's way out (``on_infeasible='return'``), so
    that an edge can name its own (the command line's ``--allow-infeasible``).
    """

    def __init__(self, message: str, *, detail: str | None = None):
        super().__init__(message)
        self.detail = detail if detail is not None else message


class OdometryInputError(InputError):
    """Encoder samples that cannot be integrated (time order, jumps, NaN, shape).

    ``sample``: index of the offending sample (0-based, counting every sample given), or
    None when the problem is not tied to one sample; ``detail``: the message without the
    sample, so that an edge can name the sample its own way (a file line).
    """

    def __init__(self, message: str, *, sample: int | None = None, detail: str | None = None):
        super().__init__(message)
        self.sample = sample
        self.detail = detail if detail is not None else message


class OutputExistsError(InputError):
    """An output path exists and the user did not ask to replace it, or it is an input."""


class ResourceLimitError(InputError):
    """A job would need more memory or time than allowed; the message names the limit and the
    way to change it. ``needed`` and ``limit`` are in the unit of ``unit`` (``"bytes"``,
    ``"seconds"``, ``"messages"``, ...)."""

    def __init__(self, message: str, *, needed: float | None = None, limit: float | None = None, unit: str = ""):
        super().__init__(message)
        self.needed = needed
        self.limit = limit
        self.unit = unit


class OutputError(OmnikinError, OSError):
    """Writing an output failed (disk full, read-only folder, ...); the message names the path.
    Not an input error: the same command may succeed elsewhere."""


class LinkError(OmnikinError, RuntimeError):
    """A link to hardware failed while running (not an input error)."""


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
