"""``omnikin simulate``: a simulated run of a robot as built (:func:`omnikin.simulate`), recorded
to a ROS 2 bag (:func:`omnikin.io.bags.record_run`) and/or an encoder tick log."""

from __future__ import annotations

import argparse
import contextlib
import math
import sys

from ..common.messages import shorten
from ..errors import InfeasibleTwistError, InputError, OmnikinError
from ..physics.engines import ENGINE_NAMES
from .budget import LOG_ROW_SECONDS, RUN_SAMPLE_SECONDS, Budget, add_budget_options, require
from .common import (
    add_as_built_options,
    add_output,
    add_output_options,
    add_step_option,
    add_world_option,
    check_seed,
    console,
    declare_inputs,
    engine_of,
    load_robot,
    number,
    physics_hint,
    print_json,
)

PROGRESS_AFTER = 3.0
"""simulate --engine physics shows its progress once a run has taken this long [s]."""

SIMULATE_EPILOG = """examples:
  omnikin simulate tomasi-omni3 --bag sim.bag
  omnikin simulate tomasi-omni3 --log log.csv && omnikin odometry tomasi-omni3 log.csv -o traj.csv
  omnikin simulate diff-drive --path 'square ccw rotate 2' --errors none --noise none --bag sim.bag
  omnikin simulate mecanum4 --path 'line 2 90; spin 180; arc 1 90' --rate 50 --seed 7 --bag sim.bag
  omnikin bag export sim.bag --topic /ground_truth --format tum -o truth.tum
  omnikin simulate tomasi-omni3 --engine physics --errors none --path 'line 1' --log log.csv
  omnikin simulate tomasi-omni3 --world examples/worlds/room.yaml --path 'line 4' --bag room.bag

engines: kinematic (default) integrates the wheels' motion with the --errors and --noise models;
physics drives the robot as built (--errors or --true-robot) in MuJoCo with real rollers, motors
and contacts (extra physics, docs/physics.md): the same plan and limits, wheel speeds commanded at
--rate, the run sampled on until the robot stops; it has no --noise model (slip comes from the
contacts) and takes --step, its time step.

--world puts walls, obstacles and floor patches around the robot (docs/world.md): it starts at the
world's start pose, stops at the first wall or obstacle it touches (physics: pushes what moves)
while its wheels turn on, and the contacts are reported; poses stay in the frame where it started.

paths (';' chains several): 'square cw|ccw rotate|translate [SIDE]', 'line LENGTH [HEADING_DEG]',
'spin ANGLE_DEG', 'arc RADIUS ANGLE_DEG'. Topics: /ground_truth and /odom (nav_msgs/Odometry),
/joint_states (sensor_msgs/JointState, wheel angles [rad]), /cmd_vel (geometry_msgs/Twist)."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``simulate`` to ``sub``."""
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
    add_world_option(sp)
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
    add_output(
        sp,
        "--imu-log",
        metavar="IMU.csv",
        help="write what the robot's IMUs read (CSV: sensor, t, gyro and accelerometer in SI units, each IMU's "
        "frame; docs/sensors.md)",
    )
    add_output(
        sp,
        "--scan-log",
        stdout=False,  # a binary archive
        metavar="SCANS.npz",
        help="write the robot's lidar scans (NumPy .npz: times, ranges, beam angles; docs/sensors.md)",
    )
    sp.add_argument("--storage", choices=("sqlite3", "mcap"), default="sqlite3", help="bag storage (default sqlite3)")
    sp.add_argument("--json", action="store_true", help="print a JSON summary")
    add_output_options(sp)
    add_budget_options(sp)
    declare_inputs(sp, "world", robots=("robot", "true_robot"))
    sp.set_defaults(func=run)


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


def run(args) -> int:
    """Simulate the run, write ``--bag`` and/or ``--log``, print a summary (or ``--json``); status 0."""
    from ..api.simulation import simulate
    from ..io.bags import record_run, require_rosbags
    from ..motion.timing import check_rate_range

    if args.bag is None and args.log is None and args.imu_log is None and args.scan_log is None:
        raise InputError("simulate: give --bag OUT.bag, --log LOG.csv, --imu-log IMU.csv and/or --scan-log SCANS.npz")
    engine = _engine_options(args)
    if args.bag is not None:
        require_rosbags()
    robot = load_robot(args.robot)
    _check_sensor_logs(args, robot)
    if args.log is not None and engine.has_noise_model:
        _check_tick_log(args, robot)
    check_seed(args.seed)
    check_rate_range(args.rate, "--rate")
    plan = parse_paths(args.path)
    noise = engine.noise_model(args.noise)
    budget = Budget.of(args)
    with _drivable(args), _progress_bar() as progress:
        simulation = simulate(
            robot,
            plan,
            true_robot=args.true_robot or None,
            errors=args.errors,
            noise=noise,
            seed=args.seed,
            rate=args.rate,
            engine=engine,
            max_memory=budget.memory,
            max_time=budget.seconds,
            progress=progress,
            on_cost=lambda cost: _within_budget(args, engine, cost),
            sensors=args.imu_log is not None or args.scan_log is not None or args.bag is not None,
        )
    run = simulation.run
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
    _write_sensor_logs(args, robot, run)
    truth_end = run.truth[0, -1]
    odom_end = run.odometry[-1]
    diff = simulation.end_error
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
        "imu_log": args.imu_log,
        "scan_log": args.scan_log,
        "truth_end": truth_end.tolist(),
        "odometry_end": odom_end.tolist(),
        "end_error": diff.tolist(),
        "end_error_distance": float(math.hypot(diff[0], diff[1])),
    }
    if simulation.injected is not None:
        summary["injected_errors"] = simulation.injected.as_dict()
    if args.world is not None:
        summary["world"] = args.world
        summary["start"] = list(run.start)
        summary["contacts"] = [
            {"time": c.time, "body": c.body, "point": list(c.point)} for c in (run.contacts[0] if run.contacts else ())
        ]
    summary.update(engine.summary(run))
    saturated = summary.get("saturated_commands", 0)  # commands held at a limit (physics)
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
        + (_contacts_text(summary["contacts"], args.world) + "\n" if args.world is not None else "")
        + (f"bag {args.bag}: " + ", ".join(f"{t} ({n})" for t, n in counts.items()) if args.bag is not None else "")
        + (
            ("\n" if args.bag is not None else "")
            + f"tick log written to {'standard output' if args.log == '-' else args.log}"
            if args.log is not None
            else ""
        )
        + "".join(_sensor_lines(args, run))
    )
    return 0


def _sensor_lines(args, run) -> list[str]:
    """The summary's lines on the sensor logs written (each starting a new line)."""
    sensing = run.sensing
    lines = []
    if args.imu_log is not None and sensing is not None:
        readings = sum(len(r.t) for r in sensing.imus)
        lines.append(f"\nIMU log written to {args.imu_log}: {readings} readings")
    if args.scan_log is not None and sensing is not None:
        scans = sum(len(r.t) for r in sensing.scans)
        lines.append(f"\nscan log written to {args.scan_log}: {scans} scans")
    return lines


def _contacts_text(contacts: list[dict], world: str) -> str:
    """One line on the run's contacts in ``world`` (the first few named, with their times)."""
    if not contacts:
        return f"world {world}: no contact with its walls or obstacles"
    shown = ", ".join(f"{c['body']!r} at t={c['time']:.4g} s" for c in contacts[:5])
    more = f" and {len(contacts) - 5} more" if len(contacts) > 5 else ""
    return f"world {world}: {len(contacts)} contact(s): {shown}{more} (the truth stopped there; the odometry did not)"


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


def _within_budget(args, engine, cost) -> None:
    """Check an estimate of :func:`omnikin.simulate` (:class:`~omnikin.api.SimulationCost`) against
    ``--max-memory`` and ``--max-time``: the samples' memory first (physics: the run can only add
    its tail), then, once the run's duration is known, after the stamps its outputs can hold
    (:func:`_check_stamps`), its memory and time with the time of writing ``--bag`` and ``--log``
    (the physics engine's first estimate, before the plan is sampled, has its memory alone)."""
    require(
        args, "simulate", memory=cost.memory, size=f"{cost.samples:.3g} samples", hint="lower --rate or shorten --path"
    )
    if cost.seconds is None:
        return
    samples = cost.duration * args.rate  # in physics, the waits and the tail at their limits
    _check_stamps(args, duration=cost.duration)
    writing = (RUN_SAMPLE_SECONDS if args.bag is not None else 0.0) + (LOG_ROW_SECONDS if args.log else 0.0)
    require(
        args,
        "simulate",
        memory=cost.memory * samples / max(cost.samples, 1.0),
        seconds=cost.seconds + samples * writing,
        size=f"{cost.samples:.3g} samples",
        hint=physics_hint(args.step, "shorten --path") if engine.measured_cost else "lower --rate or shorten --path",
    )


@contextlib.contextmanager
def _progress_bar():
    """A ``progress(done, total)`` for :func:`omnikin.simulate` (the physics engine's simulated time
    [s]) that shows a bar on standard error once the run has taken :data:`PROGRESS_AFTER` seconds
    (on a terminal only); the bar is removed at the end."""
    import time

    started: list[float] = []
    bar: list = []

    def progress(done: float, total: float) -> None:
        if not started:
            started.append(time.monotonic())
        if not bar:
            if time.monotonic() - started[0] < PROGRESS_AFTER:
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
        yield progress
    finally:
        if bar:
            bar[0].stop()


def _check_stamps(args, duration: float) -> None:
    """Refuse a --start whose stamps an output cannot hold (:func:`~omnikin.motion.timing.check_start_time`),
    before simulating: a bag's ROS 2 times (integer nanoseconds from 0 to 2**31 - 1 s), a tick
    log's times (read back as floats). ``duration`` [s]: at least the run's."""
    from ..io.bags import NS, ROS_TIME_SPAN
    from ..motion.timing import check_start_time

    if args.bag is not None:
        check_start_time(
            args.start, duration, args.rate, "--start", output="a ROS 2 bag", span=ROS_TIME_SPAN, step=1 / NS
        )
    if args.log is not None:
        check_start_time(args.start, duration, args.rate, "--start", output="a tick log")


def _check_tick_log(args, robot) -> None:
    """Refuse a --log the --noise profile cannot give (unquantised ticks), before simulating."""
    from ..simulation.error_models import noise_profile

    if not noise_profile(args.noise).quantise:
        raise InputError(
            f"--log writes whole-number encoder counts, but --noise {args.noise} leaves the ticks "
            f"unquantised; choose another --noise profile"
        )


def _check_sensor_logs(args, robot) -> None:
    """Refuse, before the run, a sensor log the robot cannot fill (one line)."""
    from ..kinematics.sensors import Imu, Lidar

    for flag, value, kind, noun in (
        ("--imu-log", args.imu_log, Imu, "IMU"),
        ("--scan-log", args.scan_log, Lidar, "lidar"),
    ):
        if value is None:
            continue
        if not any(isinstance(s, kind) for s in robot.sensors):
            raise InputError(
                f"{flag}: robot {robot.name!r} has no {noun} (declare one under sensors: in its robot file, "
                f"docs/sensors.md; the preset tomasi-omni3-lidar has one)"
            )


def _write_sensor_logs(args, robot, run) -> None:
    """Write ``--imu-log`` and ``--scan-log`` from the run's sensor readings."""
    from ..io.sensor_logs import write_imu_log, write_scan_log

    sensing = run.sensing
    if args.imu_log is not None and sensing is not None:
        errors = f"noise {args.noise}" if args.noise is not None else "the robot file's sensor errors"
        comment = f"IMU readings of {robot.name} written by omnikin simulate (seed {args.seed}, {errors})"
        write_imu_log(args.imu_log, sensing.imus, comment, start=args.start)
    if args.scan_log is not None and sensing is not None:
        write_scan_log(args.scan_log, sensing.scans, start=args.start)


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
