"""Bad study files of ``omnikin sweep`` are refused in one line naming the file, the line and the
field (omnikin.sweep.spec); hostile files cost neither time nor memory.

Each case writes a real file; the expected line is found in the test's own text (the line holding
a marker), not taken from the code under test.
"""

from __future__ import annotations

import os
import re

import pytest

from omnikin.errors import InputError, StudyFileError
from omnikin.sweep.spec import load_study

HEAD = "omnikin_sweep: 1\nrobots: [tomasi-omni3]\nseed: 1\ntrials: 4\n"


def line_of(text: str, marker: str) -> int:
    """The 1-based number of the only line of ``text`` containing ``marker``."""
    found = [i + 1 for i, line in enumerate(text.splitlines()) if marker in line]
    assert len(found) == 1, (marker, found)
    return found[0]


def refusal(tmp_path, text: str) -> StudyFileError:
    path = tmp_path / "study.yaml"
    path.write_text(text)
    with pytest.raises(StudyFileError) as info:
        load_study(path)
    message = str(info.value)
    assert "\n" not in message
    assert isinstance(info.value, InputError)
    return info.value


# (file text, field named, marker of its line, words the message must hold)
CASES = [
    (HEAD + "trails: 4\n", "trails", "trails:", ["unknown key 'trails'", "did you mean 'trials'"]),
    (HEAD + "question:\n  target_mm: 5\n  qantile: 0.9\n", "question.qantile", "qantile", ["did you mean 'quantile'"]),
    (
        HEAD + "factors:\n  scale:\n    from: 0.1\n    to: 1\n    cuont: 3\n",
        "factors.scale.cuont",
        "cuont",
        ["did you mean 'count'"],
    ),
    (HEAD + "factors:\n  scael: 1\n", "factors.scael", "scael", ["did you mean 'scale'"]),
    (HEAD.replace("trials: 4", "trials: many"), "trials", "trials:", ["whole number", "'many'"]),
    (HEAD.replace("trials: 4", "trials: 100001"), "trials", "trials:", ["100000", "got 100001"]),
    (HEAD.replace("seed: 1", "seed: -1"), "seed", "seed:", ["whole number", "got -1"]),
    (HEAD.replace("seed: 1", "seed: 1.5"), "seed", "seed:", ["whole number", "got 1.5"]),
    (HEAD.replace("omnikin_sweep: 1", "omnikin_sweep: 2"), "omnikin_sweep", "omnikin_sweep", ["version 2"]),
    (HEAD.replace("omnikin_sweep: 1", "omnikin_sweep: true"), "omnikin_sweep", "omnikin_sweep", ["True"]),
    (HEAD + "name: ''\n", "name", "name:", ["non-empty"]),
    (HEAD + "design: grd\n", "design", "design:", ["did you mean 'grid'", "got 'grd'"]),
    (HEAD + "points: 10\n", "points", "points:", ["only in the random design"]),
    (HEAD + "design: random\n", "points", "design:", ["required in the random design"]),
    (HEAD + "design: random\npoints: 0\n", "points", "points:", ["got 0"]),
    (HEAD + "question:\n  target_mm: 0\n", "question.target_mm", "target_mm", ["(0, 10000] mm", "got 0"]),
    (HEAD + "question:\n  quantile: 1\n", "question.quantile", "quantile", ["(0, 1)", "got 1"]),
    (HEAD + "question:\n  level: high\n", "question.level", "level", ["must be a number", "'high'"]),
    (HEAD + "question: 5\n", "question", "question", ["must be a mapping", "got 5"]),
    (HEAD + "umbmark:\n  side: 400\n", "umbmark.side", "side:", ["UMBmark square", "got 400"]),
    (HEAD + "umbmark:\n  runs: 0\n", "umbmark.runs", "runs:", ["whole number", "got 0"]),
    (HEAD + "umbmark:\n  mode: sideways\n", "umbmark.mode", "mode:", ["'sideways'", "translate"]),
    (HEAD + "factors: [scale]\n", "factors", "factors:", ["must be a mapping"]),
    (HEAD + "factors:\n  scale: 0\n", "factors.scale", "scale:", ["(0, 1000]", "got 0"]),
    (HEAD + "factors:\n  radius: 0.7\n", "factors.radius", "radius:", ["[0, 0.5]", "got 0.7"]),
    (HEAD + "factors:\n  hub: -0.001\n", "factors.hub", "hub:", ["[0, 0.1] m", "got -0.001"]),
    (HEAD + "factors:\n  drive_deg: 50\n", "factors.drive_deg", "drive_deg", ["[0, 45] deg", "got 50"]),
    (
        HEAD + "factors:\n  noise:\n    - typical\n    - loud\n",
        "factors.noise[1]",
        "- loud",
        ["'loud'", "typical"],
    ),
    (HEAD + "factors:\n  noise: []\n", "factors.noise", "noise:", ["empty list"]),
    (HEAD + "factors:\n  calibrate: 1\n", "factors.calibrate", "calibrate", ["true or false", "got 1"]),
    (HEAD + "factors:\n  calibrate: [true,\n    true]\n", "factors.calibrate[1]", "    true]", ["twice"]),
    (HEAD + "factors:\n  ticks_per_rev: 600.5\n", "factors.ticks_per_rev", "ticks_per_rev", ["whole number"]),
    (HEAD + "factors:\n  ticks_per_rev: 0\n", "factors.ticks_per_rev", "ticks_per_rev", ["from 1 to 4294967296"]),
    (HEAD + "factors:\n  rate: 1\n", "factors.rate", "rate:", ["sample rate", "got 1"]),
    (HEAD + "factors:\n  engine: physic\n", "factors.engine", "engine:", ["did you mean 'physics'"]),
    (
        HEAD + "factors:\n  noise: {from: 1, to: 2, count: 2}\n",
        "factors.noise",
        "noise:",
        ["numeric factors only"],
    ),
    (HEAD + "factors:\n  scale: {from: 0.1, to: 1}\n", "factors.scale", "scale:", ["'count'"]),
    (
        HEAD + "design: random\npoints: 5\nfactors:\n  scale:\n    from: 0.1\n    to: 1\n    count: 3\n",
        "factors.scale.count",
        "count: 3",
        ["only in the grid design"],
    ),
    (
        HEAD + "factors:\n  radius:\n    from: 0\n    to: 0.01\n    count: 3\n    spacing: log\n",
        "factors.radius.from",
        "from: 0",
        ["log spacing needs from > 0"],
    ),
    (
        HEAD + "factors:\n  scale:\n    from: 0.1\n    to: 1\n    count: 3\n    spacing: cubic\n",
        "factors.scale.spacing",
        "spacing",
        ["'cubic'", "linear"],
    ),
    (
        HEAD + "factors:\n  scale:\n    from: 0.1\n    to: 1\n    count: 0\n",
        "factors.scale.count",
        "count",
        ["from 1 to 1000", "got 0"],
    ),
    (HEAD + "factors:\n  scale: {from: 1, to: 0.1, count: 3}\n", "factors.scale", "scale:", ["from < to"]),
    (HEAD + "factors:\n  scale: {from: 0.1, to: 1, count: 1}\n", "factors.scale.count", "scale:", ["from == to"]),
    (
        HEAD + "factors:\n  ticks_per_rev:\n    from: 1\n    to: 3\n    count: 10\n",
        "factors.ticks_per_rev.count",
        "count: 10",
        ["repeat a value"],
    ),
    (
        HEAD + "factors:\n  noise: none\n  engine: physics\n",
        "factors.noise",
        "noise:",
        ["physics engine", "no random error model"],
    ),
    (HEAD.replace("robots: [tomasi-omni3]", "robots: []"), "robots", "robots:", ["non-empty list"]),
    (
        HEAD.replace("robots: [tomasi-omni3]", "robots:\n  - omni4\n  - mecanum4\n  - omni4  # again"),
        "robots[2]",
        "# again",
        ["appears twice", "robots[0]"],
    ),
    (HEAD.replace("tomasi-omni3", "omni5"), "robots[0]", "robots:", ["did you mean 'omni4'"]),
    (HEAD.replace("robots: [tomasi-omni3]", "robots: [3]"), "robots[0]", "robots:", ["got 3"]),
    (
        HEAD.replace("robots: [tomasi-omni3]", "robots: [diff-drive]") + "umbmark:\n  mode: translate\n",
        "robots[0]",
        "robots:",
        ["cannot drive the UMBmark square", "translate"],
    ),
]


@pytest.mark.parametrize(("text", "field", "marker", "words"), CASES, ids=[c[1] + ":" + c[3][0] for c in CASES])
def test_a_bad_study_file_is_refused_naming_its_line_and_field(tmp_path, text, field, marker, words):
    error = refusal(tmp_path, text)
    line = line_of(text, marker)
    assert str(error).startswith(f"{tmp_path / 'study.yaml'}: line {line}: {field}: "), str(error)
    assert (error.line, error.field) == (line, field)
    for word in words:
        assert word in str(error), (word, str(error))


def test_missing_required_keys_are_all_named(tmp_path):
    error = refusal(tmp_path, "# a study\nrobots: [omni4]\ntrials: 3\n")
    assert str(error).endswith("line 2: missing required key(s) ['omnikin_sweep', 'seed']")


@pytest.mark.parametrize(("text", "words"), [("", "empty"), ("- omni4\n", "mapping at top level, got list")])
def test_a_file_without_a_mapping_is_refused(tmp_path, text, words):
    assert words in str(refusal(tmp_path, text))


def test_a_broken_robot_file_is_named_with_the_robot_line_and_the_robot_error(tmp_path):
    (tmp_path / "bad.yaml").write_text(
        "omnikin: 1\nname: bad\nwheels:\n  - {name: w1, type: omni, distance: 0.1, angle_deg: 0, radius: -1}\n"
    )
    text = HEAD.replace("robots: [tomasi-omni3]", "robots:\n  - omni4\n  - bad.yaml")
    error = refusal(tmp_path, text)
    assert str(error).startswith(f"{tmp_path / 'study.yaml'}: line {line_of(text, 'bad.yaml')}: robots[1]: ")
    assert "field 'radius'" in str(error)


def test_a_robot_without_encoders_is_refused_naming_it(tmp_path):
    wheels = "".join(
        f"  - {{name: w{i}, type: omni, distance: 0.1, angle_deg: {a}, radius: 0.03}}\n"
        for i, a in enumerate((0, 120, 240))
    )
    (tmp_path / "blind.yaml").write_text(f"omnikin: 1\nname: blind\nwheels:\n{wheels}")
    text = HEAD.replace("tomasi-omni3", "blind.yaml")
    error = refusal(tmp_path, text)
    assert f"line {line_of(text, 'blind.yaml')}: robots[0]: " in str(error)
    assert "'blind'" in str(error) and "encoder" in str(error)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("a: &x [1, 2]\nb: *x\n", "anchors"),
        (HEAD.replace("seed: 1", "seed: !!int '1'"), "explicit tag"),
        (HEAD + "seed: 2\n", "duplicate key"),
        (HEAD.replace("trials: 4", "trials: 0120"), "octal"),
        (HEAD.replace("trials: 4", "trials: 1_000"), "digit separators"),
        (HEAD + "factors:\n  calibrate: yes\n", "line 6 column 14: 'yes' is a boolean in YAML 1.1"),
        (HEAD + "name: [off]\n", "'off' is a boolean in YAML 1.1"),
        (
            HEAD + "factors: {scale: [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]}\n",
            "nested deeper",
        ),
        ("omnikin_sweep: 1\n  robots: [\n", "invalid YAML"),
    ],
    ids=["alias", "tag", "duplicate", "octal", "separators", "yes", "off", "deep", "syntax"],
)
def test_hostile_or_ambiguous_yaml_is_refused(tmp_path, text, words):
    assert words in str(refusal(tmp_path, text))


def test_an_alias_bomb_is_refused_before_it_expands(tmp_path):
    rows = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    rows += [f"a{i}: &a{i} [*a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}]" for i in range(1, 20)]
    error = refusal(tmp_path, "\n".join(rows) + "\n")
    assert "anchors" in str(error) and "line 1 " in str(error)


def test_a_huge_grid_from_a_small_file_is_refused_before_it_is_built(tmp_path):
    ranges = "".join(
        f"  {name}: {{from: 0.001, to: 0.01, count: 1000}}\n" for name in ("scale", "radius", "hub", "drive_deg")
    )
    text = HEAD + "factors:\n" + ranges
    error = refusal(tmp_path, text)
    assert f"line {line_of(text, 'factors:')}: factors: " in str(error)
    assert "1 robot x 1000 scale x 1000 radius x 1000 hub x 1000 drive_deg = 1000000000000 points" in str(error)


def test_too_many_trials_in_all_are_refused_naming_the_trials(tmp_path):
    text = HEAD.replace("trials: 4", "trials: 100000") + "factors:\n  scale: {from: 0.01, to: 1, count: 101}\n"
    error = refusal(tmp_path, text)
    assert str(error).startswith(f"{tmp_path / 'study.yaml'}: line {line_of(text, 'trials:')}: trials: ")
    assert "= 10100000 trials, more than 10000000" in str(error)


def test_too_many_random_points_in_all_are_refused(tmp_path):
    text = (
        "omnikin_sweep: 1\nrobots: [tomasi-omni3, omni4, mecanum4]\nseed: 1\ntrials: 1000\n"
        "design: random\npoints: 10000\nfactors:\n  scale: {from: 0.01, to: 1}\n"
    )
    error = refusal(tmp_path, text)
    assert "line 4: trials: 1000 trials x 30000 points (3 robots x 10000 points)" in str(error)


def test_a_file_beyond_the_size_limit_or_no_file_is_refused(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_text(HEAD + "#" * (300 * 1024) + "\n")
    with pytest.raises(StudyFileError, match=re.escape(f"{big}: ") + r"\d+ bytes is too large"):
        load_study(big)
    with pytest.raises(StudyFileError, match="is a directory"):
        load_study(tmp_path)
    with pytest.raises(StudyFileError, match="no such file"):
        load_study(tmp_path / "nothing.yaml")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_named_pipe_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "study.yaml"
    os.mkfifo(fifo)
    with pytest.raises(StudyFileError, match="pipe"):
        load_study(fifo)
