"""A study file of ``omnikin sweep`` becomes the points it describes (omnikin.sweep.spec): the grid
in its documented order, log spacing, the random design's documented draws, the physics engine's
points without noise, robot files relative to the study file, a digest that follows the content.

Expected values come from closed forms and from the format as documented (itertools.product in
the order of the Point fields, the random stream's documented seed), not from the module.
"""

from __future__ import annotations

import itertools
import math
import shutil

import numpy as np
import pytest

from omnikin.io.robot_file import load_robot
from omnikin.presets import preset_path
from omnikin.sweep.points import robot_hash
from omnikin.sweep.spec import load_study, parse_study
from support.paths import ROOT

HEAD = "omnikin_sweep: 1\nrobots: [tomasi-omni3]\nseed: 1\ntrials: 4\n"


def study_of(tmp_path, text: str, name: str = "study.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return load_study(path)


def test_a_minimal_file_takes_the_documented_defaults(tmp_path):
    study = study_of(tmp_path, HEAD, "my-study.yaml")
    assert (study.name, study.seed, study.trials, study.design) == ("my-study", 1, 4, "grid")
    assert (study.target, study.quantile, study.level) == (0.010, 0.95, 0.95)
    (point,) = study.points
    assert point.robot == "tomasi-omni3"
    assert point.robot_hash == robot_hash(load_robot("tomasi-omni3"))
    documented = dict(scale=1.0, radius=0.005, hub=0.001, drive_deg=0.5, noise="typical", ticks_per_rev=None)
    documented |= dict(rate=100.0, calibrate=True, engine="kinematic", side=4.0, mode="rotate", runs=5)
    assert {k: getattr(point, k) for k in documented} == documented
    assert set(study.robots) == {"tomasi-omni3"}


def test_question_and_square_are_read_with_the_target_in_metres(tmp_path):
    text = (
        HEAD
        + "question:\n  target_mm: 2.5\n  quantile: 0.9\n  level: 0.99\numbmark: {side: 2, mode: translate, runs: 3}\n"
    )
    study = study_of(tmp_path, text)
    assert (study.target, study.quantile, study.level) == (0.0025, 0.9, 0.99)
    assert {(p.side, p.mode, p.runs) for p in study.points} == {(2.0, "translate", 3)}


def test_the_grid_is_every_combination_robots_outermost_then_the_point_fields_in_order(tmp_path):
    # written in an order unlike the fields' on purpose: the order of points follows the fields
    text = (
        "omnikin_sweep: 1\nrobots: [omni4, tomasi-omni3]\nseed: 3\ntrials: 2\nfactors:\n"
        "  calibrate: [true, false]\n  ticks_per_rev: [600, 2400]\n  noise: [typical, none]\n"
        "  scale: {from: 0.5, to: 1, count: 3}\n  rate: 50\n"
    )
    study = study_of(tmp_path, text)
    scales = [0.5 + 0.5 * i / 2 for i in range(3)]  # linear, endpoints included
    fields_order = ["robot", "scale", "noise", "ticks_per_rev", "calibrate"]  # Point's field order
    expected = list(
        itertools.product(["omni4", "tomasi-omni3"], scales, ["typical", "none"], [600, 2400], [True, False])
    )
    assert [tuple(getattr(p, f) for f in fields_order) for p in study.points] == expected
    assert {p.rate for p in study.points} == {50.0}
    assert len({p.robot_hash for p in study.points}) == 2


def test_log_spacing_gives_log_even_values_with_exact_endpoints(tmp_path):
    text = HEAD + "factors:\n  scale: {from: 0.001, to: 1, count: 13, spacing: log}\n"
    scales = [p.scale for p in study_of(tmp_path, text).points]
    closed_form = [10 ** (-3 + 3 * i / 12) for i in range(13)]
    assert scales == pytest.approx(closed_form, rel=1e-12)
    assert (scales[0], scales[-1]) == (0.001, 1.0)


def test_a_log_range_of_whole_numbers_is_rounded(tmp_path):
    text = HEAD + "factors:\n  ticks_per_rev: {from: 100, to: 10000, count: 5, spacing: log}\n"
    ticks = [p.ticks_per_rev for p in study_of(tmp_path, text).points]
    assert ticks == [100, 316, 1000, 3162, 10000]  # round(10**2.5), round(10**3.5)
    assert all(type(t) is int for t in ticks)


def test_tolerances_of_zero_are_a_perfect_build(tmp_path):
    text = HEAD + "factors:\n  radius: 0\n  hub: 0\n  drive_deg: [0, 0.5]\n"
    points = study_of(tmp_path, text).points
    assert [(p.radius, p.hub, p.drive_deg) for p in points] == [(0, 0, 0), (0, 0, 0.5)]


RANDOM = (
    "omnikin_sweep: 1\nrobots: [tomasi-omni3, omni4]\nseed: {seed}\ntrials: 3\ndesign: random\npoints: {points}\n"
    "factors:\n  scale: {{from: 0.01, to: 1, spacing: log}}\n  hub: 0.002\n  noise: [typical, none]\n"
    "  ticks_per_rev: {{from: 100, to: 4000}}\n  rate: {{from: 50, to: 200}}\n"
)


def test_the_random_design_draws_as_documented(tmp_path):
    study = study_of(tmp_path, RANDOM.format(seed=5, points=30))
    # the documented stream and order: setting by setting, factors in Point field order, a list or
    # a range drawing one number each, a single value none
    rng = np.random.default_rng(np.random.SeedSequence(5, spawn_key=(0,)))
    settings = []
    for _ in range(30):
        scale = math.exp(rng.uniform(math.log(0.01), math.log(1)))
        noise = ["typical", "none"][int(rng.integers(2))]
        ticks = round(rng.uniform(100, 4000))
        rate = rng.uniform(50, 200)
        settings.append((scale, noise, ticks, rate))
    got = [(p.robot, p.scale, p.noise, p.ticks_per_rev, p.rate) for p in study.points]
    assert got == [(robot, *s) for robot in ("tomasi-omni3", "omni4") for s in settings]
    assert {p.hub for p in study.points} == {0.002}
    assert all(0.01 <= p.scale <= 1 and 100 <= p.ticks_per_rev <= 4000 and 50 <= p.rate <= 200 for p in study.points)


def test_the_random_design_is_reproducible_and_grows_by_keeping_its_first_points(tmp_path):
    first = study_of(tmp_path, RANDOM.format(seed=5, points=10), "a.yaml")
    again = study_of(tmp_path, RANDOM.format(seed=5, points=10), "b.yaml")
    more = study_of(tmp_path, RANDOM.format(seed=5, points=20), "c.yaml")
    other = study_of(tmp_path, RANDOM.format(seed=6, points=10), "d.yaml")
    assert first.points == again.points and first.digest == again.digest
    assert more.points[:10] == first.points[:10]
    assert {p.scale for p in other.points}.isdisjoint({p.scale for p in first.points})


def test_a_random_design_of_lists_only_drops_repeated_settings(tmp_path):
    text = HEAD + "design: random\npoints: 50\nfactors:\n  noise: [typical, none]\n"
    points = study_of(tmp_path, text).points
    assert [p.noise for p in points] in (["typical", "none"], ["none", "typical"])


def test_physics_points_have_no_noise_and_repeats_are_dropped(tmp_path):
    text = HEAD + "factors:\n  scale: [0.1, 1]\n  noise: [typical, none]\n  engine: [kinematic, physics]\n"
    points = study_of(tmp_path, text).points
    expected = [
        (0.1, "typical", "kinematic"),
        (0.1, None, "physics"),
        (0.1, "none", "kinematic"),
        (1.0, "typical", "kinematic"),
        (1.0, None, "physics"),
        (1.0, "none", "kinematic"),
    ]
    assert [(p.scale, p.noise, p.engine) for p in points] == expected


def test_a_physics_study_without_a_noise_factor_runs_without_noise(tmp_path):
    points = study_of(tmp_path, HEAD + "factors:\n  engine: physics\n").points
    assert [(p.noise, p.engine) for p in points] == [(None, "physics")]


def test_robot_files_are_relative_to_the_study_file_not_the_working_folder(tmp_path, monkeypatch):
    folder = tmp_path / "studies"
    (folder / "robots").mkdir(parents=True)
    text = preset_path("omni4").read_text().replace("name: omni4", "name: my-omni4")
    (folder / "robots" / "mine.yaml").write_text(text)
    (folder / "study.yaml").write_text(HEAD.replace("[tomasi-omni3]", "[robots/mine.yaml, ./robots/mine.yaml]"))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    study = load_study(folder / "study.yaml")
    assert [p.robot for p in study.points] == ["robots/mine.yaml", "./robots/mine.yaml"]
    assert study.robots["robots/mine.yaml"].name == "my-omni4"
    assert {p.robot_hash for p in study.points} == {robot_hash(load_robot(folder / "robots" / "mine.yaml"))}


def test_parse_study_resolves_robot_files_against_the_given_base(tmp_path):
    shutil.copy(preset_path("mecanum4"), tmp_path / "m.yaml")
    study = parse_study(HEAD.replace("tomasi-omni3", "m.yaml"), "<text>", tmp_path)
    assert study.robots["m.yaml"].name == "mecanum4"


def test_the_digest_follows_what_decides_the_results_not_how_the_file_is_written(tmp_path):
    base = study_of(tmp_path, HEAD + "factors:\n  scale: [0.1, 1]\n", "a.yaml")
    reordered = study_of(
        tmp_path,
        "trials: 4\nseed: 1\n# same study\n" + HEAD.split("seed")[0] + "factors: {scale: [0.1, 1.0]}\n",
        "b.yaml",
    )
    assert len(base.digest) == 16 and base.digest == reordered.digest
    for change in ("trials: 5", "seed: 2"):
        key = change.split(":")[0]
        text = HEAD.replace(next(line for line in HEAD.splitlines() if line.startswith(key)), change)
        assert study_of(tmp_path, text + "factors:\n  scale: [0.1, 1]\n", "c.yaml").digest != base.digest
    target = study_of(tmp_path, HEAD + "question: {target_mm: 5}\nfactors:\n  scale: [0.1, 1]\n", "d.yaml")
    assert target.digest != base.digest


def test_the_digest_follows_the_content_of_a_robot_file(tmp_path):
    robot = tmp_path / "r.yaml"
    robot.write_text(preset_path("omni4").read_text())
    text = HEAD.replace("tomasi-omni3", "r.yaml")
    before = study_of(tmp_path, text).digest
    edited = preset_path("omni4").read_text().replace("radius: 0.05,", "radius: 0.051,", 1)
    assert "radius: 0.051," in edited
    robot.write_text(edited)
    assert study_of(tmp_path, text).digest != before


def test_the_example_tolerance_study_loads_as_described():
    study = load_study(ROOT / "examples" / "tolerance.yaml")
    assert set(study.robots) == {"tomasi-omni3"}
    assert all(p.noise == "typical" and p.side == 2.0 and p.runs == 5 for p in study.points)
    scales = [p.scale for p in study.points]
    assert len(scales) == 4 and scales == sorted(scales)
    ratios = [b / a for a, b in itertools.pairwise(scales)]
    assert ratios == pytest.approx([10.0] * 3, rel=1e-9)  # one per decade over 3 decades
    assert scales[-1] == 1.0 and scales[0] == pytest.approx(0.001)
    assert all(p.calibrate and p.engine == "kinematic" for p in study.points)
    assert study.trials >= 72  # enough to bound the 95th percentile from above at 95 %
    assert study.target == pytest.approx(0.010) and study.axis == "scale"


def test_the_example_layout_study_compares_three_presets():
    study = load_study(ROOT / "examples" / "layouts.yaml")
    assert list(dict.fromkeys(p.robot for p in study.points)) == ["tomasi-omni3", "omni4", "mecanum4"]
    assert len(study.points) * study.trials <= 400
