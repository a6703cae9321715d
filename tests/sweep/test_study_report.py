"""The study's report.md: the question with its numbers, the answer table first, the figures, a
bounded table per point, failures on one line each, the method and how to reproduce it."""

from __future__ import annotations

from omnikin.sweep.points import Point
from omnikin.sweep.report import MAX_ROWS, study_markdown
from omnikin.sweep.summary import answers, summarize
from support.sweep_tables import grid, make_study, proportional_table

SCALES = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)


def report_of(points, trials=80, **kwargs):
    study = make_study(points, trials=trials, target=0.010, quantile=0.95, level=0.95)
    summary = summarize(proportional_table(points, 0.008, 0.002, trials), study)
    options = {"figures": ["tolerance.png"], "failures": []} | kwargs
    return study_markdown(study, summary, answers(summary, study), **options)


def table_rows(text: str, heading: str) -> list[list[str]]:
    section = text.split(heading, 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ")]
    return [[c.strip() for c in row.strip("|").split(" | ")] for row in rows[1:]]


def test_question_names_target_quantile_and_level_and_the_answer_comes_first():
    text = report_of(grid(scales=SCALES))
    question = text.split("## Answer")[0]
    assert "10 mm" in question and "95 % of robots" in question and "95 % confidence" in question
    assert text.index("## Answer") < text.index("## Figures") < text.index("## Points") < text.index("## Method")
    assert "![tolerance.png](tolerance.png)" in text


def test_answer_table_gives_the_closed_form_tolerance_and_its_three_build_tolerances():
    rows = table_rows(report_of(grid(scales=SCALES, radius=0.004, hub=0.002, drive_deg=0.3)), "## Answer")
    before, after = rows
    assert before[1] == "before calibration" and after[1] == "after calibration"
    assert before[2] == "1.25" and after[2] == "5"  # target / c = 10 / 8 and 10 / 2
    assert before[3] == "radius 0.5 %, hub 2.5 mm, drive 0.375 deg"  # 1.25 x (0.4 %, 2 mm, 0.3 deg)
    assert before[4].startswith("crosses") and before[5] == "1.25"


def test_too_few_trials_make_the_conservative_answer_none_and_say_how_many_are_needed():
    text = report_of(grid(scales=SCALES), trials=10)
    before = table_rows(text, "## Answer")[0]
    assert before[5] == "none" and "needs 72 trials per point" in before[6]


def test_point_table_shows_medians_with_intervals_in_mm_and_is_bounded():
    rows = table_rows(report_of(grid(scales=SCALES)), "## Points")
    assert len(rows) == len(SCALES)
    assert rows[2][1] == "1" and rows[2][4] == "8.00 (8.00 to 8.00)"  # 8 mm x scale 1, no spread
    assert rows[2][6] == "100 %" and rows[3][6] == "0 %"  # 8 mm < 10 mm <= 16 mm
    assert rows[2][10] == "4"  # 8 mm / 2 mm
    many = [Point(robot="omni3", robot_hash="0" * 16, scale=0.01 * (k + 1)) for k in range(MAX_ROWS + 5)]
    text = report_of(many, trials=2)
    assert len(table_rows(text, "## Points")) == MAX_ROWS
    assert "5 more points left out" in text


def test_failures_are_one_line_each_and_a_hostile_robot_name_cannot_break_a_table():
    points = grid(robot="evil|name\nwith lines", scales=SCALES)
    failure = "point 3 (scale 2): wheel 2 radius <= 0\n" + "x" * 10_000
    text = report_of(points, failures=[failure])
    (line,) = [line for line in text.splitlines() if line.startswith("- point 3")]
    assert len(line) < 400 and "chars)" in line
    for row in table_rows(text, "## Answer"):
        assert len(row) == 7 and row[0].startswith("evil\\|name with lines")


def test_method_names_trials_common_random_numbers_and_how_to_reproduce():
    method = report_of(grid(scales=SCALES)).split("## Method")[1]
    assert "80 trials per point" in method
    assert "same build scaled" in method
    assert "order statistics" in method
    assert "`omnikin sweep test.yaml -o DIR`" in method


def test_a_study_without_calibration_describes_no_calibration():
    points = grid(scales=SCALES, calibrate=False)
    text = report_of(points)
    rows = table_rows(text, "## Answer")
    assert [r[1] for r in rows] == ["without calibration"]  # one row, no "before" of a calibration not done
    said = text.replace("does not calibrate (calibrate: false)", "").replace("without calibration", "")
    assert "calibrat" not in said and "reduction" not in said, said
    assert len(table_rows(text, "## Points")[0]) == 7  # series, scale, trials, failed, median, percentile, below
    study = make_study(points, trials=80, target=0.010, quantile=0.95, level=0.95)
    summary = summarize(proportional_table(points, 0.008, 0.002, 80), study)
    (answer,) = answers(summary, study)
    assert "without calibration" in answer.text and "before calibration" not in answer.text


def test_a_study_that_calibrates_some_points_says_which():
    points = grid(scales=SCALES, calibrate=True) + grid(scales=SCALES, calibrate=False)
    text = report_of(points)
    assert "at the points with calibrate: true it then calibrates" in text.split("## Answer")[0]
    phases = [r[1] for r in table_rows(text, "## Answer")]
    assert phases == ["before calibration", "after calibration", "without calibration"]


def test_the_figure_of_a_study_without_calibration_has_one_panel_without_calibration():
    from omnikin.viz.sweep import tolerance_figure

    points = grid(scales=SCALES, calibrate=False)
    study = make_study(points, trials=80, target=0.010, quantile=0.95, level=0.95)
    figure = tolerance_figure(summarize(proportional_table(points, 0.008, 0.002, 80), study), study)
    titles = [ax.get_title() for ax in figure.axes]
    assert titles == ["without calibration"]
    assert "calibrat" not in figure._suptitle.get_text()
