"""Reading the project's tables: CSV (tick logs, measurement files, CSV trajectories) and
whitespace-separated numbers (TUM and KITTI trajectories).

Rules shared by every table the project reads:

* UTF-8 (a byte-order mark is fine); lines that are blank or start with ``#`` are skipped;
* a field is never empty: an empty field (``1,,3``, a trailing comma) is an error naming the
  file, the line and the column, never dropped, so no value can slide into the next column;
* every problem raises the caller's error class with the file, the line and the column named.

CSV (:func:`read_rows`): one header line, comma separated, as read by the :mod:`csv` module.
Whitespace tables (:func:`iter_fields`): fields separated by runs of blanks or by one comma
with optional blanks around it (``1 2 3``, ``1, 2, 3``); two commas in a row leave an empty
field.
"""

from __future__ import annotations

import csv
import re
from collections import Counter
from collections.abc import Iterator

from ..common.messages import shorten
from ..common.number_text import number_problem
from .textfile import read_lines

_SEPARATOR = re.compile(r"\s*,\s*|\s+")


def _skipped(text: str) -> bool:
    """Blank lines and comments (``#`` first) carry no data."""
    stripped = text.strip()
    return not stripped or stripped.startswith("#")


def _refuse_empty(fields: list[str], names: list[str] | None, source: str, line: int, error: type[Exception]) -> None:
    """Raise ``error`` at the first empty field; ``names`` the header (None: this is the header)."""
    for k, value in enumerate(fields):
        if not value:
            if names is None:
                raise error(f"{source}: line {line}, field {k + 1}: empty column name")
            column = f"column {shorten(names[k], 40)} (field {k + 1})" if k < len(names) else f"field {k + 1}"
            raise error(f"{source}: line {line}, {column}: empty field (every field needs a value)")


def read_rows(path, error: type[Exception]) -> list[tuple[int, list[str]]]:
    """``[(line_number, fields), ...]`` of the CSV lines that are not blank or comments, the
    header first; fields are stripped of blanks and never empty (module docstring)."""
    return list(iter_rows(path, error))


def iter_rows(path, error: type[Exception]) -> Iterator[tuple[int, list[str]]]:
    """:func:`read_rows` one row at a time, for files too long to hold as text."""
    source = str(path)
    reader = csv.reader(text for _, text in read_lines(path, error, what="a CSV file"))
    header: list[str] | None = None
    try:
        for r in reader:
            if not r or (len(r) == 1 and not r[0].strip()) or r[0].lstrip().startswith("#"):
                continue
            fields = [c.strip() for c in r]
            _refuse_empty(fields, header, source, reader.line_num, error)
            if header is None:
                header = fields
            yield reader.line_num, fields
    except csv.Error as exc:
        raise error(f"{source}: line {reader.line_num}: malformed CSV: {exc}") from None


def iter_fields(path, error: type[Exception], names: list[str] | None = None) -> Iterator[tuple[int, list[str]]]:
    """``(line_number, fields)`` of each line of a whitespace table that is not blank or a
    comment (module docstring); ``names`` name the columns in messages."""
    source = str(path)
    for line, text in read_lines(path, error, what="a text table"):
        if _skipped(text):
            continue
        fields = _SEPARATOR.split(text.strip())
        _refuse_empty(fields, names or [], source, line, error)
        yield line, fields


def column_problems(header: list[str], required, optional=()) -> list[str]:
    """Descriptions of missing, unknown and duplicate columns (empty if none); linear in the
    number of columns."""
    counts = Counter(header)
    required = list(required)
    allowed = set(required) | set(optional)
    dup = sorted(h for h, n in counts.items() if n > 1)
    missing = [c for c in required if c not in counts]
    unknown = [c for c in header if c not in allowed]
    return (
        ([f"missing column(s) {_names(missing)}"] if missing else [])
        + ([f"unknown column(s) {_names(unknown)}"] if unknown else [])
        + ([f"duplicate column(s) {_names(dup)}"] if dup else [])
    )


def _names(names: list[str], limit: int = 8) -> str:
    """A bounded list of column names for a message."""
    shown = ", ".join(shorten(n, 40) for n in names[:limit])
    return f"[{shown}{f', ... ({len(names)} in all)' if len(names) > limit else ''}]"


def number(text: str, source: str, line: int, column: str | int, error: type[Exception]) -> float:
    """The finite number ``text`` spells (:data:`omnikin.common.number_text.PLAIN_NUMBER`), or
    ``error`` naming file, line and column (a name, or a 1-based field number) and what is wrong
    (:func:`omnikin.common.number_text.number_problem`). Every number field of every table goes through
    here: tick-log times, runs and measurements, trajectories."""
    where = f"field {column}" if isinstance(column, int) else f"column {shorten(column, 40)}"
    if not text:
        raise error(f"{source}: line {line}, {where}: empty field (every field needs a value)")
    problem = number_problem(text)
    if problem:
        raise error(f"{source}: line {line}, {where}: {problem}")
    return float(text)
