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

from ..common.number_text import mm_text, ratio_text, round_down
from ..evaluation.order_statistics import values_for_bound
from ..evaluation.threshold import ABOVE, ABOVE_FIRST, BELOW, Crossing
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


def _calibration(study: Study) -> str:
    """Whether the study's points calibrate: ``all``, ``none`` or ``some``."""
    calibrates = {p.calibrate for p in study.points}
    return "some" if len(calibrates) > 1 else ("none" if calibrates == {False} else "all")


_QUESTION = {
    "all": ", before and after calibration? Every trial builds a robot within the tolerances, runs UMBmark, "
    "calibrates it and runs UMBmark again;",
    "none": "? Every trial builds a robot within the tolerances and runs UMBmark; the study does not calibrate "
    "(calibrate: false), so E_max,syst is that of the robots as built;",
    "some": ", with and without calibration? Every trial builds a robot within the tolerances and runs UMBmark; "
    "at the points with calibrate: true it then calibrates the robot and runs UMBmark again;",
}
"""The end of the question and what a trial does, by :func:`_calibration`: a study that does not
calibrate describes no calibration."""


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
        f"{study.quantile * 100:g} % of robots (its {q_name} below the target){_QUESTION[_calibration(study)]} "
        f"the tolerances are read along {axis_label} with {level} confidence intervals.",
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


def conclusion(study: Study, answer: Answer) -> str:
    """The answer of one series and phase in a plain sentence: which tolerance keeps the
    study's quantile of E_max,syst below the target (``up to ...``, ``at every ... studied``, or
    ``at none of the ... studied``), with the three build tolerances and the conservative value."""
    share = f"{study.quantile * 100:g} % of the robots"
    target = f"{study.target * 1000:g} mm"
    axis = AXIS_UNITS[answer.axis][0].split(" [")[0]
    head = f"{cell(answer.series.label)}, {answer.phase_text}: E_max,syst stays below {target} for {share}"
    value = answer.estimate.value
    triple = tolerances_text(answer, value)
    built = "" if triple == "-" else f" ({triple})"
    if value is None:
        smallest = axis_text(answer.axis, answer.estimate.first[0])
        return f"{head} at none of the {axis} values studied: not even at the smallest, {smallest}."
    if answer.estimate.status == BELOW:
        return (
            f"{head} at every {axis} studied, up to {axis_text(answer.axis, value)}{built}; "
            "larger tolerances were not studied."
        )
    conservative = answer.conservative.value
    careful = (
        f"; with {study.level * 100:g} % confidence up to {crossing_text(answer, answer.conservative)}"
        if conservative is not None
        else f"; too few trials to say it with {study.level * 100:g} % confidence"
    )
    return f"{head} up to {axis} {axis_text(answer.axis, value)}{built}{careful}."


def _answer_lines(study: Study, summary, answers: Sequence[Answer], level: str, q_name: str) -> list[str]:
    lines = [
        "## Answer",
        "",
        *[f"- {conclusion(study, a)}" for a in answers],
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
                    a.phase_text,
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
    calibrates = _calibration(study) != "none"
    phases = ("before", "after") if calibrates else ("before",)
    names = {"before": " before", "after": " after"} if calibrates else {"before": ""}
    head = "".join(f" | median{names[p]} | {q_name}{names[p]} | below" for p in phases)
    lines = [
        f"## Points ({n})",
        "",
        f"E_max,syst [mm]: median and {q_name} with their {level} intervals (order statistics), share of "
        f"trials below {target}" + (", median reduction (before / after)." if calibrates else "."),
        "",
        f"| series | {AXIS_UNITS[study.axis][0]} | trials | failed{head}" + (" | reduction |" if calibrates else " |"),
        "|---" * (4 + 3 * len(phases) + calibrates) + "|",
    ]
    for i in range(min(n, MAX_ROWS)):

        def stat(name: str, phase: str, i: int = i) -> float:
            return float(summary[stat_column(name, phase)][i])

        cells = [cell(summary["series"][i]), axis_text(study.axis, float(summary[study.axis][i]))]
        cells += [str(int(summary["trials"][i])), str(int(summary["failed"][i]))]
        for phase in phases:
            for name in ("median", "quantile"):
                cells.append(_interval_text(stat(name, phase), stat(f"{name}_low", phase), stat(f"{name}_high", phase)))
            below = stat("below", phase)
            cells.append(f"{below * 100:.0f} %" if math.isfinite(below) else "-")
        if calibrates:
            cells.append(_reduction_text(summary, i))
        lines.append("| " + " | ".join(cells) + " |")
    if n > MAX_ROWS:
        lines.append(f"\n{n - MAX_ROWS} more points left out (see the summary table).")
    lines.append("")
    return lines


def _reduction_text(summary, i: int) -> str:
    """The median reduction of row ``i``: ``at least N`` when it is a bound (``reduction_bound``:
    some trial's after-value is below the 0.01 mm the report resolves)."""
    reduction = float(summary["median_reduction"][i])
    if not math.isfinite(reduction):
        return "-"
    if bool(summary["reduction_bound"][i]):
        return f"at least {ratio_text(round_down(reduction))}"
    return ratio_text(reduction)


def _method_lines(study: Study, q_name: str, level: str) -> list[str]:
    return [
        "## Method",
        "",
        f"- {study.trials} trials per point, {study.design} design, seed {study.seed}; a trial builds one robot "
        "within the point's tolerances and runs the UMBmark procedure (Borenstein and Feng, \"UMBmark: a "
        'benchmark test for measuring odometry errors in mobile robots")'
        + {
            "all": ", calibrates and runs it again.",
            "none": ", without calibration.",
            "some": "; at the points that calibrate it calibrates and runs it again.",
        }[_calibration(study)],
        "- Common random numbers: trial k of every point of one robot draws the same random numbers, so it is "
        "the same build scaled by the point's tolerances; the curves along the tolerance are smooth and the "
        "differences between points sharp, while each point's statistics are those of independent trials.",
        f"- Quantiles: NumPy's linear interpolation between order statistics (Hyndman and Fan, \"Sample "
        f'quantiles in statistical packages", type 7). {level} intervals of the median and the {q_name}: '
        'distribution-free, from order statistics with binomial ranks (David and Nagaraja, "Order '
        'Statistics"); an end the trials cannot reach is shown as unbounded. Failed trials are left out of '
        "the statistics and counted.",
        *(
            [
                "- Reduction: the median over the trials of E_max,syst before / after calibration; an after-value "
                "below 0.01 mm (the resolution of this report's millimetres) counts as 0.01 mm, and the factor "
                "is then only a lower bound, printed as `at least N`."
            ]
            if _calibration(study) != "none"
            else []
        ),
        "- Tolerance found: the first crossing of the target from the small end of the axis, interpolated "
        "between the adjacent grid values in log-log (when the values are positive) or linearly.",
        f"- Reproduce: `omnikin sweep {cell(study.source)} -o DIR`"
        + (f" (study digest {study.digest})" if study.digest else ""),
        "",
    ]
