"""``report.md`` of ``omnikin sweep``: the study's question, its answer, the figures, the
statistics per point, the failures and how it was computed.

Built from the study (:class:`~omnikin.sweep.study.Study`), its summary
(:func:`~omnikin.sweep.summary.summarize`) and answers (:func:`~omnikin.sweep.summary.answers`);
every table is bounded (:data:`MAX_ROWS`) and says how many rows it leaves out, and every text
that comes from a user's file (robot names, errors) is cut to one line (:func:`cell`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..evaluation.order_statistics import values_for_bound
from ..evaluation.threshold import ABOVE, ABOVE_FIRST, Crossing
from ..number_text import mm_text, ratio_text
from ..viz.sweep import AXIS_UNITS
from .study import Study
from .summary import Answer, axis_text, crossing_text, stat_column, tolerances_text

MAX_ROWS = 200
"""The most rows of the per-point table and of the list of failures."""

MAX_CELL = 120
"""The most characters of one table cell or failure line taken from a user's input."""


def cell(text: object, limit: int = MAX_CELL) -> str:
    """``text`` as one Markdown table cell: one line, ``|`` escaped, at most ``limit`` characters."""
    line = " ".join(str(text).split())
    if len(line) > limit:
        line = line[: limit - 15] + f"... ({len(line)} chars)"
    return line.replace("|", "\\|")


def _status_text(answer: Answer, crossing: Crossing, need: int) -> str:
    """The status of a crossing; above the target: where and how far (an unbounded interval end
    says how many trials per point would bound it)."""
    text = crossing.status
    if crossing.status in (ABOVE, ABOVE_FIRST) and math.isfinite(crossing.first[0]):
        q = crossing.first[1]
        shown = f"unbounded, needs {need} trials per point" if math.isinf(q) else f"{mm_text(q)} mm"
        text += f" (at {axis_text(answer.axis, crossing.first[0])}: {shown})"
    elif crossing.status not in (ABOVE, ABOVE_FIRST):
        text += f", {crossing.interpolation} interpolation" if crossing.interpolation != "none" else ""
    return text + (f"; {crossing.note}" if crossing.note else "")


def _interval_text(value: float, low: float, high: float) -> str:
    """``5.50 (2.00 to 9.00)`` [mm]; an unbounded end as ``unbounded``."""
    if not math.isfinite(value):
        return "-"
    ends = [None if not math.isfinite(v) else v for v in (low, high)]
    return f"{mm_text(value)} ({mm_text(ends[0])} to {mm_text(ends[1])})"


def study_markdown(
    study: Study,
    summary: Mapping[str, np.ndarray],
    answers: Sequence[Answer],
    *,
    figures: list[str],
    failures: list[str],
    note: str = "",
) -> str:
    """The report of ``study`` (module docstring): ``figures`` are paths relative to the report,
    ``failures`` one line per failing point (the point and its error), ``note`` a paragraph set
    under the question (e.g. an interrupted run)."""
    level = f"{study.level * 100:g} %"
    q_name = f"{study.quantile * 100:g}th percentile"
    target = f"{study.target * 1000:g} mm"
    axis_label = AXIS_UNITS[study.axis][0]
    lines = [
        f"# Tolerance study: {cell(study.name)}",
        "",
        f"Which build tolerances keep E_max,syst (UMBmark, Borenstein and Feng) below {target} for "
        f"{study.quantile * 100:g} % of robots (its {q_name} below the target), with and without "
        "calibration? Every trial builds a robot within the tolerances, runs "
        "UMBmark, calibrates it and runs UMBmark again; the tolerances are read along "
        f"{axis_label} with {level} confidence intervals.",
        "",
    ]
    if note:
        lines += [note, ""]
    lines += _answer_lines(study, summary, answers, level, q_name)
    if figures:
        lines += ["## Figures", ""]
        lines += [f"![{cell(f)}]({f})" for f in figures]
        lines.append("")
    lines += _point_lines(study, summary, level, q_name, target)
    if failures:
        lines += [f"## Failures ({len(failures)})", ""]
        lines += [f"- {cell(f, 300)}" for f in failures[:MAX_ROWS]]
        if len(failures) > MAX_ROWS:
            lines.append(f"- ... {len(failures) - MAX_ROWS} more left out (see the trial table's error column)")
        lines.append("")
    lines += _method_lines(study, q_name, level)
    return "\n".join(lines) + "\n"


def _answer_lines(study: Study, summary, answers: Sequence[Answer], level: str, q_name: str) -> list[str]:
    lines = [
        "## Answer",
        "",
        f"The largest {AXIS_UNITS[study.axis][0]} at which the {q_name} of E_max,syst stays below "
        f"{study.target * 1000:g} mm; conservative: the same from the upper end of its {level} interval.",
        "",
        "| series | phase | tolerance found | as radius, hub, drive | status | conservative | status |",
        "|---|---|---|---|---|---|---|",
    ]
    short = []
    need = values_for_bound(study.quantile, study.level)
    for a in answers:
        lines.append(
            "| "
            + " | ".join(
                [
                    cell(a.series.label),
                    "before calibration" if a.phase == "before" else "after calibration",
                    crossing_text(a, a.estimate),
                    tolerances_text(a, a.estimate.value),
                    cell(_status_text(a, a.estimate, need), 300),
                    crossing_text(a, a.conservative),
                    cell(_status_text(a, a.conservative, need), 300),
                ]
            )
            + " |"
        )
        q = np.asarray(summary[stat_column("quantile", a.phase)], dtype=float)[list(a.series.rows)]
        high = np.asarray(summary[stat_column("quantile_high", a.phase)], dtype=float)[list(a.series.rows)]
        if np.any(np.isnan(high) & ~np.isnan(q)):
            short.append(a.series.label)
    lines.append("")
    if not answers:
        lines += ["No series to answer (the study has no points).", ""]
    if short:
        lines += [
            f"Too few trials bound the {q_name} from above at some points of {len(set(short))} series "
            f"(it needs {need} trials per point at {level}): the conservative answer counts them as above "
            "the target.",
            "",
        ]
    if study.design == "random":
        lines += [
            "Random design: each series' points differ in more than the axis (every tolerance factor is "
            "drawn), so its answer, read from the points sorted by the axis, is approximate.",
            "",
        ]
    return lines


def _point_lines(study: Study, summary, level: str, q_name: str, target: str) -> list[str]:
    n = len(summary["point"])
    lines = [
        f"## Points ({n})",
        "",
        f"E_max,syst [mm]: median and {q_name} with their {level} intervals (order statistics), share of "
        f"trials below {target}, median reduction (before / after).",
        "",
        f"| series | {AXIS_UNITS[study.axis][0]} | trials | failed | median before | {q_name} before | below "
        f"| median after | {q_name} after | below | reduction |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for i in range(min(n, MAX_ROWS)):

        def stat(name: str, phase: str, i: int = i) -> float:
            return float(summary[stat_column(name, phase)][i])

        cells = [cell(summary["series"][i]), axis_text(study.axis, float(summary[study.axis][i]))]
        cells += [str(int(summary["trials"][i])), str(int(summary["failed"][i]))]
        for phase in ("before", "after"):
            for name in ("median", "quantile"):
                cells.append(_interval_text(stat(name, phase), stat(f"{name}_low", phase), stat(f"{name}_high", phase)))
            below = stat("below", phase)
            cells.append(f"{below * 100:.0f} %" if math.isfinite(below) else "-")
        reduction = float(summary["median_reduction"][i])
        cells.append(ratio_text(reduction) if math.isfinite(reduction) else "-")
        lines.append("| " + " | ".join(cells) + " |")
    if n > MAX_ROWS:
        lines.append(f"\n{n - MAX_ROWS} more points left out (see the summary table).")
    lines.append("")
    return lines


def _method_lines(study: Study, q_name: str, level: str) -> list[str]:
    return [
        "## Method",
        "",
        f"- {study.trials} trials per point, {study.design} design, seed {study.seed}; a trial builds one robot "
        "within the point's tolerances, runs the UMBmark procedure (Borenstein and Feng, \"UMBmark: a benchmark "
        'test for measuring odometry errors in mobile robots"), calibrates and runs it again.',
        "- Common random numbers: trial k of every point of one robot draws the same random numbers, so it is "
        "the same build scaled by the point's tolerances; the curves along the tolerance are smooth and the "
        "differences between points sharp, while each point's statistics are those of independent trials.",
        f"- Quantiles: NumPy's linear interpolation between order statistics (Hyndman and Fan, \"Sample "
        f'quantiles in statistical packages", type 7). {level} intervals of the median and the {q_name}: '
        'distribution-free, from order statistics with binomial ranks (David and Nagaraja, "Order '
        'Statistics"); an end the trials cannot reach is shown as unbounded. Failed trials are left out of '
        "the statistics and counted.",
        "- Tolerance found: the first crossing of the target from the small end of the axis, interpolated "
        "between the adjacent grid values in log-log (when the values are positive) or linearly.",
        f"- Reproduce: `omnikin sweep {cell(study.source)} -o DIR`"
        + (f" (study digest {study.digest})" if study.digest else ""),
        "",
    ]
