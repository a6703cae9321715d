"""What ``omnikin view --replay`` plays: the runs of an UMBmark report or of a ROS 2 bag.

- **A report folder** of ``omnikin umbmark`` (:func:`load_report`): the robot as built
  (``true_robot.yaml``: the robot that drove the runs), the square's side (``result.json``,
  ``settings.side``) and the runs of ``run_poses.csv`` (:mod:`omnikin.io.run_poses`), one
  :class:`~omnikin.viewer.replay.Track` per run, named ``before cw run 1``. The robot it was
  built to (``result.json``'s ``robot``, same wheel names) is its design
  (:attr:`omnikin.kinematics.robot.Robot.design`): the page draws the robot as built with the body of its
  design (:func:`omnikin.physics.description.describe`), as the physics engine models it; a
  robot file holds no design, so without it a few millimetres of hub errors would draw
  another body.
- **A bag** (:func:`load_bag`: a rosbag2 folder, a ``.db3`` or ``.mcap`` file, as
  :mod:`omnikin.io.bags` reads them) of a robot the caller names: one track from the
  ``nav_msgs/Odometry`` (or ``PoseStamped``) topics of the ground truth (default
  ``/ground_truth``) and of the odometry (default ``/odom``), and the measured wheel angles and
  steering of ``sensor_msgs/JointState`` (default ``/joint_states``; joint name = wheel name,
  ``W_steer`` for steering) when the bag has that topic. Times are header stamps, from the
  earliest of the topics. A bag with only one of the two pose topics at their default names is
  played with that one for both (:attr:`ReplaySource.notes` says so); a bag with neither, or
  without a topic the user named, is refused, naming the topics it has.

:func:`load_replay` tells the two apart; :func:`combine` puts the runs of several (reports,
bags) on one page. Every problem is one line naming the file (and the line or topic):
:class:`ReplayError` or the reader's own error.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..common.messages import one_line, shorten
from ..errors import BagError, InputError, ReplayError
from ..kinematics.robot import Robot
from .replay import JointSeries, PoseSeries, Track

REPORT_FILES = ("true_robot.yaml", "result.json", "run_poses.csv")
BAG_TOPICS = {"ground_truth": "/ground_truth", "odom": "/odom", "joint_states": "/joint_states"}
"""The topics a bag is replayed from, by role (``omnikin simulate --bag`` writes these)."""
MAX_RESULT_BYTES = 1 << 22
"""Largest ``result.json`` read [bytes] (a report's is some 20 KB)."""


def shown(path) -> str:
    """A path as an error message names it: on one line, at most 200 characters."""
    return one_line(path, 200)


@dataclass(frozen=True)
class ReplaySource:
    """The robot that drove the runs, the tracks, the UMBmark square's side [m] (None: not a
    UMBmark run) and ``notes``: lines to tell the user (a topic missing from a bag)."""

    label: str
    robot: Robot
    tracks: list[Track]
    side: float | None = None
    notes: list[str] = field(default_factory=list)


def is_report(path) -> bool:
    """A folder holding ``result.json`` or ``run_poses.csv``: an UMBmark report."""
    p = Path(path)
    return p.is_dir() and any((p / name).exists() for name in ("result.json", "run_poses.csv"))


def load_report(folder) -> ReplaySource:
    """The report folder ``folder`` as a :class:`ReplaySource` (module docstring)."""
    from ..evaluation.umbmark import check_side
    from ..io.robot_file import load_robot
    from ..io.run_poses import read_run_poses
    from ..io.textfile import read_text

    base = Path(folder)
    if not base.is_dir():
        raise ReplayError(f"{one_line(folder, 300)}: not a folder (expected an omnikin umbmark report folder)")
    missing = [name for name in REPORT_FILES if not (base / name).exists()]
    if missing:
        why = (
            "; reports of omnikin before run_poses.csv have no runs to replay: run omnikin umbmark again"
            if missing == ["run_poses.csv"]
            else ""
        )
        raise ReplayError(f"{shown(folder)}: an omnikin umbmark report needs {', '.join(missing)}, not found{why}")
    robot = load_robot(base / "true_robot.yaml")
    result = base / "result.json"
    text = read_text(result, ReplayError, what="a result.json", max_bytes=MAX_RESULT_BYTES)
    try:
        doc = json.loads(text)
    except ValueError as exc:
        raise ReplayError(f"{result}: not JSON ({one_line(exc)})") from None
    if isinstance(doc, dict) and isinstance(doc.get("settings"), dict):
        side = doc["settings"].get("side")
    else:
        side = None
    if isinstance(side, bool) or not isinstance(side, (int, float)) or not math.isfinite(side):
        raise ReplayError(f"{result}: settings.side is {shorten(side)}, expected the square's side [m]")
    try:
        check_side(float(side))
    except InputError as exc:
        raise ReplayError(f"{result}: settings.side: {exc}") from None
    robot = with_design(robot, doc.get("robot") if isinstance(doc, dict) else None, result)
    tracks = []
    for run in read_run_poses(base / "run_poses.csv"):
        tracks.append(Track(run.name, PoseSeries(run.t, run.truth), PoseSeries(run.t, run.odometry)))
    return ReplaySource(str(folder), robot, tracks, float(side))


def with_design(robot: Robot, design, source: Path) -> Robot:
    """``robot`` (as built) with ``design``, a robot document (``result.json``'s ``robot``), as
    its design when that has the same wheel names (module docstring); ``robot`` as it is when
    ``design`` is None (no such entry), names other wheels, or ``robot`` has a design already.
    A document that is not a robot is one line naming ``source``."""
    from ..io.robot_file import robot_from_dict

    if design is None or robot.design is not None:
        return robot
    try:
        nominal = robot_from_dict(design, f"{source}: robot")
    except InputError as exc:
        raise ReplayError(one_line(exc, 400)) from None
    if nominal.design is not None or nominal.wheel_names != robot.wheel_names:
        return robot
    return replace(robot, design=nominal)


def load_bag(
    bag,
    robot: Robot,
    topics: dict | None = None,
    *,
    required: tuple[str, ...] = (),
    max_messages: int | None = None,
    max_message_bytes: int | None = None,
) -> ReplaySource:
    """The bag ``bag`` of ``robot`` as a :class:`ReplaySource` of one track (module
    docstring); ``topics`` renames the roles of :data:`BAG_TOPICS`; a role in ``required``
    (a topic the user named) must be in the bag; ``max_messages`` and ``max_message_bytes``
    bound what is read per topic (:mod:`omnikin.io.bags`)."""
    from ..io.bags import read_joint_states, read_poses, topic_types

    names = dict(BAG_TOPICS, **(topics or {}))
    unknown = sorted(set(names) - set(BAG_TOPICS))
    if unknown:
        raise ReplayError(f"unknown bag topic role(s) {unknown}; roles are {sorted(BAG_TOPICS)}")
    present = topic_types(bag)
    have = ", ".join(f"{t} ({present[t]})" for t in sorted(present)) or "no topics"
    truth_topic, odom_topic = names["ground_truth"], names["odom"]
    for role in required:
        if names[role] not in present:
            raise ReplayError(
                f"{shown(bag)}: no topic {shorten(names[role])} ({role.replace('_', ' ')}); "
                f"the bag has: {one_line(have, 500)}"
            )
    if truth_topic not in present and odom_topic not in present:
        raise ReplayError(
            f"{shown(bag)}: no ground truth topic {truth_topic} and no odometry topic {odom_topic} to replay "
            f"(--ground-truth-topic, --odom-topic); the bag has: {one_line(have, 500)}"
        )
    notes = []
    truth, odom = (
        read_poses(bag, topic, max_messages=max_messages, max_message_bytes=max_message_bytes)
        if topic in present
        else None
        for topic in (truth_topic, odom_topic)
    )
    if truth is None:
        notes.append(
            f"{shown(bag)}: no ground truth topic {truth_topic}: the robot is drawn at its odometry {odom_topic}"
        )
    if odom is None:
        notes.append(
            f"{shown(bag)}: no odometry topic {odom_topic}: the odometry shown is the ground truth {truth_topic}"
        )
    joints = None
    if names["joint_states"] in present:
        joints = read_joint_states(
            bag,
            robot,
            names["joint_states"],
            stamp="header",
            max_messages=max_messages,
            max_message_bytes=max_message_bytes,
        )
    else:
        notes.append(
            f"{shown(bag)}: no joint states topic {names['joint_states']}: wheel angles and steering from the "
            "kinematics"
        )
    first_truth = truth if truth is not None else odom
    first_odom = odom if odom is not None else truth
    assert first_truth is not None and first_odom is not None
    starts = [int(first_truth.stamps[0]), int(first_odom.stamps[0])] + ([int(joints.stamps[0])] if joints else [])
    t0 = min(starts)

    def series(track, topic) -> PoseSeries:
        try:
            return PoseSeries((track.stamps - t0) * 1e-9, track.poses)
        except InputError as exc:
            raise BagError(f"{shown(bag)}: topic {topic!r}: {exc}") from None

    joint_series = None
    if joints is not None:
        joint_series = JointSeries(
            (joints.stamps - t0) * 1e-9,
            tuple(joints.wheel_names),
            joints.angles,
            tuple(robot.steer_names) if joints.steer is not None else (),
            joints.steer,
        )
    track = Track(
        Path(bag).name or str(bag),
        series(first_truth, first_truth.topic),
        series(first_odom, first_odom.topic),
        joint_series,
        missing=tuple(role for role, got in (("truth", truth), ("odometry", odom)) if got is None),
    )
    return ReplaySource(str(bag), robot, [track], None, notes)


def load_replay(path, robot: Robot | None, topics: dict | None = None, **options) -> ReplaySource:
    """A report folder (``robot`` must be None: the report names its robot) or a bag of
    ``robot`` (required), as :class:`ReplaySource`; ``options`` those of :func:`load_bag`."""
    if is_report(path):
        if robot is not None:
            raise ReplayError(
                f"{shown(path)}: an UMBmark report names its robot (true_robot.yaml, the robot as built): "
                "give no ROBOT with --replay REPORT_DIR"
            )
        return load_report(path)
    p = Path(path)
    if not p.exists():
        raise ReplayError(
            f"{one_line(path, 300)}: no such report folder or bag (an omnikin umbmark report folder, a rosbag2 "
            "folder, a .db3 or .mcap file)"
        )
    if p.is_dir() and not (p / "metadata.yaml").exists():
        raise ReplayError(
            f"{shown(path)}: neither an omnikin umbmark report folder (result.json, run_poses.csv) nor a ROS 2 bag "
            "(a folder with metadata.yaml, a .db3 or .mcap file)"
        )
    if robot is None:
        raise ReplayError(
            f"{shown(path)}: a bag does not say which robot drove it: give ROBOT (omnikin view ROBOT --replay BAG)"
        )
    return load_bag(path, robot, topics, **options)


def wheels_of(robot: Robot) -> list[tuple[str, str]]:
    """The robot's wheels as ``(name, type)`` in file order: what must agree for runs of two
    robots to be drawn by one drawing."""
    return [(w.name, w.type) for w in robot.wheels]


def combine(sources: Sequence[ReplaySource]) -> ReplaySource:
    """The runs of ``sources`` (``omnikin view --replay A --replay B``: before and after, two
    reports, two bags) as one :class:`ReplaySource`: every track keeps the robot that drove it
    (:attr:`~omnikin.viewer.replay.Track.robot`), and with more than one source its name is
    prefixed by its file's name (``after: before cw run 1``; a bag's track is named after its
    file already), numbered when two are alike. The robots must have the same wheels (names
    and types, in order; as-built sizes may differ): else one line names both. The UMBmark
    square is the first report's."""
    if len(sources) == 1:
        return sources[0]
    first = sources[0]
    tracks: list[Track] = []
    names: set[str] = set()
    for source in sources:
        if wheels_of(source.robot) != wheels_of(first.robot):

            def listed(src: ReplaySource) -> str:
                wheels = wheels_of(src.robot)
                return f"{shorten(src.robot.name)} with {len(wheels)} wheels {shorten([n for n, _ in wheels])}"

            raise ReplayError(
                f"{shown(source.label)}: its runs are of {listed(source)}, those of {shown(first.label)} of "
                f"{listed(first)}: runs shown together must be of one robot"
            )
        prefix = Path(source.label).name or source.label
        for track in source.tracks:
            name = track.name if track.name == prefix else f"{prefix}: {track.name}"
            base, k = name, 2
            while name in names:
                name, k = f"{base} ({k})", k + 1
            names.add(name)
            tracks.append(replace(track, name=name, robot=track.robot or source.robot))
    sides = [s.side for s in sources if s.side is not None]
    return ReplaySource(
        ", ".join(s.label for s in sources),
        first.robot,
        tracks,
        sides[0] if sides else None,
        [note for s in sources for note in s.notes],
    )
