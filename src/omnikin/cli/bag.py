"""``omnikin bag odometry``, ``omnikin bag export``, ``omnikin simulate`` and ``omnikin metrics``.

Bags are ROS 2 bags (rosbag2 directories with sqlite3 or MCAP storage, or a bare ``.mcap`` /
``.db3`` file), read and written with the ``rosbags`` package (``pip install "omnikin[bags]"``);
see :mod:`omnikin.io.bags`. Metrics are those of :mod:`omnikin.evaluation.metrics` (evo's ATE and
RPE, in the plane).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys

import numpy as np

from ..common.messages import shorten
from ..errors import InfeasibleTwistError, InputError, OmnikinError
from ..kinematics.se2 import wrap_angle
from ..physics.engines import ENGINE_NAMES
from .budget import Budget, add_budget_options, explained, require
from .common import (
    add_as_built_options,
    add_method_option,
    add_output,
    add_output_options,
    add_step_option,
    add_wheel_bound_options,
    check_seed,
    console,
    declare_inputs,
    engine_of,
    load_robot,
    number,
    physics_hint,
    print_json,
    robot_as_built,
    whole,
)

# Measured costs of the bag commands (rosbags 0.11, CPython 3.11, tracemalloc peaks of 67,000-sample
# runs of mecanum4): memory rounded up; times on the fast side (measured 25 us per message written,
# 27 us read on a loaded 2-core machine), so that only clearly oversized jobs are refused.
JOINT_STATE_BYTES = 400
"""bag odometry: per JointState message read, its odometry and the Odometry written (measured 303)."""
POSE_BYTES = 600
"""bag export: per pose message read and its line of text (measured 545)."""
MESSAGE_SECONDS = 10e-6
"""Reading (deserializing) or writing (serializing) one message."""
SIM_SAMPLE_SECONDS = 4 * MESSAGE_SECONDS
"""simulate --bag: per sample, its four messages made and written (the simulation itself, and the
memory of it all: :func:`omnikin.simulation.simulate.run_cost`)."""
LOG_ROW_SECONDS = 5e-6
"""simulate --log: per sample, its row of the tick log made and written (measured 19 us)."""
PROGRESS_AFTER = 3.0
"""simulate --engine physics shows its progress once a run has taken this long [s]."""
LARGEST_MESSAGE_SHARE = 64
"""One message may use at most 1/64 of --max-memory (its bytes decoded into Python objects)."""

BAG_EPILOG = """examples:
  omnikin bag odometry tomasi-omni3 run.bag -o odom.bag
  omnikin bag odometry my_robot.yaml run.mcap -o odom.bag --joint-states-topic /wheels/joint_states \\
      --odom-topic /wheel_odom --method exact --storage mcap
  omnikin bag export odom.bag --topic /odom --format tum -o odom.tum
  omnikin bag export sim.bag --topic /ground_truth --format kitti > truth.kitti

joint names = wheel names of the robot file (positions in rad, positive drives the hub along
its drive direction); a steerable wheel W needs a joint W_steer [rad]. Output: nav_msgs/Odometry
in frame 'odom' with child 'base_link' (REP-105), twist in body axes (REP-103)."""

SIMULATE_EPILOG = """examples:
  omnikin simulate tomasi-omni3 --bag sim.bag
  omnikin simulate tomasi-omni3 --log log.csv && omnikin odometry tomasi-omni3 log.csv -o traj.csv
  omnikin simulate diff-drive --path 'square ccw rotate 2' --errors none --noise none --bag sim.bag
  omnikin simulate mecanum4 --path 'line 2 90; spin 180; arc 1 90' --rate 50 --seed 7 --bag sim.bag
  omnikin bag export sim.bag --topic /ground_truth --format tum -o truth.tum
  omnikin simulate tomasi-omni3 --engine physics --errors none --path 'line 1' --log log.csv

engines: kinematic (default) integrates the wheels' motion with the --errors and --noise models;
physics drives the robot as built (--errors or --true-robot) in MuJoCo with real rollers, motors
and contacts (extra physics, docs/physics.md): the same plan and limits, wheel speeds commanded at
--rate, the run sampled on until the robot stops; it has no --noise model (slip comes from the
contacts) and takes --step, its time step.

paths (';' chains several): 'square cw|ccw rotate|translate [SIDE]', 'line LENGTH [HEADING_DEG]',
'spin ANGLE_DEG', 'arc RADIUS ANGLE_DEG'. Topics: /ground_truth and /odom (nav_msgs/Odometry),
/joint_states (sensor_msgs/JointState, wheel angles [rad]), /cmd_vel (geometry_msgs/Twist)."""

METRICS_EPILOG = """examples:
  omnikin metrics truth.tum odom.tum
  omnikin metrics truth.tum odom.tum --align --delta 10 --json
  omnikin metrics truth.tum odom.csv --t-max-diff 0.02 --t-offset 0.005

files: TUM (t x y z qx qy qz qw), KITTI (12 numbers per line; pose k at t = k) or CSV
(header t,x,y,theta), detected from the first line. ATE: translation error after optional SE(2)
alignment (Umeyama without scale); RPE: over DELTA frames of the associated poses,
non-overlapping pairs unless --all-pairs. Same definitions as evo_ape / evo_rpe (--pose_relation
trans_part, --delta N --delta_unit f)."""


def add_parsers(sub, robot_help: str) -> None:
    """Add ``bag`` (with ``odometry`` and ``export``), ``simulate`` and ``metrics`` to ``sub``."""
    bag = sub.add_parser(
        "bag",
        help="ROS 2 bags: wheel odometry from joint states, export of pose topics",
        description="Work with ROS 2 bags (rosbag2: sqlite3 or MCAP); needs the rosbags package "
        '(pip install "omnikin[bags]").',
        epilog=BAG_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    bag.set_defaults(func=cmd_bag_help, bag_parser=bag)
    bsub = bag.add_subparsers(dest="bag_command", metavar="SUBCOMMAND")

    sp = bsub.add_parser(
        "odometry",
        help="sensor_msgs/JointState wheel angles -> nav_msgs/Odometry in a new bag",
        description="Read the wheel angles of ROBOT from a JointState topic (joint name = wheel "
        "name, rad), integrate them exactly on SE(2) and write nav_msgs/Odometry to a "
        "new bag (one message per input sample, same stamps).",
        epilog=BAG_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument("bag", metavar="IN.bag", help="input bag (directory, .db3 or .mcap)")
    add_output(
        sp,
        "-o",
        "--output",
        folder="data",
        required=True,
        metavar="OUT.bag",
        help="new bag to write (a new name; --force replaces a bag omnikin wrote)",
    )
    sp.add_argument(
        "--joint-states-topic",
        default="/joint_states",
        metavar="TOPIC",
        help="sensor_msgs/JointState topic (default /joint_states)",
    )
    sp.add_argument("--odom-topic", default="/odom", metavar="TOPIC", help="output topic (default /odom)")
    add_method_option(sp)
    add_wheel_bound_options(sp, angles=True)
    sp.add_argument(
        "--stamp",
        choices=("auto", "header", "bag"),
        default="auto",
        help="sample times: header stamps, bag record times, or auto (header unless all zero)",
    )
    sp.add_argument("--frame-id", default="odom", metavar="FRAME", help="header.frame_id (default odom)")
    sp.add_argument("--child-frame-id", default="base_link", metavar="FRAME", help="child_frame_id (default base_link)")
    sp.add_argument(
        "--pose-cov-diag",
        type=number,
        nargs=6,
        metavar="V",
        help="pose covariance diagonal (x y z roll pitch yaw) [m^2, rad^2]; default zeros",
    )
    sp.add_argument(
        "--twist-cov-diag",
        type=number,
        nargs=6,
        metavar="V",
        help="twist covariance diagonal (vx vy vz wx wy wz); default zeros",
    )
    sp.add_argument(
        "--storage", choices=("sqlite3", "mcap"), default="sqlite3", help="output storage (default sqlite3)"
    )
    sp.add_argument("--json", action="store_true", help="print a JSON summary")
    add_output_options(sp)
    add_budget_options(sp)
    declare_inputs(sp, "bag", robots=("robot",))
    sp.set_defaults(func=cmd_bag_odometry)

    sp = bsub.add_parser(
        "export",
        help="export a nav_msgs/Odometry or geometry_msgs/PoseStamped topic",
        description="Write the planar poses (x, y, yaw) of an Odometry or PoseStamped topic as TUM "
        "(t x y z qx qy qz qw), KITTI (3x4 row-major [R|t], no times) or CSV "
        "(t,x,y,theta); times are the header stamps.",
        epilog=BAG_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("bag", metavar="IN.bag", help="input bag (directory, .db3 or .mcap)")
    sp.add_argument("--topic", required=True, metavar="TOPIC", help="nav_msgs/Odometry or geometry_msgs/PoseStamped")
    sp.add_argument("--format", required=True, choices=("tum", "kitti", "csv"), help="output format")
    add_output(sp, "-o", "--output", metavar="FILE", default="-", help="file to write (default '-': standard output)")
    add_output_options(sp)
    add_budget_options(sp)
    declare_inputs(sp, "bag")
    sp.set_defaults(func=cmd_bag_export)

    from ..motion.timing import RATE_RANGE
    from ..simulation.error_models import NOISE

    sp = sub.add_parser(
        "simulate",
        help="simulate a run and record it to a ROS 2 bag",
        description="Simulate ROBOT as built (systematic --errors, random --noise) driving a path "
        "commanded by its nominal model, and record ground truth, odometry, wheel "
        "joint states and cmd_vel to a new bag and/or the encoder tick log.",
        epilog=SIMULATE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument(
        "--path",
        default="square cw rotate 4",
        metavar="PATH",
        help="the path (see below; default 'square cw rotate 4')",
    )
    add_as_built_options(sp)
    sp.add_argument(
        "--noise",
        metavar="PROFILE",
        help=f"random errors: {', '.join(sorted(NOISE))} (default typical; kinematic engine only)",
    )
    sp.add_argument(
        "--engine",
        choices=ENGINE_NAMES,
        default="kinematic",
        help="kinematic: wheel motion and error models; physics: MuJoCo with rollers and motors "
        "(extra physics; see below) (default kinematic)",
    )
    add_step_option(sp)
    sp.add_argument(
        "--rate",
        type=number,
        default=100.0,
        metavar="HZ",
        help=f"sample rate of all topics, {RATE_RANGE[0]:g} to {RATE_RANGE[1]:g} Hz (default 100)",
    )
    sp.add_argument(
        "--start",
        type=number,
        default=0.0,
        metavar="SEC",
        help="stamp of the first sample [s] (default 0); a bag stamps 0 to 2147483647 s (ROS 2 time), and "
        "the stamps must stay distinct at --rate",
    )
    add_output(
        sp,
        "--bag",
        folder="data",
        metavar="OUT.bag",
        help="new bag to write (a new name; --force replaces a bag omnikin wrote)",
    )
    add_output(
        sp,
        "--log",
        metavar="LOG.csv",
        help="also (or only) write the encoder tick log, the input of 'omnikin odometry'",
    )
    sp.add_argument("--storage", choices=("sqlite3", "mcap"), default="sqlite3", help="bag storage (default sqlite3)")
    sp.add_argument("--json", action="store_true", help="print a JSON summary")
    add_output_options(sp)
    add_budget_options(sp)
    declare_inputs(sp, robots=("robot", "true_robot"))
    sp.set_defaults(func=cmd_simulate)

    sp = sub.add_parser(
        "metrics",
        help="ATE and RPE of an estimated trajectory against a reference",
        description="Absolute trajectory error (translation, optionally after SE(2) alignment) "
        "and relative pose error (translation and rotation over DELTA frames) of EST "
        "against REF, after associating their timestamps.",
        epilog=METRICS_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("ref", metavar="REF", help="reference trajectory (TUM, KITTI or CSV)")
    sp.add_argument("est", metavar="EST", help="estimated trajectory (TUM, KITTI or CSV)")
    sp.add_argument("--align", action="store_true", help="align EST to REF by SE(2) least squares before the ATE")
    sp.add_argument("--delta", type=whole, default=1, metavar="N", help="RPE pose distance in frames (default 1)")
    sp.add_argument("--all-pairs", action="store_true", help="RPE over all pairs (i, i+N), not only consecutive")
    sp.add_argument(
        "--t-max-diff",
        type=number,
        default=0.01,
        metavar="SEC",
        help="largest time difference of associated poses [s] (default 0.01)",
    )
    sp.add_argument(
        "--t-offset",
        type=number,
        default=0.0,
        metavar="SEC",
        help="time offset added to EST's timestamps [s] (default 0)",
    )
    sp.add_argument("--json", action="store_true", help="print JSON (rotation in rad and in deg)")
    add_budget_options(sp, time=False)
    sp.set_defaults(func=cmd_metrics)


# --- helpers ------------------------------------------------------------------------------------------
def _covariance(diag):
    return None if diag is None else np.asarray(diag, dtype=float)


# --- bag ----------------------------------------------------------------------------------------------
def cmd_bag_help(args) -> int:
    raise InputError("bag: give a sub-command, 'odometry' or 'export' (omnikin bag -h)")


def _read_bounds(args, bytes_each: float) -> dict:
    """The reader bounds that follow from ``--max-memory``: messages held, bytes of one message."""
    budget = Budget.of(args)
    return {
        "max_messages": budget.messages(bytes_each),
        "max_message_bytes": int(budget.memory // LARGEST_MESSAGE_SHARE),
    }


def _size_bag_job(args, what: str, bag, topic: str, bytes_each: float, hint: str) -> None:
    """Refuse a bag job over budget from the message count the bag declares."""
    from ..io.bags import message_count

    count = message_count(bag, topic)
    require(
        args, what, memory=count * bytes_each, seconds=count * 2 * MESSAGE_SECONDS, size=f"{count} messages", hint=hint
    )


def cmd_bag_odometry(args) -> int:
    from ..io.bags import bag_odometry, check_frame_ids, check_topic, require_rosbags

    require_rosbags()
    robot = load_robot(args.robot)
    for name, diag in (("--pose-cov-diag", args.pose_cov_diag), ("--twist-cov-diag", args.twist_cov_diag)):
        if diag is not None and not all(math.isfinite(v) and v >= 0 for v in diag):
            raise InputError(f"{name}: variances must be finite and >= 0, got {diag}")
    check_topic(args.joint_states_topic, "--joint-states-topic")
    check_topic(args.odom_topic, "--odom-topic")
    check_frame_ids(args.frame_id, args.child_frame_id, ("--frame-id", "--child-frame-id"))
    _size_bag_job(
        args,
        "bag odometry",
        args.bag,
        args.joint_states_topic,
        JOINT_STATE_BYTES,
        hint="split the bag (ros2 bag convert)",
    )
    with explained(args):
        res = bag_odometry(
            robot,
            args.bag,
            args.output,
            joint_states_topic=args.joint_states_topic,
            odom_topic=args.odom_topic,
            method=args.method,
            max_wheel_speed=args.max_wheel_speed,
            max_wheel_accel=args.max_wheel_accel,
            stamp=args.stamp,
            frame_id=args.frame_id,
            child_frame_id=args.child_frame_id,
            pose_covariance=_covariance(args.pose_cov_diag),
            twist_covariance=_covariance(args.twist_cov_diag),
            storage=args.storage,
            force=args.force,
            **_read_bounds(args, JOINT_STATE_BYTES),
        )
    s = res.summary()
    s.update(robot=robot.name, method=args.method)
    if args.json:
        print_json(s)
        return 0
    end = s["final_pose"]
    notes = []
    if s["skipped_messages"]:
        notes.append(f"{s['skipped_messages']} message(s) without the wheel joints skipped")
    if s["duplicates_dropped"]:
        notes.append(f"{s['duplicates_dropped']} exact repeat(s) dropped")
    console(120).print(
        f"{robot.name}: {s['samples']} joint-state samples on {args.joint_states_topic} over {s['duration']:.6g} s "
        f"({s['stamp_source']} stamps), {args.method} integration\n"
        f"final pose x={end[0]:.6g} m, y={end[1]:.6g} m, theta={end[2]:.6g} rad; path {s['path_length']:.6g} m\n"
        f"nav_msgs/Odometry on {args.odom_topic} written to {args.output}"
        + (f"\nnote: {'; '.join(notes)}" if notes else "")
    )
    return 0


def cmd_bag_export(args) -> int:
    from ..io.bags import check_topic, export_poses, require_rosbags

    require_rosbags()
    check_topic(args.topic, "--topic")
    _size_bag_job(args, "bag export", args.bag, args.topic, POSE_BYTES, hint="split the bag (ros2 bag convert)")
    with explained(args):
        track = export_poses(
            args.bag, args.topic, args.format, args.output, force=args.force, **_read_bounds(args, POSE_BYTES)
        )
    console(120).print(
        f"{len(track.poses)} poses of {args.topic} ({track.msgtype}, frame "
        f"{track.frame_id!r}) written to {args.output} ({args.format})"
    )
    return 0


# --- simulate ----------------------------------------------------------------------------------------
def parse_paths(text: str):
    """A plan from one or more ``;``-separated paths of the runs-file grammar
    (:func:`omnikin.io.runs.path_plan`: plain numbers)."""
    from ..io.runs import path_plan
    from ..motion.plans import PATH_BLANKS

    parts = [p.strip(PATH_BLANKS) for p in text.split(";")]
    if not any(parts):
        raise InputError("--path: empty path")
    plan = None
    for part in parts:
        if not part:
            raise InputError(f"--path {shorten(text)}: empty part between ';'")
        try:
            p = path_plan(part)
        except OmnikinError as exc:
            raise InputError(f"--path: {exc}") from None
        plan = p if plan is None else plan + p
    return plan


@contextlib.contextmanager
def _drivable(args):
    """A path the robot cannot drive (:class:`~omnikin.errors.InfeasibleTwistError`) as one line
    naming ``--path``."""
    try:
        yield
    except InfeasibleTwistError as exc:
        raise InputError(f"--path {shorten(args.path)}: {exc.detail}; choose a path this robot can drive") from None


def cmd_simulate(args) -> int:
    from ..io.bags import record_run, require_rosbags
    from ..motion.timing import check_rate_range

    if args.bag is None and args.log is None:
        raise InputError("simulate: give --bag OUT.bag and/or --log LOG.csv")
    engine = _engine_options(args)
    if args.bag is not None:
        require_rosbags()
    robot = load_robot(args.robot)
    if args.log is not None and engine.has_noise_model:
        _check_tick_log(args, robot)
    check_seed(args.seed)
    check_rate_range(args.rate, "--rate")
    plan = parse_paths(args.path)
    noise = engine.noise_model(args.noise)
    cost = engine.cost(plan, robot, robot, rate=args.rate, timed=False)  # the plan's samples and memory
    seeds = np.random.SeedSequence(args.seed).spawn(2)
    true, errors = robot_as_built(robot, args.true_robot, args.errors, seeds[0])
    # the samples' memory first (physics: the run can only add its tail), then the plan sampled
    require(
        args, "simulate", memory=cost.bytes, size=f"{cost.samples:.3g} samples", hint="lower --rate or shorten --path"
    )
    with _drivable(args):
        estimate = engine.cost(plan, true, robot, rate=args.rate, budget=Budget.of(args).seconds)
    duration, seconds = estimate.simulated, estimate.seconds  # physics: the waits and the tail at their limits
    samples = duration * args.rate
    _check_stamps(args, duration=duration)
    writing = (SIM_SAMPLE_SECONDS if args.bag is not None else 0.0) + (LOG_ROW_SECONDS if args.log else 0.0)
    require(
        args,
        "simulate",
        memory=cost.bytes * samples / max(cost.samples, 1.0),
        seconds=seconds + samples * writing,
        size=f"{cost.samples:.3g} samples",
        hint=physics_hint(args.step, "shorten --path") if engine.measured_cost else "lower --rate or shorten --path",
    )
    with _drivable(args):
        # the seed's second stream draws the run's random errors, for an engine with a model of them
        run = _simulate_physics(args, engine, plan, true, robot, noise, seeds[1] if noise else None)
    custom = {
        "omnikin.robot": robot.name,
        "omnikin.path": args.path,
        "omnikin.seed": str(args.seed),
        "omnikin.errors": "file " + args.true_robot if args.true_robot else args.errors,
        "omnikin.rate": f"{args.rate:g}",
        "omnikin.engine": engine.name,
    }
    if engine.has_noise_model:
        custom["omnikin.noise"] = args.noise
    counts = (
        record_run(args.bag, run, robot, start=args.start, storage=args.storage, custom=custom, force=args.force)
        if args.bag is not None
        else {}
    )
    if args.log is not None:
        _write_tick_log(args, engine, robot, run)
    truth_end = run.truth[0, -1]
    odom_end = run.odometry[-1]
    diff = truth_end - odom_end
    diff[2] = wrap_angle(diff[2])
    summary = {
        "robot": robot.name,
        "path": args.path,
        "errors": None if args.true_robot else args.errors,
        "true_robot": args.true_robot,
        "noise": args.noise,
        "engine": engine.name,
        "step": args.step,
        "seed": args.seed,
        "rate": args.rate,
        "samples": len(run.t),
        "duration": float(run.t[-1]),
        "bag": args.bag,
        "topics": counts,
        "log": args.log,
        "truth_end": truth_end.tolist(),
        "odometry_end": odom_end.tolist(),
        "end_error": diff.tolist(),
        "end_error_distance": float(math.hypot(diff[0], diff[1])),
    }
    if errors is not None:
        summary["injected_errors"] = errors.as_dict()
    saturated = getattr(run, "saturated", 0)
    summary.update(engine.summary(run))
    for problem in engine.problems(run):  # the run did not drive as commanded: one line each
        print(f"omnikin: warning: {robot.name}: {problem}", file=sys.stderr)
    if saturated:
        print(
            f"omnikin: warning: {robot.name}: {saturated} of {len(run.t) - 1} commands asked a motor beyond its "
            f"speed limit or a steering joint beyond its end stop and were held at the limit",
            file=sys.stderr,
        )
    if args.json:
        print_json(summary)
        return 0
    noise_text = args.noise or "from the contacts"
    console(120).print(
        f"{robot.name}: '{args.path}' at {args.rate:g} Hz ({engine.name} engine), {summary['samples']} samples over "
        f"{summary['duration']:.6g} s (errors {summary['errors'] or 'from ' + args.true_robot}, noise {noise_text}, "
        f"seed {args.seed})\n"
        f"end pose: truth x={truth_end[0]:.6g} m, y={truth_end[1]:.6g} m, theta={truth_end[2]:.6g} rad; odometry "
        f"x={odom_end[0]:.6g} m, y={odom_end[1]:.6g} m, theta={odom_end[2]:.6g} rad "
        f"(off by {summary['end_error_distance'] * 1000:.3g} mm)\n"
        + (f"bag {args.bag}: " + ", ".join(f"{t} ({n})" for t, n in counts.items()) if args.bag is not None else "")
        + (
            ("\n" if args.bag is not None else "")
            + f"tick log written to {'standard output' if args.log == '-' else args.log}"
            if args.log is not None
            else ""
        )
    )
    return 0


def _engine_options(args):
    """The engine of ``--engine`` (:func:`~omnikin.cli.common.engine_of`), the options checked
    against it and its defaults filled in (``--noise`` typical for the kinematic engine;
    ``--step`` 2 ms for physics). The physics engine maps ``--errors``, ``--true-robot`` and
    ``--seed`` (the robot as built is the physical model), has no random errors (any ``--noise``
    is refused: slip comes from the contacts, the encoders count whole ticks); ``--step`` is the
    physics engine's alone."""
    engine = engine_of(args)
    args.noise = engine.default_noise if args.noise is None else args.noise
    args.step = engine.options.get("step")
    return engine


def _simulate_physics(args, engine, plan, true, robot, noise, rng):
    """The run, ``engine.drive``, with a progress bar on standard error once it has taken
    :data:`PROGRESS_AFTER` seconds (shown on a terminal only; the physics engine reports its
    progress, the kinematic engine's runs take a moment)."""
    import time

    started = time.monotonic()
    bar: list = []

    def progress(done: float, total: float) -> None:
        if not bar:
            if time.monotonic() - started < PROGRESS_AFTER:
                return
            err = console(stderr=True)
            if not err.is_terminal:  # rich would still end the bar with an empty line on a pipe
                return
            from rich.progress import Progress

            display = Progress(console=err, transient=True)
            display.start()
            bar.extend([display, display.add_task("simulating (physics)", total=total)])
        bar[0].update(bar[1], completed=done)

    try:
        return engine.drive(plan, true, robot, rate=args.rate, noise=noise, rng=rng, progress=progress)
    finally:
        if bar:
            bar[0].stop()


def _check_stamps(args, duration: float) -> None:
    """Refuse a --start whose stamps an output cannot hold (:func:`~omnikin.motion.timing.check_start`),
    before simulating: a bag's ROS 2 times (integer nanoseconds from 0 to 2**31 - 1 s), a tick
    log's times (read back as floats). ``duration`` [s]: at least the run's."""
    from ..io.bags import NS, ROS_TIME_SPAN
    from ..motion.timing import check_start

    if args.bag is not None:
        check_start(args.start, duration, args.rate, "--start", output="a ROS 2 bag", span=ROS_TIME_SPAN, step=1 / NS)
    if args.log is not None:
        check_start(args.start, duration, args.rate, "--start", output="a tick log")


def _check_tick_log(args, robot) -> None:
    """Refuse a --log the --noise profile cannot give (unquantised ticks), before simulating."""
    from ..simulation.error_models import noise as noise_profile

    if not noise_profile(args.noise).quantise:
        raise InputError(
            f"--log writes whole-number encoder counts, but --noise {args.noise} leaves the ticks "
            f"unquantised; choose another --noise profile"
        )


def _write_tick_log(args, engine, robot, run) -> None:
    import shlex

    from ..io.logs import write_tick_log

    command = " ".join(
        ["omnikin simulate", shlex.quote(args.robot), "--path", shlex.quote(args.path)]
        + (["--true-robot", shlex.quote(args.true_robot)] if args.true_robot else ["--errors", args.errors])
        + (["--noise", args.noise] if engine.has_noise_model else ["--engine", engine.name, "--step", f"{args.step:g}"])
        + ["--seed", str(args.seed), "--rate", f"{args.rate:g}"]
        + ["--log", shlex.quote(args.log)]
    )
    write_tick_log(
        args.log,
        run.t + args.start,
        run.readings,
        robot.encoded_names,
        run.steer,
        steer_names=robot.steer_names,
        comment=f"encoder tick log of {robot.name} written by: {command}",
    )


# --- metrics -----------------------------------------------------------------------------------------
def cmd_metrics(args) -> int:
    from ..evaluation.metrics import evaluate, statistics
    from ..io.trajectories import detect_format, read_trajectory

    if args.delta < 1:
        raise InputError(f"--delta must be a whole number of frames >= 1, got {args.delta}")
    if not (math.isfinite(args.t_max_diff) and args.t_max_diff >= 0):
        raise InputError(f"--t-max-diff must be a time >= 0 [s], got {args.t_max_diff}")
    if not math.isfinite(args.t_offset):
        raise InputError(f"--t-offset must be a finite time [s], got {args.t_offset}")
    paths = (args.ref, args.est)
    for path in paths:
        _size_trajectory_file(args, path)
    formats = [detect_format(p) for p in paths]
    if formats.count("kitti") == 1:
        kitti, timed = paths if formats[0] == "kitti" else paths[::-1]
        raise InputError(
            f"{kitti} is KITTI (no timestamps: pose k stands at t = k) but {timed} has timestamps "
            f"[s]: they cannot be associated; export both as TUM or CSV, or both as KITTI to "
            f"compare by index"
        )
    t_ref, ref = read_trajectory(args.ref, formats[0])
    t_est, est = read_trajectory(args.est, formats[1])
    try:
        ev = evaluate(
            t_ref,
            ref,
            t_est,
            est,
            align=args.align,
            delta=args.delta,
            all_pairs=args.all_pairs,
            max_diff=args.t_max_diff,
            offset=args.t_offset,
        )
    except OmnikinError as exc:
        raise InputError(f"{args.ref} vs {args.est}: {exc}") from None
    rot_deg = statistics(np.degrees(ev.rpe.rotation))
    doc = {
        "reference": args.ref,
        "estimate": args.est,
        "reference_poses": len(t_ref),
        "estimate_poses": len(t_est),
        **ev.as_dict(),
    }
    doc["rpe"]["rotation_deg"] = rot_deg.as_dict()
    if args.json:
        print_json(doc)
        return 0
    from rich.table import Table

    con = console(120)
    a = ev.ate
    con.print(
        f"{args.est} against {args.ref}: {a.errors.size} associated poses (of {len(t_est)} and {len(t_ref)}; "
        f"max time difference {args.t_max_diff:g} s" + (f", offset {args.t_offset:g} s" if args.t_offset else "") + ")"
    )
    if a.alignment is not None:
        al = a.alignment
        con.print(f"SE(2) alignment: x={al.x:.6g} m, y={al.y:.6g} m, theta={math.degrees(al.theta):.6g} deg")
    table = Table(title_justify="left")
    cols = ("rmse", "mean", "median", "std", "min", "max")
    table.add_column("")
    for c in cols:
        table.add_column(c, justify="right")
    pairs = "all pairs (i, i+N)" if args.all_pairs else "consecutive pairs"
    con.print(f"RPE over delta N = {args.delta} frames: {ev.rpe.translation.size} {pairs}")
    rows = (
        ("ATE translation [m]" + (" (aligned)" if args.align else ""), a.stats),
        ("RPE translation [m]", ev.rpe.translation_stats),
        ("RPE rotation [deg]", rot_deg),
    )
    for label, s in rows:
        table.add_row(label, *[f"{getattr(s, c):.6g}" for c in cols])
    con.print(table)
    return 0


TRAJECTORY_BYTES_PER_FILE_BYTE = 24
"""Memory to read a trajectory file, per byte of the file (its text, its lines as Python
strings, the parsed numbers): measured 4 for TUM lines, 9 for KITTI, 16 for 12-byte CSV lines."""


def _size_trajectory_file(args, path) -> None:
    """Refuse a trajectory file too large to read within ``--max-memory`` (from its size; a pipe
    has none and is read as it comes, a device is refused by the reader)."""
    import os
    import stat

    try:
        info = os.stat(path)
    except OSError:
        return  # the reader names a missing or unreadable file
    if not stat.S_ISREG(info.st_mode):
        return
    size = info.st_size
    require(
        args,
        "metrics",
        memory=size * TRAJECTORY_BYTES_PER_FILE_BYTE,
        size=f"{path} ({size} bytes)",
        hint="compare shorter trajectories",
    )
