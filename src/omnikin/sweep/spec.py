"""The study file of ``omnikin sweep``, schema version 1: YAML read as strictly as robot files.

A study file says which robots to build within which tolerances, how many trials each point
of the study runs, and which question the study answers (docs/sweeps.md)::

    omnikin_sweep: 1                 # required: the schema version
    name: Build tolerances           # optional; default: the file's name without its ending
    robots: [tomasi-omni3]           # required: preset names or robot files (relative to this file)
    seed: 1                          # required: whole number >= 0
    trials: 200                      # required: trials per point, 1 to 100000
    design: grid                     # optional: grid (default) or random
    points: 40                       # random design only, required there: settings drawn, 1 to 10000
    question:                        # optional
      target_mm: 10                  # threshold of E_max,syst [mm], (0, 10000], default 10
      quantile: 0.95                 # share of robots that must stay below it, (0, 1), default 0.95
      level: 0.95                    # confidence level of the intervals, (0, 1), default 0.95
    umbmark:                         # optional: the square of every trial (defaults of omnikin umbmark)
      side: 4                        # [m], 0.05 to 100, default 4
      mode: rotate                   # rotate (default) or translate
      runs: 5                        # runs per direction, 1 to 1000, default 5
    factors:                         # optional: each a value, a list of values or a range
      scale: {from: 0.001, to: 1, count: 13, spacing: log}
      radius: 0.005                  # sigma of the wheel radius [relative], [0, 0.5], default 0.005
      hub: 0.001                     # sigma of the hub position [m], isotropic, [0, 0.1], default 0.001
      drive_deg: 0.5                 # sigma of the drive direction [deg], [0, 45], default 0.5
      noise: [typical, none]         # random errors of the runs (NOISE names), default typical
      ticks_per_rev: [600, 2400]     # every encoder's resolution, whole; default: the robot's own
      rate: 100                      # sample rate [Hz], 5 to 10000, default 100
      calibrate: [true, false]       # default true
      engine: kinematic              # kinematic (default) or physics

The factors are the fields of :class:`~omnikin.sweep.points.Point`; ``scale`` (in (0, 1000],
default 1) multiplies the three tolerances ``radius``, ``hub`` and ``drive_deg``. Their limits
(:data:`FACTOR_RANGES`): a relative radius sigma of 0.5 already draws wheels of zero radius at
2 sigma, a hub sigma of 10 cm and a drive sigma of 45 deg describe no robot as designed; 0 is a
perfectly built robot. A factor is written as

* a value (``radius: 0.005``): every point takes it;
* a list (``noise: [typical, none]``, at least one value, none twice): the grid takes every
  value, the random design draws one of them (uniformly) for each point;
* a range of a numeric factor ``{from: A, to: B, count: N, spacing: linear|log}`` (A < B, or
  A == B with N = 1; ``spacing`` defaults to linear; log needs A > 0). In the grid ``count``
  (1 to 1000) is required and gives N values spaced evenly (log: evenly in the logarithm), A and B
  included; a random design draws from a range *without* count, uniformly (log: uniformly in the
  logarithm), for each point. Whole-number factors (``ticks_per_rev``) are rounded.

Booleans are ``true`` and ``false`` only; numbers are plain decimals
(:func:`~omnikin.io.robot_file.strict_yaml_loader`: no anchors, tags, duplicate keys, octal or
base-60 forms).

Points (:func:`parse_study`), in a stable order: robots outermost, then the factors in the order
of :class:`~omnikin.sweep.points.Point`'s fields (``scale`` ... ``engine``), the last varying
fastest. The grid takes every combination of the factors' values. The random design draws
``points`` settings from ``np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0,)))``
(a stream apart from the trials', whose spawn keys have three words,
:func:`~omnikin.sweep.points.trial_seed`): setting after setting, within one setting the factors
in field order, each list of several values or range drawing one number, a
single value none; every robot
runs every setting. The same file gives the same points, and a larger ``points`` keeps the
settings of a smaller one. A setting equal to an earlier one is dropped (a point is named by its
settings), so a random design of lists only may give fewer points than asked.

The physics engine has no noise model
(:func:`~omnikin.physics.engines.check_physics_noise`): its points get ``noise`` None; a
``noise`` factor in a study whose every point runs the physics engine is an error, and with
both engines the noise values apply to the kinematic points (the physics points they would
repeat are dropped, the first kept).

Every robot is loaded when the file is (:func:`~omnikin.io.robot_file.load_robot`; a file
relative to the study file's folder), must have encoders that observe its motion
(:func:`~omnikin.odometry.batch.encoded_wheels`) and must be able to drive the study's UMBmark square
(:func:`~omnikin.evaluation.umbmark.square_refusal`). A study of more than :data:`MAX_POINTS`
points, or of more than :data:`MAX_TRIALS` trials in all, is refused before a point is built.

Every problem raises :class:`~omnikin.errors.StudyFileError` in one line naming the file, the
line and the field (``study.yaml: line 12: factors.scale.count: must be a whole number from 1
to 1000, got 0``); values are quoted through :func:`~omnikin.common.messages.shorten`. The lines come from
the YAML node tree composed by the same strict loader.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..common.arrays import range_problem, whole_problem
from ..common.messages import did_you_mean, shorten
from ..errors import InputError, RobotFileError, StudyFileError
from ..evaluation.umbmark import check_side, square_refusal
from ..io.robot_file import is_preset_spec, load_robot, parse_yaml, strict_yaml_loader
from ..io.textfile import read_text
from ..kinematics.encoder import TICKS_PER_REV_RANGE
from ..kinematics.robot import Robot, robot_name_problem
from ..motion.plans import check_mode
from ..motion.timing import RATE_RANGE, check_rate_range
from ..odometry.batch import encoded_wheels
from ..physics.engines import ENGINE_NAMES, engine_class
from ..presets import PRESET_NAMES
from ..simulation.error_models import NOISE
from .points import POINT_FIELDS, Point, _digest, canonical_json, robot_hash
from .study import DESIGNS, Study

SCHEMA_VERSION = 1

TOP_KEYS = {
    "omnikin_sweep": True,
    "name": False,
    "robots": True,
    "seed": True,
    "trials": True,
    "design": False,
    "points": False,
    "question": False,
    "umbmark": False,
    "factors": False,
}
"""The keys of a study file and whether each is required (``points``: in the random design)."""

QUESTION_KEYS = ("target_mm", "quantile", "level")
UMBMARK_KEYS = ("side", "mode", "runs")
RANGE_KEYS = ("from", "to", "count", "spacing")
SPACINGS = ("linear", "log")

_NOT_FACTORS = ("robot", "robot_hash", *UMBMARK_KEYS)
FACTORS = tuple(name for name in POINT_FIELDS if name not in _NOT_FACTORS)
"""The factors of a study, in the order of :class:`~omnikin.sweep.points.Point`'s fields."""

DEFAULTS: dict[str, Any] = {f.name: f.default for f in fields(Point) if f.name not in ("robot", "robot_hash")}
"""The value of every factor and UMBmark setting a file leaves out (the defaults of :class:`Point`)."""

FACTOR_RANGES: dict[str, tuple[float, float, str, bool]] = {
    "scale": (0.0, 1000.0, "", True),
    "radius": (0.0, 0.5, "", False),
    "hub": (0.0, 0.1, "m", False),
    "drive_deg": (0.0, 45.0, "deg", False),
    "rate": (*RATE_RANGE, "Hz", False),
}
"""``(low, high, unit, low excluded)`` of each real factor (module docstring gives the reasons;
``rate``: :data:`~omnikin.motion.timing.RATE_RANGE`, checked by
:func:`~omnikin.motion.timing.check_rate_range`). ``scale`` excludes 0: set a tolerance
itself to 0 for a perfect build in that respect."""

WHOLE_FACTORS: dict[str, tuple[int, int]] = {
    "ticks_per_rev": (int(TICKS_PER_REV_RANGE[0]), int(TICKS_PER_REV_RANGE[1])),
}
"""Range of each whole-number factor (:data:`~omnikin.kinematics.encoder.TICKS_PER_REV_RANGE`)."""

CHOICE_FACTORS: dict[str, tuple[str, ...]] = {"noise": tuple(NOISE), "engine": ENGINE_NAMES}
BOOL_FACTORS = ("calibrate",)

SEED_RANGE = (0, 2**64 - 1)
"""Seeds: any whole number a ``numpy.random.SeedSequence`` takes that also fits an unsigned 64-bit column."""
TRIALS_RANGE = (1, 100_000)
"""Trials per point: 100 000 trials give a 95 % quantile to +-0.14 percentage points; more is cost, not insight."""
POINTS_RANGE = (1, 10_000)
"""Settings a random design draws."""
COUNT_RANGE = (1, 1000)
"""Values of a grid range."""
RUNS_RANGE = (1, 1000)
"""UMBmark runs per direction (Borenstein and Feng use 5)."""
TARGET_MM_RANGE = (0.0, 10_000.0)
"""Threshold of ``E_max,syst`` [mm], 0 excluded: up to 10 m, beyond the largest UMBmark square error."""

MAX_ROBOTS = 100
"""Robots of one study: each is read and checked when the file is loaded (a robot file may take
a second to parse), so that a small file cannot name thousands of them."""
MAX_POINTS = 100_000
"""Points of one study: the points and their keys are held in memory, and the study folder
writes a part per point."""
MAX_TRIALS = 10_000_000
"""Trials of one study (points x trials): at 0.15 s a trial, about 17 core-days."""


class _Where:
    """Turns a key path (``("factors", "noise", 1)``) into the line of the file it is on and the
    field it names (``factors.noise[1]``), for one-line errors."""

    def __init__(self, source: str, lines: Mapping[tuple, int]):
        self.source = source
        self.lines = lines

    def line(self, path: tuple) -> int:
        """The line of ``path``, else of its nearest enclosing key (1 for the whole file)."""
        while path not in self.lines and path:
            path = path[:-1]
        return self.lines.get(path, 1)

    def error(self, path: tuple, problem: str, at: tuple | None = None) -> StudyFileError:
        """The error ``problem`` of the field ``path``, on the line of ``at`` (default: of ``path``)."""
        field = field_name(path)
        line = self.line(path if at is None else at)
        head = f"{self.source}: line {line}: " + (f"{field}: " if field else "")
        return StudyFileError(head + problem, line=line, field=field or None)

    def checked(self, path: tuple, check: Callable[[str], Any]) -> Any:
        """``check(field)``, an omnikin check that names the field it is given, with its
        InputError turned into this file's error at ``path``."""
        field = field_name(path)
        try:
            return check(field)
        except InputError as exc:
            raise self.error(path, str(exc).removeprefix(f"{field}: ")) from None


def field_name(path: tuple) -> str:
    """``("factors", "noise", 1)`` as ``factors.noise[1]``."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def key_lines(node, path: tuple = (), lines: dict[tuple, int] | None = None) -> dict[tuple, int]:
    """The line (1-based) of every key path of a composed YAML node tree: a mapping entry's is the
    line of its key, a list item's the line it starts on."""
    import yaml

    if lines is None:
        lines = {(): node.start_mark.line + 1}
    if isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            inner = (*path, key.value)
            lines.setdefault(inner, key.start_mark.line + 1)
            key_lines(value, inner, lines)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            inner = (*path, index)
            lines.setdefault(inner, item.start_mark.line + 1)
            key_lines(item, inner, lines)
    return lines


_BOOLEANS = ("true", "True", "TRUE", "false", "False", "FALSE")
"""How a boolean is written: the spellings YAML 1.1 (PyYAML) and YAML 1.2 both read as booleans."""


def yaml11_boolean(node):
    """The first scalar of the node tree ``node`` that PyYAML (YAML 1.1) reads as a boolean but
    YAML 1.2 as text (``yes``, ``no``, ``on``, ``off``, ``y``, ``n``), or None."""
    import yaml

    stack = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, yaml.ScalarNode):
            if item.tag == "tag:yaml.org,2002:bool" and item.value not in _BOOLEANS:
                return item
        elif isinstance(item, yaml.MappingNode):
            stack.extend(v for pair in reversed(item.value) for v in reversed(pair))
        elif isinstance(item, yaml.SequenceNode):
            stack.extend(reversed(item.value))
    return None


# --- small checks -------------------------------------------------------------------------------


def _mapping(where: _Where, path: tuple, value: Any, keys, required=()) -> Mapping:
    """``value``, a mapping of some of ``keys`` holding every key of ``required``."""
    if not isinstance(value, Mapping):
        raise where.error(path, f"must be a mapping with keys {list(keys)}, got {shorten(value)}")
    unknown = [k for k in value if str(k) not in keys]
    if unknown:
        word = str(unknown[0])
        hint = did_you_mean(word, keys) if len(word) <= 100 else ""
        raise where.error((*path, word), f"unknown key {shorten(unknown[0])}; allowed: {list(keys)}{hint}")
    missing = [k for k in required if k not in value]
    if missing:
        raise where.error(path, f"missing required key(s) {missing}")
    return value


def _real(where: _Where, path: tuple, value: Any, low: float, high: float, unit: str = "", *, open_ends="") -> float:
    """``value`` as a float in ``[low, high]`` (``open_ends``: ``"low"``, ``"high"`` or ``"both"``
    excluded), else an error at ``path``."""
    problem = range_problem(value, low, high, unit)
    if problem is None:
        x = float(value)
        if (x == low and open_ends in ("low", "both")) or (x == high and open_ends in ("high", "both")):
            left = "(" if open_ends in ("low", "both") else "["
            right = ")" if open_ends in ("high", "both") else "]"
            problem = f"must lie in {left}{low:g}, {high:g}{right}{' ' + unit if unit else ''}, got {x:g}"
    if problem:
        raise where.error(path, problem)
    return float(value)


def _whole(where: _Where, path: tuple, value: Any, low: int, high: int) -> int:
    problem = whole_problem(value, low, high)
    if problem:
        raise where.error(path, problem)
    return int(value)


def _choice(where: _Where, path: tuple, value: Any, choices) -> str:
    if not isinstance(value, str) or value not in choices:
        hint = did_you_mean(value, choices) if isinstance(value, str) and len(value) <= 100 else ""
        raise where.error(path, f"must be one of {list(choices)}, got {shorten(value)}{hint}")
    return value


# --- factors -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Range:
    """A range drawn from in a random design: uniform in ``[low, high]``, or in its logarithm."""

    low: float
    high: float
    log: bool
    whole: bool

    def draw(self, rng: np.random.Generator) -> float | int:
        if self.log:
            x = math.exp(rng.uniform(math.log(self.low), math.log(self.high)))
        else:
            x = rng.uniform(self.low, self.high)
        x = min(max(float(x), self.low), self.high)
        return int(round(x)) if self.whole else x


def _factor_value(where: _Where, path: tuple, name: str, value: Any) -> Any:
    """One value of the factor ``name``, checked against its kind and range."""
    if name in BOOL_FACTORS:
        if not isinstance(value, bool):
            raise where.error(path, f"must be true or false, got {shorten(value)}")
        return value
    if name in CHOICE_FACTORS:
        return _choice(where, path, value, CHOICE_FACTORS[name])
    if name in WHOLE_FACTORS:
        return _whole(where, path, value, *WHOLE_FACTORS[name])
    if name == "rate":
        return where.checked(path, lambda field: check_rate_range(value, field))
    low, high, unit, open_low = FACTOR_RANGES[name]
    return _real(where, path, value, low, high, unit, open_ends="low" if open_low else "")


def _factor_range(where: _Where, path: tuple, name: str, spec: Mapping, design: str) -> list | _Range:
    """The values of the range ``spec`` of factor ``name`` (grid), or the range to draw from (random)."""
    if name not in FACTOR_RANGES and name not in WHOLE_FACTORS:
        raise where.error(path, f"a range is for numeric factors only: give a value or a list, got {shorten(spec)}")
    _mapping(where, path, spec, RANGE_KEYS, ("from", "to"))
    low = _factor_value(where, (*path, "from"), name, spec["from"])
    high = _factor_value(where, (*path, "to"), name, spec["to"])
    spacing = _choice(where, (*path, "spacing"), spec.get("spacing", "linear"), SPACINGS)
    if spacing == "log" and low <= 0:
        raise where.error((*path, "from"), f"log spacing needs from > 0, got {shorten(low)}")
    whole = name in WHOLE_FACTORS
    if design == "random":
        if "count" in spec:
            raise where.error(
                (*path, "count"), "only in the grid design: a random design draws from a range without count"
            )
        if not low < high:
            raise where.error(path, f"needs from < to, got from {shorten(low)} and to {shorten(high)}")
        return _Range(float(low), float(high), spacing == "log", whole)
    if "count" not in spec:
        raise where.error(path, "missing required key 'count' (how many values the grid takes from the range)")
    count = _whole(where, (*path, "count"), spec["count"], *COUNT_RANGE)
    if count == 1 and low != high:
        raise where.error((*path, "count"), f"count 1 takes one value: needs from == to, got {low:g} and {high:g}")
    if count > 1 and not low < high:
        raise where.error(path, f"needs from < to, got from {shorten(low)} and to {shorten(high)}")
    spaced = np.geomspace(low, high, count) if spacing == "log" else np.linspace(low, high, count)
    values = [int(round(v)) for v in spaced] if whole else [float(v) for v in spaced]
    if len(set(values)) < len(values):
        raise where.error((*path, "count"), f"{count} whole numbers from {low} to {high} repeat a value: give fewer")
    return values


def _factor(where: _Where, name: str, spec: Any, design: str) -> list | _Range:
    """The values of the factor ``name`` as the file gives it (module docstring), or a range to
    draw from in a random design."""
    path = ("factors", name)
    if isinstance(spec, Mapping):
        return _factor_range(where, path, name, spec, design)
    if isinstance(spec, list):
        if not spec:
            raise where.error(path, "an empty list: give at least one value")
        values = [_factor_value(where, (*path, i), name, v) for i, v in enumerate(spec)]
        seen: dict[Any, int] = {}
        for i, v in enumerate(values):
            if v in seen:
                raise where.error((*path, i), f"{shorten(v)} appears twice (also item {seen[v]})")
            seen[v] = i
        return values
    return [_factor_value(where, path, name, spec)]


# --- robots --------------------------------------------------------------------------------------


def _robot_names(where: _Where, value: Any) -> list[str]:
    if not isinstance(value, list) or not value:
        raise where.error(("robots",), f"must be a non-empty list of preset names or robot files, got {shorten(value)}")
    if len(value) > MAX_ROBOTS:
        raise where.error(("robots",), f"at most {MAX_ROBOTS} robots in one study, got {len(value)}")
    seen: dict[str, int] = {}
    for i, name in enumerate(value):
        if not isinstance(name, str) or not name:
            raise where.error(("robots", i), f"must be a preset name or a robot file, got {shorten(name)}")
        if name in seen:
            raise where.error(("robots", i), f"{shorten(name)} appears twice (also robots[{seen[name]}])")
        seen[name] = i
    return list(value)


def _load_robots(where: _Where, names: list[str], base: Path, side: float, mode: str) -> dict[str, Robot]:
    """Each robot of ``names`` (presets, or files relative to ``base``), checked to have encoders
    and to drive the UMBmark square of ``side`` [m] and ``mode``."""
    robots: dict[str, Robot] = {}
    read: dict[str, Robot] = {}  # one read of each file, however many spellings name it
    for i, name in enumerate(names):
        path = ("robots", i)
        try:
            if is_preset_spec(name):
                robot = load_robot(name)
            else:
                file = os.path.join(base, name)
                if not os.path.lexists(file):  # False, not an OSError, for a name too long or with NUL
                    raise where.error(
                        path,
                        f"no preset of that name, nor a robot file {shorten(file)} (robot files are relative to "
                        f"the study file's folder){did_you_mean(name, PRESET_NAMES)}; got {shorten(name)}",
                    )
                real = os.path.realpath(file) if "\0" not in file else file
                robot = read[real] if real in read else load_robot(file)
                read[real] = robot
            encoded_wheels(robot)
        except (RobotFileError, InputError) as exc:
            raise where.error(path, str(exc)) from None
        refusal = square_refusal(robot, side, mode)
        if refusal:
            raise where.error(
                path, f"robot {robot.name!r} cannot drive the UMBmark square (side {side:g} m, mode {mode}): {refusal}"
            )
        robots[name] = robot
    return robots


# --- the study ------------------------------------------------------------------------------------


def _size_problem(counts: Mapping[str, int], robots: int) -> tuple[int, str]:
    """The number of points of a grid and how it comes about (``2 robots x 13 scale x ...``)."""
    total = robots * math.prod(counts.values())
    parts = [f"{robots} robot{'s' if robots != 1 else ''}"] + [f"{n} {name}" for name, n in counts.items() if n > 1]
    return total, " x ".join(parts)


def _check_size(where: _Where, path: tuple, points: int, how: str, trials: int) -> None:
    """Refuse a study of more than :data:`MAX_POINTS` points or :data:`MAX_TRIALS` trials."""
    if points > MAX_POINTS:
        raise where.error(path, f"{how} = {points} points, more than {MAX_POINTS}: give fewer values")
    if points * trials > MAX_TRIALS:
        raise where.error(
            ("trials",),
            f"{trials} trials x {points} points ({how}) = {points * trials} trials, more than {MAX_TRIALS}: "
            "give fewer trials or points",
        )


def _point(robot: str, hashes: Mapping[str, str], setting: Mapping[str, Any], square: Mapping[str, Any]) -> Point:
    values = dict(setting)
    if not engine_class(values["engine"]).has_noise_model:
        values["noise"] = None
    return Point(robot=robot, robot_hash=hashes[robot], **values, **square)


def _unique(points) -> tuple[Point, ...]:
    """``points`` without repeats, the first of each kept, in order."""
    return tuple(dict.fromkeys(points))


def parse_study(text: str, source: str, base: Path) -> Study:
    """The study the text of a study file describes (module docstring); ``source`` names the
    file in messages and gives the default name, ``base`` is the folder robot files are relative
    to (the study file's)."""
    import yaml

    data = parse_yaml(text, source, StudyFileError)
    tree = yaml.compose(text, Loader=strict_yaml_loader()) if data is not None else None
    where = _Where(source, key_lines(tree) if tree is not None else {})
    if tree is not None:
        boolean = yaml11_boolean(tree)
        if boolean is not None:
            mark = boolean.start_mark
            raise StudyFileError(
                f"{source}: line {mark.line + 1} column {mark.column + 1}: {shorten(boolean.value)} is a boolean in "
                "YAML 1.1 but text in YAML 1.2: write true or false (text in quotes)",
                line=mark.line + 1,
            )
    if data is None:
        raise where.error((), "empty: a study file needs at least omnikin_sweep: 1, robots, seed and trials")
    if not isinstance(data, Mapping):
        raise where.error((), f"a study file must be a mapping at top level, got {type(data).__name__}")
    _mapping(where, (), data, TOP_KEYS, [k for k, required in TOP_KEYS.items() if required])

    version = data["omnikin_sweep"]
    if isinstance(version, bool) or version != SCHEMA_VERSION:
        raise where.error(
            ("omnikin_sweep",),
            f"unsupported schema version {shorten(version)}; this omnikin reads version {SCHEMA_VERSION}",
        )
    name = data.get("name", Path(source).stem)
    problem = robot_name_problem(name)
    if problem:
        raise where.error(("name",), problem)
    seed = _whole(where, ("seed",), data["seed"], *SEED_RANGE)
    trials = _whole(where, ("trials",), data["trials"], *TRIALS_RANGE)
    design = _choice(where, ("design",), data.get("design", "grid"), DESIGNS)
    draws = 0
    if design == "random":
        if "points" not in data:
            raise where.error(("points",), "required in the random design: how many settings to draw", at=("design",))
        draws = _whole(where, ("points",), data["points"], *POINTS_RANGE)
    elif "points" in data:
        raise where.error(("points",), "only in the random design (a grid runs every combination of the factors)")

    question = _mapping(where, ("question",), data.get("question", {}), QUESTION_KEYS)
    target_mm = _real(
        where, ("question", "target_mm"), question.get("target_mm", 10), *TARGET_MM_RANGE, "mm", open_ends="low"
    )
    quantile = _real(where, ("question", "quantile"), question.get("quantile", 0.95), 0.0, 1.0, open_ends="both")
    level = _real(where, ("question", "level"), question.get("level", 0.95), 0.0, 1.0, open_ends="both")

    umbmark = _mapping(where, ("umbmark",), data.get("umbmark", {}), UMBMARK_KEYS)
    side_value = umbmark.get("side", DEFAULTS["side"])
    side = where.checked(("umbmark", "side"), lambda field: check_side(side_value, field))
    mode_value = umbmark.get("mode", DEFAULTS["mode"])
    mode = where.checked(("umbmark", "mode"), lambda field: check_mode(mode_value))
    runs = _whole(where, ("umbmark", "runs"), umbmark.get("runs", DEFAULTS["runs"]), *RUNS_RANGE)
    square = {"side": side, "mode": mode, "runs": runs}

    given = _mapping(where, ("factors",), data.get("factors", {}), FACTORS)
    factors: dict[str, list | _Range] = {
        name: _factor(where, name, given[name], design) if name in given else [DEFAULTS[name]] for name in FACTORS
    }
    engines = factors["engine"]
    if "noise" in given and isinstance(engines, list) and not any(engine_class(e).has_noise_model for e in engines):
        raise where.error(
            ("factors", "noise"),
            "every point runs the physics engine, which has no random error model (slip comes from the "
            "wheels' roller contact, its encoders count whole ticks): drop noise",
        )

    robot_names = _robot_names(where, data["robots"])
    if design == "grid":
        counts = {name: len(values) for name, values in factors.items() if isinstance(values, list)}
        total, how = _size_problem(counts, len(robot_names))
        _check_size(where, ("factors",), total, f"the grid has {how}", trials)
    else:
        total, how = _size_problem({"points": draws}, len(robot_names))
        _check_size(where, ("points",), total, how, trials)

    robots = _load_robots(where, robot_names, base, side, mode)
    hashes = {name: robot_hash(robot) for name, robot in robots.items()}
    if design == "grid":
        grids = [factors[name] for name in FACTORS]
        settings = [dict(zip(FACTORS, values, strict=True)) for values in itertools.product(*grids)]  # type: ignore[arg-type]
    else:
        settings = _draw_settings(factors, draws, seed)
    points = _unique(_point(robot, hashes, setting, square) for robot in robot_names for setting in settings)

    digest = _digest(
        canonical_json(
            {
                "points": [p.as_dict() for p in points],
                "trials": trials,
                "seed": seed,
                "target": target_mm / 1000.0,
                "quantile": quantile,
                "level": level,
                "design": design,
            }
        )
    )
    return Study(
        source=source,
        name=name,
        seed=seed,
        trials=trials,
        design=design,
        points=points,
        robots=robots,
        target=target_mm / 1000.0,
        quantile=quantile,
        level=level,
        digest=digest,
    )


def _draw_settings(factors: Mapping[str, list | _Range], count: int, seed: int) -> list[dict[str, Any]]:
    """``count`` settings of a random design (module docstring: setting after setting, the factors
    in field order, a list or range drawing one number each, a single value none)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0,)))
    settings = []
    for _ in range(count):
        setting: dict[str, Any] = {}
        for name in FACTORS:
            spec = factors[name]
            if isinstance(spec, _Range):
                setting[name] = spec.draw(rng)
            elif len(spec) == 1:
                setting[name] = spec[0]
            else:
                setting[name] = spec[int(rng.integers(len(spec)))]
        settings.append(setting)
    return settings


def load_study(path: str | Path) -> Study:
    """The study of the study file ``path`` (module docstring); only a regular UTF-8 file of at
    most 256 KiB is read (:func:`~omnikin.io.textfile.read_text`)."""
    text = read_text(path, StudyFileError, what="a study file")
    return parse_study(text, str(path), Path(path).parent)
