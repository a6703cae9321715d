"""UMBmark figures in the style of the seed paper (Tomasi and Todt, Figures 8 and 9).

* :func:`return_errors_figure`: return positions ``(eps_x, eps_y)`` of every run per
  direction with their centres of gravity, before and after calibration (Fig. 9);
* :func:`euclidean_errors_figure`: the Euclidean return error of each run (Fig. 8);
* :func:`trajectories_figure`: true vs odometry paths of the first run of each direction;
* :func:`monte_carlo_figure`: distribution of ``E_max,syst`` over repeated procedures.

Figures are ``matplotlib.figure.Figure`` objects (no pyplot, no backend switching).
"""

from __future__ import annotations

import numpy as np

from . import require_matplotlib

COLORS = {"cw": "#d62728", "ccw": "#1f77b4"}


def _figure(*args, **kwargs):
    require_matplotlib()
    from matplotlib.figure import Figure

    return Figure(*args, **kwargs)


def _finish(fig, title: str):
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def _style_axes(ax, xlabel: str, ylabel: str, title: str, equal: bool = False) -> None:
    """Labels, title, grid and legend shared by the figures."""
    if equal:
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")


def return_errors_figure(results: dict, title: str = ""):
    """Scatter of return errors [mm]; ``results``: ``{"before": UMBmarkResult, "after": ...}``."""
    fig = _figure(figsize=(5.2 * len(results), 5.0), dpi=100)
    for k, (label, res) in enumerate(results.items()):
        ax = fig.add_subplot(1, len(results), k + 1)
        for d in (res.cw, res.ccw):
            e = d.epsilon[:, :2] * 1000
            ax.scatter(e[:, 0], e[:, 1], s=28, color=COLORS[d.direction], alpha=0.75, label=f"{d.direction} runs")
            cg = d.cg * 1000
            ax.scatter([cg[0]], [cg[1]], s=160, marker="X", color=COLORS[d.direction], edgecolor="k",
                       label=f"{d.direction} c.g., r = {d.r_cg * 1000:.1f} mm")
        ax.axhline(0, color="0.6", lw=0.8)
        ax.axvline(0, color="0.6", lw=0.8)
        _style_axes(ax, "return error x [mm]", "return error y [mm]",
                    f"{label}: E_max,syst = {res.e_max_syst * 1000:.1f} mm", equal=True)
    return _finish(fig, title)


def euclidean_errors_figure(results: dict, title: str = ""):
    """Euclidean return error of each run [mm], per direction, before and after."""
    fig = _figure(figsize=(7.5, 4.2), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    styles = {0: "-o", 1: "--s", 2: ":^"}
    for k, (label, res) in enumerate(results.items()):
        for d in (res.cw, res.ccw):
            err = np.hypot(d.epsilon[:, 0], d.epsilon[:, 1]) * 1000
            ax.plot(np.arange(1, len(err) + 1), err, styles.get(k, "-o"), color=COLORS[d.direction],
                    label=f"{label} {d.direction}")
    ax.set_yscale("log")
    n = max(len(r.cw.epsilon) for r in results.values())
    ax.set_xticks(np.arange(1, n + 1))
    ax.set_xlabel("run")
    ax.set_ylabel("Euclidean return error [mm] (log scale)")
    ax.set_title(title or "Euclidean return error per run", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    return fig


def trajectories_figure(runs: dict, side: float, title: str = ""):
    """True (solid) vs odometry (dashed) paths; ``runs``: ``{label: {"cw": SimulatedRun, "ccw": ...}}``."""
    fig = _figure(figsize=(5.2 * len(runs), 5.2), dpi=100)
    for k, (label, sims) in enumerate(runs.items()):
        ax = fig.add_subplot(1, len(runs), k + 1)
        for d, sim in sims.items():
            truth = sim.truth[0]
            ax.plot(truth[:, 0], truth[:, 1], "-", color=COLORS[d], lw=1.4, label=f"{d} true")
            ax.plot(sim.odometry[:, 0], sim.odometry[:, 1], "--", color=COLORS[d], lw=1.0, alpha=0.7,
                    label=f"{d} odometry")
            ax.plot([truth[-1, 0]], [truth[-1, 1]], "o", color=COLORS[d])
        ax.plot([0], [0], "k*", ms=10, label="start")
        _style_axes(ax, "x [m]", "y [m]", f"{label}: first run of each direction ({side:g} m square)", equal=True)
    return _finish(fig, title)


def monte_carlo_figure(values: dict, title: str = ""):
    """Histograms of ``E_max,syst`` [mm] over procedures; ``values``: ``{label: array [m]}``."""
    fig = _figure(figsize=(7.5, 4.2), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    data = {k: np.asarray(v) * 1000 for k, v in values.items()}
    lo = max(min(float(v.min()) for v in data.values()), 1e-3)
    hi = max(float(v.max()) for v in data.values())
    bins = np.logspace(np.log10(lo), np.log10(hi * 1.01), 40)
    for label, v in data.items():
        ax.hist(v, bins=bins, alpha=0.6, label=f"{label} (median {np.median(v):.1f} mm)")
    ax.set_xscale("log")
    ax.set_xlabel("E_max,syst [mm]")
    ax.set_ylabel("procedures")
    ax.set_title(title or "E_max,syst over repeated UMBmark procedures", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig
