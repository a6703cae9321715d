"""Figure of a calibration: the end-position residual of each run, before and after."""

from __future__ import annotations

import numpy as np

from . import new_figure


def residuals_figure(residuals: dict, labels: list, title: str = ""):
    """Measured minus predicted end position [mm] of every run, one marker per run, one panel
    per model (``residuals``: ``{"nominal": (n, 2) [m], "calibrated": (n, 2) [m]}``); runs
    of the same path share a colour."""
    fig = new_figure(figsize=(4.6 * len(residuals), 5.4))
    axes = fig.subplots(1, len(residuals), squeeze=False)[0]
    paths = list(dict.fromkeys(labels))
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    for ax, (model, res) in zip(axes, residuals.items(), strict=True):
        r = np.asarray(res, dtype=float) * 1000
        for k, path in enumerate(paths):
            sel = [i for i, lbl in enumerate(labels) if lbl == path]
            ax.scatter(
                r[sel, 0],
                r[sel, 1],
                s=24,
                color=cmap(k % 10),
                alpha=0.85,
                edgecolor="white",
                linewidth=0.4,
                zorder=3,
                gid=f"runs:{model}:{path}",
                label=path,
            )
        ax.scatter([0], [0], s=50, marker="+", color="k", lw=1.0, zorder=4, label="prediction")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("measured - predicted x [mm]")
        ax.set_ylabel("measured - predicted y [mm]")
        rms = float(np.sqrt(np.mean(np.sum(r**2, axis=1)))) if len(r) else 0.0
        ax.set_title(f"{model} model: RMS {rms:.3g} mm", fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    return fig
