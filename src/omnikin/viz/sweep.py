r"""The figure of a tolerance study (``omnikin sweep``): ``E_max,syst`` against a build tolerance.

:func:`tolerance_figure` draws a study's summary (one row per point,
:data:`omnikin.sweep.summary.SUMMARY_COLUMNS`): one panel per phase (before and after
calibration; one panel "without calibration" when no point calibrates), the tolerance factor of the study's axis
on x, ``E_max,syst`` [mm] on y, one colour per series (a robot with one setting of the other
factors, the summary's ``series`` column). Each series shows its median (solid) and its
``study.quantile`` quantile (dashed), each with its confidence interval as a band (absent where
the trials are too few to bound it), the target as a horizontal line and the crossing of the
quantile with it as a marker (:func:`omnikin.evaluation.threshold.threshold`). A random design
is drawn as points with interval bars, not lines. At most :data:`MAX_SERIES` series are drawn;
the title says how many are left out.

Artists carry ``gid`` s for tests and SVG readers: ``median:<phase>:<series>``,
``quantile:<phase>:<series>``, ``median-band:...``, ``quantile-band:...``,
``crossing:<phase>:<series>`` (series numbered from 0 in the summary's order) and
``target:<phase>``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..evaluation.threshold import CROSSES, threshold
from . import new_figure
from .umbmark import E_MAX

AXIS_UNITS = {
    "scale": ("scale [-]", 1.0),
    "radius": ("radius [%]", 100.0),
    "hub": ("hub [mm]", 1000.0),
    "drive_deg": ("drive [deg]", 1.0),
}
"""Per tolerance factor: its axis label and the factor from its own unit (scale [-], radius
[relative], hub [m], drive_deg [deg]) to the unit shown."""

MAX_SERIES = 12
"""The most series one figure draws (colours stay distinguishable, the legend readable)."""

PHASE_TITLES = {"before": "before calibration", "after": "after calibration"}


def _series_rows(summary: Mapping[str, np.ndarray], axis: str) -> list[tuple[str, np.ndarray]]:
    """``(label, rows sorted by the axis)`` per series, in the order of their first row."""
    labels = [str(s) for s in summary["series"]]
    order: dict[str, list[int]] = {}
    for i, label in enumerate(labels):
        order.setdefault(label, []).append(i)
    x = np.asarray(summary[axis], dtype=float)
    return [(label, np.array(sorted(rows, key=lambda i: x[i]), dtype=int)) for label, rows in order.items()]


def _spans_decade(values: np.ndarray) -> bool:
    v = values[np.isfinite(values)]
    return bool(len(v) and np.all(v > 0) and v.max() / v.min() > 10)


def _log_axis(axis, set_scale, values: np.ndarray, ticks: bool) -> None:
    """A log scale; over at most 3 decades with plain numbers at 1, 2 and 5 per decade (``0.5``,
    ``10``), wider with matplotlib's powers of ten. ``ticks`` puts the major ticks at the (at most
    6: more labels would run into each other) distinct ``values`` of a grid, to 3 digits."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    set_scale("log")
    positive = np.unique(values[np.isfinite(values) & (values > 0)])
    if ticks and len(positive) <= 6:
        axis.set_ticks(positive)
    elif len(positive) and positive[-1] / positive[0] <= 1e3:
        axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    else:
        return
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.0f}" if v >= 100 else f"{v:.3g}"))  # 1000, not 1e+03
    axis.set_minor_formatter(NullFormatter())


def tolerance_figure(summary: Mapping[str, np.ndarray], study):
    """``E_max,syst`` [mm] against the study's axis factor (module docstring); ``study``: the
    :class:`~omnikin.sweep.study.Study` the summary belongs to (its ``axis``, ``target`` [m],
    ``quantile``, ``level`` and ``design``)."""
    axis = study.axis
    label, unit = AXIS_UNITS[axis]
    calibrates = bool(np.any(np.asarray(summary["calibrate"], dtype=bool)))
    phases = ("before", "after") if calibrates else ("before",)
    series = _series_rows(summary, axis)
    drawn = series[:MAX_SERIES]
    random = study.design == "random"
    x_all = np.asarray(summary[axis], dtype=float) * unit
    q_name = f"{study.quantile * 100:g}th percentile"
    level = f"{study.level * 100:g} %"
    fig = new_figure(figsize=(5.2 * len(phases) + 0.6, 5.4))
    panels = fig.subplots(1, len(phases), squeeze=False, sharey=True)[0]
    colours = [f"C{j % 10}" if j < 10 else ("#444444", "#8c564b")[j % 2] for j in range(len(drawn))]
    plotted = [study.target * 1000]
    for ax, phase in zip(panels, phases, strict=True):
        for j, (name, rows) in enumerate(drawn):
            x = x_all[rows]
            colour = colours[j]
            for stat, style in (("median", "-"), ("quantile", "--")):
                y = np.asarray(summary[f"{stat}_{phase}"], dtype=float)[rows] * 1000
                low = np.asarray(summary[f"{stat}_{phase}_low"], dtype=float)[rows] * 1000
                high = np.asarray(summary[f"{stat}_{phase}_high"], dtype=float)[rows] * 1000
                plotted += [*y, *low, *high]
                line_label = name if (stat == "median" and ax is panels[0]) else None
                if random:
                    below = np.where(y - low < 0, 0, y - low)
                    above = np.where(high - y < 0, 0, high - y)
                    bars = ax.errorbar(
                        x,
                        y,
                        yerr=np.vstack([below, above]),
                        fmt="o" if stat == "median" else "^",
                        ms=4,
                        color=colour,
                        elinewidth=0.8,
                        capsize=2,
                        alpha=0.85,
                        label=line_label,
                    )
                    bars.lines[0].set_gid(f"{stat}:{phase}:{j}")
                else:
                    ax.plot(x, y, style, color=colour, lw=1.5, marker=".", gid=f"{stat}:{phase}:{j}", label=line_label)
                    ax.fill_between(x, low, high, color=colour, alpha=0.15, lw=0, gid=f"{stat}-band:{phase}:{j}")
            q = np.asarray(summary[f"quantile_{phase}"], dtype=float)[rows]
            crossing = threshold(x, q, study.target)
            if crossing.status == CROSSES and crossing.value is not None:
                ax.plot(
                    [crossing.value],
                    [study.target * 1000],
                    "D",
                    ms=7,
                    mfc="white",
                    mec=colour,
                    mew=1.6,
                    zorder=4,
                    gid=f"crossing:{phase}:{j}",
                )
        ax.axhline(study.target * 1000, color="k", lw=1.0, ls=":", gid=f"target:{phase}")
        ax.set_title(PHASE_TITLES[phase] if calibrates else "without calibration", fontsize=10)
        ax.set_xlabel(label)
        if _spans_decade(x_all):
            _log_axis(ax.xaxis, ax.set_xscale, x_all, ticks=not random)
        ax.grid(True, which="both", alpha=0.3)
    panels[0].set_ylabel(f"{E_MAX} [mm]")
    if _spans_decade(np.asarray(plotted, dtype=float)):
        _log_axis(panels[0].yaxis, panels[0].set_yscale, np.asarray(plotted, dtype=float), ticks=False)
    _legend(fig, panels[0], q_name, level, random)
    left_out = len(series) - len(drawn)
    title = (
        f"{study.name}: {q_name} of {E_MAX} below {study.target * 1000:g} mm?"
        + (" (approximate: random design)" if random else "")
        + (
            f"\n{len(drawn)} of {len(series)} series drawn, {left_out} left out (see the report's tables)"
            if left_out
            else ""
        )
    )
    fig.suptitle(title, fontsize=11)
    return fig


def _legend(fig, ax, q_name: str, level: str, random: bool) -> None:
    """One legend below the panels: the series' colours, then what the line styles mean."""
    from matplotlib.artist import Artist
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles, labels = ax.get_legend_handles_labels()
    keys: list[Artist]
    if random:
        keys = [
            Line2D([], [], marker="o", ls="", color="0.3", label=f"median, {level} interval"),
            Line2D([], [], marker="^", ls="", color="0.3", label=f"{q_name}, {level} interval"),
        ]
    else:
        keys = [
            Line2D([], [], ls="-", color="0.3", label="median"),
            Line2D([], [], ls="--", color="0.3", label=q_name),
            Patch(color="0.3", alpha=0.15, label=f"{level} interval (absent where the trials cannot bound it)"),
        ]
    keys += [
        Line2D([], [], ls=":", color="k", label="target"),
        Line2D([], [], marker="D", ls="", mfc="white", mec="0.3", label=f"{q_name} reaches the target"),
    ]
    fig.legend(
        handles + keys,
        labels + [k.get_label() for k in keys],
        loc="outside lower center",
        ncol=3,
        fontsize=8,
        frameon=False,
    )
