"""Figure of one tracked path (:class:`omnikin.api.tracking.Tracking`): where the robot went
against the path [m], its distance to the path over time [mm], and the wheel speeds it was
commanded against their limit [rad/s]."""

from __future__ import annotations

from . import new_figure

TRUTH, ODOMETRY, REFERENCE, PATH = "#2ca02c", "#1f77b4", "#ff7f0e", "#7f7f7f"


def tracking_figure(tracking):
    """Three panels: the path (grey), the truth (green) and the odometry (blue, dashed) in the
    plane [m]; the truth's distance to the path over time [mm] with its RMS; the commanded wheel
    speeds over time against the limit (dotted) [rad/s]."""
    from ..evaluation.tracking import distance_to_path

    run, path = tracking.run, tracking.path
    summary = tracking.summary()
    fig = new_figure(figsize=(11.0, 5.2))
    grid = fig.add_gridspec(2, 2, width_ratios=(1.1, 1.0))
    plane = fig.add_subplot(grid[:, 0])
    plane.plot(path.pose[:, 0], path.pose[:, 1], "-", color=PATH, lw=4.0, alpha=0.35, label="path")
    plane.plot(run.truth[:, 0], run.truth[:, 1], "-", color=TRUTH, lw=1.3, label="truth")
    plane.plot(run.odometry[:, 0], run.odometry[:, 1], "--", color=ODOMETRY, lw=1.0, label="odometry")
    plane.plot([path.pose[0, 0]], [path.pose[0, 1]], "k+", ms=9, mew=1.2, label="start")
    plane.set_aspect("equal", adjustable="datalim")
    plane.set_xlabel("x [m]")
    plane.set_ylabel("y [m]")
    plane.grid(True, alpha=0.3)
    plane.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=4, frameon=False)
    plane.set_title(
        f"{tracking.robot.name}: {path.name} ({tracking.controller}, {tracking.engine} engine)", fontsize=10
    )

    error = fig.add_subplot(grid[0, 1])
    distance, _ = distance_to_path(run.truth, path.pose)
    error.plot(run.t, distance * 1e3, color=TRUTH, lw=1.0)
    error.axvline(tracking.trajectory.duration, color="k", lw=0.8, ls=":", label="reference ends")
    error.set_ylabel("distance to path [mm]")
    error.set_title(
        f"RMS {summary['rms_error_m'] * 1e3:.3g} mm, largest {summary['max_error_m'] * 1e3:.3g} mm", fontsize=9
    )
    error.grid(True, alpha=0.3)
    error.legend(fontsize=8, frameon=False)

    wheels = fig.add_subplot(grid[1, 1], sharex=error)
    names = [w.name for w in tracking.robot.rolling]
    for k, name in enumerate(names):
        wheels.plot(run.t, run.wheel_speeds[:, k], lw=0.9, label=name)
    limit = tracking.trajectory.limits.speed
    for sign in (1.0, -1.0):
        wheels.axhline(sign * limit, color="k", lw=0.8, ls=":")
    wheels.set_xlabel("t [s]")
    wheels.set_ylabel("wheel speed [rad/s]")
    wheels.set_ylim(-1.15 * limit, 1.15 * limit)
    wheels.grid(True, alpha=0.3)
    wheels.legend(fontsize=7, frameon=False, loc="center left", bbox_to_anchor=(1.0, 0.5))
    saturated = summary["saturated_samples"]
    excess = f" (asked at most {summary['largest_excess_percent']:.2g} % beyond)" if saturated else ""
    fig.suptitle(
        f"{summary['duration_s']:.4g} s at up to {limit:g} rad/s; {saturated} of {summary['samples']} commands "
        f"saturated{excess}",
        fontsize=9,
    )
    return fig
