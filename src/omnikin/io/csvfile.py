"""CSV reading shared by the tick logs and the measurement files.

One header line, comma separated, UTF-8 (a byte-order mark is fine); blank lines and lines
starting with ``#`` are skipped. Every problem raises the caller's error class with the file,
the line and the column named.
"""

from __future__ import annotations

import csv
import math


def read_rows(path, error: type[Exception]) -> list[tuple[int, list[str]]]:
    """``[(line_number, fields), ...]`` of the non-blank, non-comment lines (header first)."""
    source = str(path)
    try:
        handle = open(path, newline="", encoding="utf-8-sig")
    except OSError as exc:
        raise error(f"{source}: cannot open: {exc.strerror}") from None
    with handle:
        try:
            return [(i + 1, [c.strip() for c in r]) for i, r in enumerate(csv.reader(handle))
                    if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
        except UnicodeDecodeError as exc:
            raise error(f"{source}: not a UTF-8 text file (byte {exc.start}: {exc.reason})") from None
        except csv.Error as exc:
            raise error(f"{source}: malformed CSV: {exc}") from None


def column_problems(header: list[str], required, optional=()) -> list[str]:
    """Descriptions of missing, unknown and duplicate columns (empty if none)."""
    dup = sorted({h for h in header if header.count(h) > 1})
    missing = [c for c in required if c not in header]
    unknown = [c for c in header if c not in required and c not in optional]
    return ([f"missing column(s) {missing}"] if missing else []) + \
        ([f"unknown column(s) {unknown}"] if unknown else []) + \
        ([f"duplicate column(s) {dup}"] if dup else [])


def number(text: str, source: str, line: int, column: str | int, error: type[Exception]) -> float:
    """A finite float, or ``error`` naming file, line and column (a name, or a 1-based field number)."""
    where = f"field {column}" if isinstance(column, int) else f"column {column!r}"
    try:
        value = float(text)
    except ValueError:
        raise error(f"{source}: line {line}, {where}: not a number: {text!r}") from None
    if not math.isfinite(value):
        raise error(f"{source}: line {line}, {where}: non-finite value {text!r}")
    return value
