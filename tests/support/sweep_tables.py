"""Studies and trial tables built by hand for the sweep tests (no Dask, no files)."""

from __future__ import annotations

import math

import numpy as np

from omnikin.sweep.points import Point, point_key
from omnikin.sweep.study import TRIAL_COLUMNS, Study


def make_study(points, design="grid", trials=10, **question) -> Study:
    return Study(
        source="test.yaml",
        name="test",
        seed=1,
        trials=trials,
        design=design,
        points=tuple(points),
        robots={},
        **question,
    )


def grid(robot="omni3", scales=(0.5, 1.0, 2.0, 4.0), **fixed) -> list[Point]:
    return [Point(robot=robot, robot_hash="0123456789abcdef", scale=s, **fixed) for s in scales]


def trial_table(rows) -> dict[str, np.ndarray]:
    """The trial table of ``rows``: ``(point, trial, before [m], after [m], error)`` tuples."""
    columns: dict[str, list] = {name: [] for name, _ in TRIAL_COLUMNS}
    for point, k, before, after, error in rows:
        columns["point"].append(point_key(point))
        for name, value in point.as_dict().items():
            columns[name].append(value)
        columns["trial"].append(k)
        nan = error is not None
        columns["e_max_syst_before"].append(math.nan if nan else before)
        columns["e_max_syst_after"].append(math.nan if nan else after)
        columns["systematic_before"].append(math.nan)
        columns["systematic_after"].append(math.nan)
        columns["reduction"].append(before / after if not nan and after > 0 else math.nan)
        columns["error"].append(error)
        columns["seconds"].append(0.1)
    out = {}
    for name, kind in TRIAL_COLUMNS:
        values = columns[name]
        if kind == "string" or any(v is None for v in values):
            out[name] = np.array(values, dtype=object)
        else:
            out[name] = np.array(values, dtype={"float64": float, "int64": np.int64, "bool": bool}[kind])
    return out


def proportional_table(points, c_before, c_after, trials):
    """Every trial of a point measures exactly ``c * scale`` [m] (no noise), before and after."""
    return trial_table(
        (p, k, c_before * p.scale, c_after * p.scale if p.calibrate else math.nan, None)
        for p in points
        for k in range(trials)
    )
