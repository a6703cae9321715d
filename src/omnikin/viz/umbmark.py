r"""UMBmark figures in the style of Tomasi and Todt ("Three wheeled omnidirectional mobile
robot", Figures 8 and 9) and Borenstein and Feng.

* :func:`return_errors_figure`: return positions ``(eps_x, eps_y)`` [mm] of every run per
  direction, drawn over their centre of gravity (an open ring, so every run stays visible),
  with the noise floor as a circle, before and after calibration (Fig. 9);
* :func:`euclidean_errors_figure`: the Euclidean return error of each run [mm], one marker
  per run, grouped by stage and direction (Fig. 8; runs are independent, so no line joins
  them);
* :func:`trajectories_figure`: true vs odometry paths of every run of each direction [m];
* :func:`monte_carlo_figure`: distribution of ``E_max,syst`` [mm] over repeated procedures.

Every figure takes a ``caption``: one line under the title saying what it shows (engine, random
errors, seed, simulated or measured; :func:`omnikin.api.umbmark` builds it from the report's
settings). A log axis has a labelled tick at every decade of its range, and spans at least two
decades (:func:`label_decades`).

Figures are ``matplotlib.figure.Figure`` objects (no pyplot, no backend switching); write them
with :func:`omnikin.viz.save_figure` (PNG, SVG or PDF). Run markers carry the ``gid``
``"runs:<stage>:<direction>"``, centres of gravity ``"cg:<stage>:<direction>"``; the paths of
:func:`trajectories_figure` ``"truth:<stage>:<direction>:<run>"`` and
``"odometry:<stage>:<direction>:<run>"``.
"""

from __future__ import annotations

import math

import numpy as np

from . import new_figure

COLORS = {"cw": "#d62728", "ccw": "#1f77b4"}
MARKERS = {"cw": "o", "ccw": "s"}
E_MAX = r"$E_{\max,\mathrm{syst}}$"
"""``E_max,syst`` in math text."""


def _titles(fig, title: str, caption: str) -> None:
    """The figure's title, with ``caption`` (what it shows) as a second, smaller line."""
    if title or caption:
        fig.suptitle("\n".join(t for t in (title, caption) if t), fontsize=10 if caption else 11)


def label_decades(axis) -> None:
    """A log ``axis`` (``ax.xaxis`` or ``ax.yaxis``) with a major tick and label at every power of
    ten in its range; a range with fewer than two powers of ten is widened to the decades
    around it (so every label is a decade and at least two are shown)."""
    from matplotlib.ticker import LogFormatterSciNotation, LogLocator

    get, set_ = (
        (axis.axes.get_xlim, axis.axes.set_xlim)
        if axis.axis_name == "x"
        else (
            axis.axes.get_ylim,
            axis.axes.set_ylim,
        )
    )
    lo, hi = sorted(get())
    first, last = math.ceil(math.log10(lo) - 1e-9), math.floor(math.log10(hi) + 1e-9)
    if last - first < 1:
        first, last = math.floor(math.log10(lo) + 1e-9), math.ceil(math.log10(hi) - 1e-9)
        last = max(last, first + 1)
        set_(10.0**first, 10.0**last)
    axis.set_major_locator(LogLocator(base=10.0, numticks=1000))
    axis.set_major_formatter(LogFormatterSciNotation(base=10.0, labelOnlyBase=True))


def _run_style(stage: str, direction: str) -> dict:
    """Marker style of the individual runs of one direction (both figures): drawn above the
    centre-of-gravity rings, tagged ``runs:<stage>:<direction>`` for tests and SVG readers."""
    return {
        "marker": MARKERS[direction],
        "color": COLORS[direction],
        "alpha": 0.85,
        "edgecolor": "white",
        "linewidth": 0.4,
        "zorder": 3,
        "gid": f"runs:{stage}:{direction}",
    }


def return_errors_figure(
    results: dict,
    title: str = "",
    floor: float | None = None,
    floor_label: str = "noise floor (95th percentile)",
    caption: str = "",
):
    """Return positions [mm]; ``results``: ``{stage: UMBmarkResult}``; ``floor``: the noise
    floor [m] (:class:`~omnikin.evaluation.umbmark.NoiseFloor` ``.limit``), drawn as a circle
    labelled ``floor_label``; ``caption``: what the figure shows (module docstring)."""
    from matplotlib.patches import Circle

    fig = new_figure(figsize=(4.4 * len(results) + 0.4, 5.4))
    axes = fig.subplots(1, len(results), squeeze=False)[0]
    for ax, (stage, res) in zip(axes, results.items(), strict=True):
        for d in (res.cw, res.ccw):
            e = d.epsilon[:, :2] * 1000
            cg = d.cg * 1000
            ax.scatter(
                [cg[0]],
                [cg[1]],
                s=240,
                marker="o",
                facecolor="none",
                edgecolor=COLORS[d.direction],
                lw=1.6,
                zorder=2,
                gid=f"cg:{stage}:{d.direction}",
                label=f"{d.direction} centre of gravity",
            )
            ax.scatter(
                e[:, 0],
                e[:, 1],
                s=22,
                **_run_style(stage, d.direction),
                label=f"{d.direction} runs",
            )
        if floor is not None and floor > 0:
            ax.add_patch(
                Circle(
                    (0, 0),
                    floor * 1000,
                    fill=False,
                    ls="--",
                    lw=0.9,
                    color="0.45",
                    zorder=1,
                    gid="noise-floor",
                    label=floor_label,
                )
            )
        ax.scatter([0], [0], s=50, marker="+", color="k", lw=1.0, zorder=4, gid="origin", label="start = goal")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(r"return error $\epsilon_x$ [mm]")
        ax.set_ylabel(r"return error $\epsilon_y$ [mm]")
        ax.set_title(
            f"{stage}: {E_MAX} = {res.e_max_syst * 1000:.1f} mm\n"
            rf"$r_{{cg}}$: cw {res.cw.r_cg * 1000:.1f} mm, ccw {res.ccw.r_cg * 1000:.1f} mm",
            fontsize=10,
        )
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8, frameon=False, markerscale=0.6)
    _titles(fig, title, caption)
    return fig


def euclidean_errors_figure(results: dict, title: str = "", caption: str = ""):
    """Euclidean return error of each run [mm]: one marker per run, grouped by stage and
    direction (log scale when the values span more than a factor 30, every decade labelled);
    ``caption``: what the figure shows (module docstring)."""
    fig = new_figure(figsize=(6.4, 4.4))
    ax = fig.add_subplot(1, 1, 1)
    ticks, names, values = [], [], []
    for k, (stage, res) in enumerate(results.items()):
        for j, d in enumerate((res.cw, res.ccw)):
            err = np.hypot(d.epsilon[:, 0], d.epsilon[:, 1]) * 1000
            x0 = 3 * k + j
            offsets = np.linspace(-0.25, 0.25, len(err)) if len(err) > 1 else np.zeros(1)
            ax.scatter(
                x0 + offsets,
                err,
                s=26,
                **_run_style(stage, d.direction),
                label=f"{d.direction} runs" if k == 0 else None,
            )
            ticks.append(x0)
            names.append(d.direction + "\n" + stage.replace(" ", "\n"))
            values.append(err)
    v = np.concatenate(values)
    positive = v[v > 0]
    log = bool(positive.size and positive.max() / positive.min() > 30)
    if log:
        ax.set_yscale("log")
        ax.set_ylim(positive.min() / 1.5, positive.max() * 1.5)
        label_decades(ax.yaxis)
    else:
        ax.set_ylim(bottom=0)
    ax.set_xticks(ticks, names)
    ax.set_xlim(min(ticks) - 0.7, max(ticks) + 0.7)
    ax.set_ylabel(r"Euclidean return error $\|(\epsilon_x, \epsilon_y)\|$ [mm]")
    ax.set_title("Euclidean return error of each run", fontsize=10)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    _titles(fig, title, caption)
    return fig


def trajectories_figure(runs: dict, side: float, title: str = "", caption: str = ""):
    """True (solid) vs odometry (dashed) path [m] of every run; ``runs``: ``{stage: {"cw": [run,
    ...], "ccw": [...]}}``, each run with ``truth`` and ``odometry`` ``(n, 3)`` [m, m, rad]
    arrays (:class:`~omnikin.evaluation.run_poses.RunPoses`: every run of the first procedure),
    numbered from 1 in list order; the true end of each run is marked. ``side`` [m]: the
    square's side (kept for callers; the view fits the paths). ``caption``: what the figure shows (module docstring)."""
    fig = new_figure(figsize=(4.4 * len(runs) + 0.4, 5.4))
    axes = fig.subplots(1, len(runs), squeeze=False)[0]
    for ax, (stage, by_direction) in zip(axes, runs.items(), strict=True):
        count = 0
        for d, paths in by_direction.items():
            for k, run in enumerate(paths, start=1):
                truth, odometry = np.asarray(run.truth), np.asarray(run.odometry)
                first = k == 1
                ax.plot(
                    truth[:, 0],
                    truth[:, 1],
                    "-",
                    color=COLORS[d],
                    lw=1.0,
                    alpha=0.7,
                    gid=f"truth:{stage}:{d}:{k}",
                    label=f"{d} true paths" if first else None,
                )
                ax.plot(
                    odometry[:, 0],
                    odometry[:, 1],
                    "--",
                    color=COLORS[d],
                    lw=0.8,
                    alpha=0.6,
                    gid=f"odometry:{stage}:{d}:{k}",
                    label=f"{d} odometry" if first else None,
                )
                ax.plot(
                    [truth[-1, 0]],
                    [truth[-1, 1]],
                    MARKERS[d],
                    color=COLORS[d],
                    ms=4,
                    mfc="none",
                    gid=f"end:{stage}:{d}:{k}",
                    label=f"{d} true ends" if first else None,
                )
            count += len(paths)
        ax.plot([0], [0], "k+", ms=9, mew=1.2, label="start")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"{stage}: all {count} runs", fontsize=10)
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    _titles(fig, title, caption)
    return fig


def monte_carlo_figure(values: dict, title: str = "", caption: str = ""):
    """Histograms of ``E_max,syst`` [mm] over procedures (log axis, every decade labelled);
    ``values``: ``{label: array [m]}`` (e.g. before, after calibration, and the noise floor's
    perfectly calibrated robot); ``caption``: what the figure shows (module docstring)."""
    fig = new_figure(figsize=(6.4, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    data = {k: np.asarray(v, dtype=float) * 1000 for k, v in values.items()}
    every = np.concatenate(list(data.values()))
    lo = max(float(every.min()), 1e-3)
    hi = max(float(every.max()), lo * 1.01)
    bins = np.logspace(np.log10(lo), np.log10(hi * 1.01), 40)
    for label, v in data.items():
        ax.hist(
            np.clip(v, lo, None),
            bins=bins,
            weights=np.full(len(v), 1.0 / len(v)),
            histtype="step",
            lw=1.6,
            label=f"{label}: {len(v)} procedures, median {np.median(v):.3g} mm",
        )
    ax.set_xscale("log")
    ax.set_xlim(bins[0], bins[-1])
    label_decades(ax.xaxis)
    ax.set_xlabel(f"{E_MAX} [mm]")
    ax.set_ylabel("fraction of procedures")
    ax.set_title(f"{E_MAX} over repeated UMBmark procedures", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    _titles(fig, title, caption)
    return fig
