"""``omnikin track``: a robot drives a path at the speed its wheels allow, steered by a tracking
controller (:func:`omnikin.track`); the error, the reference and the truth written out."""

from __future__ import annotations

import argparse
import math

from ..common.messages import shorten
from ..errors import CliError
from ..physics.engines import ENGINE_NAMES
from .budget import LOG_ROW_SECONDS, RUN_SAMPLE_SECONDS, add_budget_options, require
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

TRACK_EPILOG = """examples:
  omnikin track tomasi-omni3 'figure8 1' --plot track.svg
  omnikin track tomasi-omni3 'figure8 1' --engine physics --plot fig.svg --json
  omnikin track mecanum4 'square 1 0.2' --max-wheel-speed 8 --reference ref.tum --truth truth.tum
  omnikin track omni4 waypoints.csv --blend 0.3 --errors typical --noise typical --json
  omnikin track tomasi-omni3 waypoints.yaml --smooth --heading fixed
  omnikin track diff-drive 'circle 1' --controller mpc --json     (extra control: OSQP)
  omnikin track ackermann 'figure8 6' --plot car.svg              (pure pursuit within its turning radius)
  omnikin track tomasi-omni3 'circle 1' --noise typical --log ticks.csv --bag run.bag
      (then: omnikin odometry tomasi-omni3 ticks.csv; omnikin view tomasi-omni3 --replay run.bag)

paths: a built-in path, 'circle RADIUS', 'figure8 SIZE', 'square SIDE [BLEND]' (metres; each
starts at the origin heading along +x), or a path file of waypoints in metres and radians:
CSV with a header x,y or x,y,theta, or YAML 'waypoints: [[x, y], [x, y, theta], ...]' (and
'closed: true'). A CSV path whose last row repeats the first is closed. Corners are stopped at,
cut by arcs (--blend R), or the whole path is a smooth curve through the points (--smooth). The
robot starts at rest on the path's first point, at its heading; outputs are in the path's frame.

timing: the reference is the fastest the wheels allow, every wheel within --max-wheel-speed and
--max-wheel-accel at once (not a box per axis; in physics the motors' own speed and torque
limits too); the controller steers by the robot's odometry (as on a real robot) at --rate, and
the runtime saturates its commands to the speed limit.

--json: duration_s, path_length_m, rms_error_m and max_error_m (the truth's distance to the
path), rms_heading_error_rad, max_wheel_speed_rad_s (commanded), saturated_samples,
solve_time_ms (p50, p95, max: the controller's wall time per tick) and more."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``track`` to ``sub``."""
    from ..api.tracking import DEFAULT_RATE
    from ..control.controllers import CONTROLLERS
    from ..control.path import HEADINGS
    from ..simulation.error_models import NOISE

    sp = sub.add_parser(
        "track",
        help="drive a path at the wheels' limits with a tracking controller",
        description="ROBOT drives PATH at the fastest timing its wheel limits allow, steered by a tracking "
        "controller from its odometry, in the kinematic or the physics engine; prints how far the truth "
        "strayed from the path.",
        epilog=TRACK_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument(
        "path", metavar="PATH", help="a built-in path ('figure8 1', see below) or a path file (.csv, .yaml)"
    )
    sp.add_argument(
        "--controller",
        choices=tuple(CONTROLLERS),
        help="; ".join(f"{name}: {what}" for name, what in CONTROLLERS.items()) + " (default feedback; mpc for a "
        "differential drive, pursuit for a car)",
    )
    sp.add_argument(
        "--engine",
        choices=ENGINE_NAMES,
        default="kinematic",
        help="kinematic: wheel motion and error models; physics: MuJoCo with rollers and motors (extra physics) "
        "(default kinematic)",
    )
    add_step_option(sp)
    add_world_option(sp)
    add_as_built_options(sp, default_errors="none")
    sp.add_argument(
        "--noise",
        metavar="PROFILE",
        help=f"random errors of the kinematic engine: {', '.join(sorted(NOISE))} (default none)",
    )
    sp.add_argument("--rate", type=number, default=DEFAULT_RATE, metavar="HZ", help="control rate [Hz] (default 50)")
    sp.add_argument(
        "--max-wheel-speed",
        type=number,
        default=12.0,
        metavar="RAD_S",
        help="every wheel's speed limit [rad/s] (default 12)",
    )
    sp.add_argument(
        "--max-wheel-accel",
        type=number,
        default=40.0,
        metavar="RAD_S2",
        help="every wheel's acceleration limit [rad/s^2] (default 40)",
    )
    sp.add_argument(
        "--heading",
        metavar="MODE",
        help=f"heading along a path without one: {', '.join(HEADINGS)} or an angle [rad] (default: fixed for "
        "circle and figure8, tangent for squares and files, tangent for a robot with fixed wheels)",
    )
    sp.add_argument("--blend", type=number, metavar="R", help="path files: cut the corners by arcs of radius R [m]")
    sp.add_argument("--smooth", action="store_true", help="path files: a smooth curve through the waypoints")
    add_output(sp, "--truth", metavar="OUT.tum", help="write the ground truth at the ticks (TUM)")
    add_output(sp, "--reference", metavar="OUT.tum", help="write the timed reference at the ticks (TUM)")
    add_output(sp, "--odometry", metavar="OUT.tum", help="write the odometry at the ticks (TUM)")
    add_output(
        sp,
        "--log",
        metavar="LOG.csv",
        help="write the encoder tick log at the ticks, the input of 'omnikin odometry' (needs whole encoder "
        "counts: the physics engine, or --noise typical)",
    )
    add_output(
        sp,
        "--bag",
        folder="data",
        metavar="OUT.bag",
        help="write the run to a new ROS 2 bag: /ground_truth, /odom, /joint_states, /cmd_vel, the poses in the odom "
        "frame fixed where the robot started (extra bags; a new name, --force replaces a bag omnikin wrote)",
    )
    sp.add_argument("--storage", choices=("sqlite3", "mcap"), default="sqlite3", help="bag storage (default sqlite3)")
    add_output(
        sp,
        "--plot",
        stdout=False,
        metavar="FIG",
        help="draw path, truth, odometry, error over time and wheel speeds against their limit (.png, .svg, .pdf)",
    )
    sp.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_output_options(sp)
    add_budget_options(sp)
    declare_inputs(sp, "path", "world", robots=("robot", "true_robot"))  # (a built-in path names no file: harmless)
    sp.set_defaults(func=run)


def _heading(text: str | None):
    """``--heading``: a mode name or an angle [rad]."""
    from ..control.path import HEADINGS

    if text is None or text in HEADINGS:
        return text
    try:
        value = number(text)
    except argparse.ArgumentTypeError:
        raise CliError(f"--heading {shorten(text)}: one of {', '.join(HEADINGS)} or an angle [rad]") from None
    return value


def run(args) -> int:
    """Track the path, write the outputs, print the summary (or ``--json``); status 0."""
    from ..api.tracking import track
    from ..io.path_file import is_path_file
    from ..io.trajectories import write_trajectory

    if args.plot is not None:
        from ..viz import figure_format, require_matplotlib

        require_matplotlib()
        figure_format(args.plot)
    if args.bag is not None:
        from ..io.bags import require_rosbags

        require_rosbags()
    check_seed(args.seed)
    heading = _heading(args.heading)
    robot = load_robot(args.robot)
    if args.log is not None:
        _check_tick_log(args)
    writing = (RUN_SAMPLE_SECONDS if args.bag is not None else 0.0) + (LOG_ROW_SECONDS if args.log else 0.0)

    def within(cost) -> None:
        require(
            args,
            "track",
            memory=cost.memory,
            seconds=cost.seconds + cost.ticks * writing,
            size=f"{cost.ticks:.3g} control ticks",
            hint=physics_hint(cost.step, "shorten PATH or raise --max-wheel-speed")
            if cost.step is not None
            else "lower --rate, shorten PATH or raise --max-wheel-speed",
        )

    tracking = track(
        robot,
        args.path,
        controller=args.controller,
        engine=engine_of(args),  # with --step and --world
        true_robot=args.true_robot or None,
        errors=args.errors,
        noise=args.noise,
        seed=args.seed,
        rate=args.rate,
        max_wheel_speed=args.max_wheel_speed,
        max_wheel_accel=args.max_wheel_accel,
        heading=heading,
        blend=args.blend,
        smooth=args.smooth,
        max_memory=math.inf,  # (the budget options are checked by within)
        max_time=math.inf,
        on_cost=within,
    )
    run = tracking.run
    inputs = [f for f in ((args.path if is_path_file(args.path) else None), args.true_robot) if f]
    for option, poses in (("truth", run.truth), ("reference", run.reference), ("odometry", run.odometry)):
        target = getattr(args, option)
        if target is not None:
            write_trajectory(target, run.t, poses, "tum", force=args.force, inputs=inputs)
    counts = _write_bag(args, tracking) if args.bag is not None else {}
    if args.log is not None:
        _write_tick_log(args, tracking)
    if args.plot is not None:
        _save_plot(tracking, args.plot)
    summary = tracking.summary()
    summary.update(
        errors=None if args.true_robot else args.errors,
        true_robot=args.true_robot,
        noise=args.noise,
        seed=args.seed,
        log=args.log,
        bag=args.bag,
        topics=counts,
    )
    if args.world is not None:
        summary["world"] = args.world
        summary["contacts"] = [{"time": c.time, "body": c.body, "point": list(c.point)} for c in tracking.run.contacts]
    if args.json:
        print_json(summary)
        return 0
    solve = summary["solve_time_ms"]
    mm = {key: summary[key] * 1e3 for key in ("rms_error_m", "max_error_m", "end_error_m")}
    lines = [
        f"{robot.name}: {tracking.path.name}, {summary['path_length_m']:.4g} m in {summary['duration_s']:.4g} s "
        f"({tracking.controller} controller at {args.rate:g} Hz, {tracking.engine} engine)",
        f"distance to the path: RMS {mm['rms_error_m']:.3g} mm, largest {mm['max_error_m']:.3g} mm; the end "
        f"{mm['end_error_m']:.3g} mm off; heading RMS {math.degrees(summary['rms_heading_error_rad']):.3g} deg",
        f"wheels: limits {args.max_wheel_speed:g} rad/s and {args.max_wheel_accel:g} rad/s^2, up to "
        f"{summary['max_wheel_speed_rad_s']:.4g} rad/s commanded",
        f"saturated: {summary['saturated_samples']} of {summary['samples']} commands"
        + (f", asked at most {summary['largest_excess_percent']:.2g} % beyond" if summary["saturated_samples"] else ""),
        f"controller: {solve['p50']:.3g} ms per tick (p95 {solve['p95']:.3g} ms, largest {solve['max']:.3g} ms)",
    ]
    if args.world is not None:
        contacts = summary["contacts"]
        lines.append(
            f"world {args.world}: "
            + (
                f"{len(contacts)} contact(s), the first {contacts[0]['body']!r} at t={contacts[0]['time']:.4g} s"
                if contacts
                else "no contact with its walls or obstacles"
            )
        )
    lines += [
        f"{option} written to {'standard output' if getattr(args, option) == '-' else getattr(args, option)}"
        for option in ("truth", "reference", "odometry", "log", "bag", "plot")
        if getattr(args, option) is not None
    ]
    console(120).print("\n".join(lines))
    return 0


def _save_plot(tracking, path: str) -> None:
    """Draw the run (:meth:`omnikin.api.tracking.Tracking.plot`) to ``path`` whole or not at all."""
    from ..io.output import atomic_write
    from ..viz import figure_format, save_figure

    figure = tracking.plot()
    with atomic_write(path, "wb") as handle:
        save_figure(figure, handle, format=figure_format(path))


def _check_tick_log(args) -> None:
    """Refuse a ``--log`` the run cannot give, before it is driven: a tick log holds whole
    encoder counts, and the kinematic engine's encoders count whole ticks only under a noise
    profile that quantises them (not under none, the default)."""
    from ..errors import InputError
    from ..simulation.error_models import noise_profile

    if args.engine == "kinematic" and (args.noise is None or not noise_profile(args.noise).quantise):
        raise InputError(
            f"--log writes whole-number encoder counts, but the kinematic engine's encoders are exact under "
            f"--noise {args.noise or 'none'}; give --noise typical, or --engine physics, or record --bag instead"
        )


def _command(args) -> str:
    """The command line that reproduces the run (written into the tick log and the bag)."""
    import shlex

    words = ["omnikin track", shlex.quote(args.robot), shlex.quote(args.path)]
    for option in ("controller", "heading", "blend", "noise", "true_robot", "step"):
        value = getattr(args, option)
        if value is not None:
            words += [f"--{option.replace('_', '-')}", shlex.quote(repr(value) if isinstance(value, float) else value)]
    if args.smooth:
        words.append("--smooth")
    if not args.true_robot:
        words += ["--errors", shlex.quote(args.errors)]
    words += ["--engine", args.engine, "--seed", str(args.seed), "--rate", repr(args.rate)]
    words += ["--max-wheel-speed", repr(args.max_wheel_speed), "--max-wheel-accel", repr(args.max_wheel_accel)]
    return " ".join(words)


def _counts(tracking):
    """The encoder counts of the run ``(n, n_encoded)`` (int64, unwrapped): the angles the runtime
    read over the nominal robot's angle per tick, whole numbers by :func:`_check_tick_log`."""
    import numpy as np

    from ..errors import InputError

    robot = tracking.robot
    ticks = tracking.run.wheel_angles / robot.rad_per_tick(robot.encoded_names)
    counts = np.rint(ticks)
    if not np.all(np.abs(ticks - counts) <= 1e-6 * np.maximum(1.0, np.abs(counts))):
        raise InputError("--log: the run's encoder readings are not whole counts; give --noise typical")
    return counts.astype(np.int64)


def _write_tick_log(args, tracking) -> None:
    """``--log``: the encoder counts as the robot's counters output them, at the ticks."""
    from ..io.logs import write_tick_log
    from ..simulation.kinematic import counter_output

    robot = tracking.robot
    names = robot.encoded_names
    readings = counter_output(_counts(tracking), [robot.wheel(n).encoder.counter_bits for n in names])
    write_tick_log(
        args.log,
        tracking.run.t,
        readings,
        names,
        tracking.run.steer,
        steer_names=robot.steer_names,
        comment=f"encoder tick log of {robot.name} written by: {_command(args)} --log {args.log}",
    )


def _write_bag(args, tracking) -> dict:
    """``--bag``: the run's truth, odometry, wheel angles and commands
    (:func:`omnikin.io.bags.record_samples`), the poses in the odom frame fixed where the robot
    started (as the wheels' odometry reads them back; the TUM outputs are in the path's frame)."""
    from ..io.bags import record_samples

    run = tracking.run
    custom = {
        "omnikin.robot": tracking.robot.name,
        "omnikin.path": args.path,
        "omnikin.controller": tracking.controller,
        "omnikin.engine": tracking.engine,
        "omnikin.seed": str(args.seed),
        "omnikin.errors": "file " + args.true_robot if args.true_robot else args.errors,
        "omnikin.rate": f"{args.rate:g}",
        "omnikin.command": _command(args),
    }
    return record_samples(
        args.bag,
        tracking.robot,
        run.t,
        truth=tracking.in_start_frame(run.truth),
        odometry=tracking.in_start_frame(run.odometry),
        wheel_angles=run.wheel_angles,
        steer=run.steer,
        command=run.command,
        rate=args.rate,
        storage=args.storage,
        custom=custom,
        force=args.force,
    )
