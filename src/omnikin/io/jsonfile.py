"""JSON that omnikin prints and writes: strict JSON (RFC 8259), never ``NaN`` or ``Infinity``.

Python's :mod:`json` writes non-finite floats as ``NaN`` / ``Infinity`` by default, which
no strict JSON reader accepts (``jq``, JavaScript's ``JSON.parse``, Go, Rust's serde). Every
``--json`` output and every JSON file omnikin writes goes through :func:`to_json`:

* a non-finite number is an error naming its field (``rpe.rotation_deg.std``,
  ``wheel_speeds[2]``), a :class:`NonFiniteValueError`;
* except in the fields a caller documents as *nullable* (say, an improvement factor that is
  infinite when the error after calibration is zero): there it is written as ``null``.

NumPy scalars and arrays are written as plain numbers and lists.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping

import numpy as np

from ..errors import NonFiniteValueError


def to_json(data, *, nullable: Iterable[str] = (), indent: int | None = 2) -> str:
    """Strict JSON text of ``data`` (module docstring).

    ``nullable``: field names (the last key, ``improvement``) or paths (``calibration.improvement``)
    whose non-finite values are written as ``null``.
    """
    return json.dumps(_plain(data, "", frozenset(nullable)), indent=indent, allow_nan=False)


def write_json(path, data, *, nullable: Iterable[str] = (), force: bool = False, inputs: Iterable = ()) -> None:
    """Write :func:`to_json` of ``data`` to ``path`` (``-``: standard output) under the output
    policy of :mod:`omnikin.io.output` (an existing file needs ``force``; written atomically)."""
    from .output import check_output, write_text

    text = to_json(data, nullable=nullable) + "\n"
    check_output(path, inputs=inputs, force=force)
    write_text(path, text)


def _plain(value, field: str, nullable: frozenset):
    """``value`` with NumPy types made plain and non-finite floats checked."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v, f"{field}.{k}" if field else str(k), nullable) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{field}[{k}]", nullable) for k, v in enumerate(value)]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        if _nullable(field, nullable):
            return None
        raise NonFiniteValueError(
            f"result field {field or '(top level)'} is {value} and JSON has no NaN or "
            f"Infinity; an input may be out of range",
            field=field,
        )
    return value


def _nullable(field: str, nullable: frozenset) -> bool:
    if not nullable:
        return False
    if field in nullable:
        return True
    last = field.rsplit(".", 1)[-1].split("[", 1)[0]
    return last in nullable
