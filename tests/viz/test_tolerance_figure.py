"""The tolerance study's figure: one panel per phase, median and quantile of every series with
their interval bands, the target, the crossings, units on the axes, a bounded number of series;
read from the Figure's artists and from the written PNG."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.collections import FillBetweenPolyCollection  # noqa: E402

from omnikin.sweep.points import Point  # noqa: E402
from omnikin.sweep.summary import summarize  # noqa: E402
from omnikin.viz import save_figure  # noqa: E402
from omnikin.viz.sweep import MAX_SERIES, tolerance_figure  # noqa: E402
from support.sweep_tables import grid, make_study, proportional_table, trial_table  # noqa: E402

SCALES = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)


def gids(ax) -> set[str]:
    return {a.get_gid() for a in ax.get_children() if a.get_gid()}


def noisy_table(points, trials=80, seed=4):
    rng = np.random.default_rng(seed)
    spread = rng.lognormal(0, 0.4, trials)
    return trial_table(
        (p, k, 0.005 * p.scale * b, 0.001 * p.scale * b if p.calibrate else math.nan, None)
        for p in points
        for k, b in enumerate(spread)
    )


def test_two_panels_with_median_quantile_bands_target_and_crossing_per_series(tmp_path):
    points = grid(scales=SCALES) + grid(scales=SCALES, noise="none")
    study = make_study(points, trials=80)
    fig = tolerance_figure(summarize(noisy_table(points), study), study)
    before, after = fig.axes
    assert (before.get_title(), after.get_title()) == ("before calibration", "after calibration")
    for phase, ax in (("before", before), ("after", after)):
        for j in (0, 1):
            for gid in ("median", "quantile", "median-band", "quantile-band", "crossing"):
                assert f"{gid}:{phase}:{j}" in gids(ax)
        assert f"target:{phase}" in gids(ax)
        (target,) = [line for line in ax.lines if line.get_gid() == f"target:{phase}"]
        assert list(target.get_ydata()) == [10.0, 10.0]
        assert ax.get_xlabel() == "scale [-]" and ax.get_xscale() == "log"
        quantile = next(line for line in ax.lines if line.get_gid() == f"quantile:{phase}:0")
        assert quantile.get_linestyle() == "--"
        assert any(isinstance(c, FillBetweenPolyCollection) for c in ax.collections)
    assert "[mm]" in before.get_ylabel()
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "omni3, noise=typical" in legend and "omni3, noise=none" in legend
    save_figure(fig, tmp_path / "tolerance.png", dpi=60)
    assert (tmp_path / "tolerance.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_crossing_marker_sits_at_the_closed_form_threshold():
    points = grid(scales=SCALES)
    study = make_study(points, trials=80)
    fig = tolerance_figure(summarize(proportional_table(points, 0.008, 0.002, 80), study), study)
    before, after = fig.axes
    (mark,) = [line for line in before.lines if line.get_gid() == "crossing:before:0"]
    assert mark.get_xdata()[0] == pytest.approx(0.010 / 0.008)
    (mark,) = [line for line in after.lines if line.get_gid() == "crossing:after:0"]
    assert mark.get_xdata()[0] == pytest.approx(0.010 / 0.002)


def test_one_panel_when_no_point_calibrates_and_units_of_the_hub_axis():
    points = [Point(robot="omni3", robot_hash="0" * 16, hub=h, calibrate=False) for h in (0.0005, 0.001, 0.002)]
    study = make_study(points, trials=80)
    fig = tolerance_figure(summarize(noisy_table(points), study), study)
    (ax,) = fig.axes
    assert ax.get_xlabel() == "hub [mm]" and ax.get_xscale() == "linear"
    line = next(line for line in ax.lines if line.get_gid() == "median:before:0")
    assert list(line.get_xdata()) == pytest.approx([0.5, 1.0, 2.0])


def test_at_most_twelve_series_are_drawn_and_the_title_says_how_many_are_left_out():
    points = [p for rate in range(50, 50 + 15) for p in grid(scales=SCALES, rate=float(rate))]
    study = make_study(points, trials=3)
    fig = tolerance_figure(summarize(noisy_table(points, trials=3), study), study)
    drawn = {g.split(":")[2] for g in gids(fig.axes[0]) if g.startswith("median:")}
    assert len(drawn) == MAX_SERIES
    assert f"{MAX_SERIES} of 15 series drawn, 3 left out" in fig.get_suptitle()


def test_random_design_is_drawn_as_points_not_lines():
    rng = np.random.default_rng(2)
    points = [Point(robot="omni3", robot_hash="0" * 16, scale=s) for s in rng.uniform(0.2, 5.0, 12)]
    study = make_study(points, design="random", trials=10)
    fig = tolerance_figure(summarize(noisy_table(points, trials=10), study), study)
    median = next(line for line in fig.axes[0].lines if line.get_gid() == "median:before:0")
    assert median.get_linestyle() == "None" and median.get_marker() == "o"
    assert "random design" in fig.get_suptitle()


def test_every_log_axis_has_labelled_ticks_even_over_many_decades():
    # after calibration 0.001 mm, before 10 m: nine decades on the shared y axis
    points = grid(scales=SCALES)
    study = make_study(points, trials=5)
    table = trial_table((p, k, 10.0 * p.scale, 1e-6 * p.scale, None) for p in points for k in range(5))
    fig = tolerance_figure(summarize(table, study), study)
    FigureCanvasAgg(fig).draw()
    assert [ax.get_yscale() for ax in fig.axes] == ["log", "log"]
    ax = fig.axes[0]  # the shared y axis is labelled on the first panel
    low, high = ax.get_ylim()
    shown = [t for t in ax.yaxis.get_majorticklabels() if t.get_text() and low <= t.get_position()[1] <= high]
    assert len(shown) >= 3
