"""Figure of one simulated run: the true path and the odometry [m]."""

from __future__ import annotations

from . import new_figure


def run_figure(run, title: str = ""):
    """True path (solid) and odometry (dashed) of the first trial of a
    :class:`~omnikin.simulation.kinematic.SimulatedRun` whose ground truth was kept [m]."""
    fig = new_figure(figsize=(5.6, 5.6))
    ax = fig.add_subplot(1, 1, 1)
    truth = run.truth[0]
    ax.plot(truth[:, 0], truth[:, 1], "-", color="#2ca02c", lw=1.4, label="true path")
    ax.plot(run.odometry[:, 0], run.odometry[:, 1], "--", color="#1f77b4", lw=1.1, label="odometry")
    ax.plot([truth[-1, 0]], [truth[-1, 1]], "o", color="#2ca02c", ms=5, label="true end")
    ax.plot([run.odometry[-1, 0]], [run.odometry[-1, 1]], "s", color="#1f77b4", ms=5, label="odometry end")
    ax.plot([0], [0], "k+", ms=9, mew=1.2, label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3, frameon=False)
    if title:
        ax.set_title(title, fontsize=10)
    return fig
