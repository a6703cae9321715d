"""``omnikin view``: the robot in 3D in the browser, driven from the page (extra ``viewer``)."""

from __future__ import annotations

import argparse
import sys

from ..motion.plans import UMBMARK_SIDE
from ..physics.engines import ENGINE_NAMES
from .budget import LARGEST_MESSAGE_SHARE, POSE_BYTES, Budget, add_budget_options
from .common import (
    add_step_option,
    add_teleop_options,
    add_world_option,
    declare_inputs,
    engine_of,
    load_robot,
    number,
    teleop_limits,
    whole,
)

EPILOG = """the page (open the printed address in a browser; click the scene so that it has the keys):
  W / S      drive forward / back at --speed while held
  A / D      drive left / right at --speed while held (robots with fixed wheels cannot)
  Q / E      turn counter-clockwise / clockwise at --turn while held
  space      stop
  [ / ]      steer every steerable wheel 15 deg (robot at rest)
  1 / 2 / 3  camera free (mouse) / top / follow
  4          camera run: straight down on all the runs shown (a replay's; a live page has none)
The side panel has the same controls (a twist held until Stop), camera presets, the pose,
twist and forward-kinematics residual, a table of the joints and a plot of the wheel speeds.
Every command passes the runtime's command filter: --max-speed, --max-turn, and --timeout
(a page that falls silent stops the robot). --echo prints a line per key action as it acts:
  T s  ACTION  x X m  y Y m  theta TH rad
(T: the simulated time of the control step it acts from, the step made at the key's arrival;
the true pose then), as 'omnikin sim --echo' does.

On a robot's own computer, serve to the network with --host 0.0.0.0 and open
http://ROBOT-ADDRESS:PORT/ on a laptop (anyone who reaches the port can drive the robot).

replay (--replay: no driving; keys 1/2/3/4 still move the camera, 4: all the runs shown):
  omnikin view --replay REPORT_DIR
      the runs of an 'omnikin umbmark' report folder (its run_poses.csv: before and after
      calibration, cw and ccw, every run of the first procedure); the report names its robot
      (true_robot.yaml, the robot as built that drove the runs), so give no ROBOT
  omnikin view ROBOT --replay BAG
      a ROS 2 bag (rosbag2 folder, .db3 or .mcap) of ROBOT: the true poses of
      --ground-truth-topic (default /ground_truth), the odometry of --odom-topic (default
      /odom), the wheel angles and steering of --joint-states-topic (default /joint_states; joint
      name = wheel name, W_steer for steering; without it, from the kinematics); the bags of
      'omnikin simulate ROBOT --path ... --bag OUT.bag' have all three
  omnikin view --replay before-report --replay after-report
      the runs of several reports (or several bags of ROBOT) on one page
The Replay folder has the run selector, a time slider, Play/Pause and the playback speed; the
whole true and odometry paths of the run are drawn, the robot at the slider's time; "shown
together" adds other runs (their paths, a see-through robot at the same time), and the camera
preset "run" frames them all.

live ROS (--ros): the page follows a running 'omnikin ros ROBOT' node in the same
ROS_DOMAIN_ID: the robot at its ground_truth (else its odometry), its odom and joint_states;
the keys, controls and goal publish cmd_vel (the node's limits and cmd_vel_timeout act).
  omnikin ros tomasi-omni3 &  omnikin view tomasi-omni3 --ros

paths (--path, or shift-click the floor; the Path folder's Follow starts it): the robot plans
the path from where it is, within its --max-speed and --max-turn and their accelerations, and
tracks it steering by its odometry; the path, its reference point and the error are drawn, and
any key, the Drive controls or a goal stop it.
  omnikin view tomasi-omni3 --path examples/waypoints.csv --blend 0.3
  omnikin view omni4 --path 'figure8 1'

examples:
  omnikin view tomasi-omni3
  omnikin view mecanum4 --engine physics --port 8081
  omnikin view ackermann --duration 60
  omnikin view --replay umbmark-report
  omnikin view tomasi-omni3 --replay run.bag"""


def add_parser(sub, robot_help: str) -> None:
    """Add ``view`` to ``sub``."""
    sp = sub.add_parser(
        "view",
        help="3D viewer in the browser: drive the robot with the keyboard, see its wheels and odometry",
        description="Serve a web page with the robot in 3D (drawn from the physical description the "
        "physics engine uses: chassis, wheels, rollers, steering legs), its true and odometry "
        "trails on a ground grid with the UMBmark squares, and drive it with the keyboard or the "
        "page's controls through the runtime's command filter; or, with --replay, play back the runs of an "
        "UMBmark report or a ROS 2 bag with a timeline.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument(
        "robot", metavar="ROBOT", nargs="?", help=f"{robot_help} (not with --replay REPORT_DIR: the report names it)"
    )
    sp.add_argument(
        "--engine",
        choices=ENGINE_NAMES,
        help="kinematic (default): moved exactly by its wheels; physics: MuJoCo with rollers (extra physics)",
    )
    sp.add_argument(
        "--ros",
        action="store_true",
        help="follow a running 'omnikin ros ROBOT' node (odom, joint_states, ground_truth) in ROS_DOMAIN_ID "
        "and drive it: the page's commands go to its cmd_vel (extra ros)",
    )
    sp.add_argument(
        "--stamped", action="store_true", help="--ros: send geometry_msgs/TwistStamped (the node's use_stamped_vel)"
    )
    sp.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1: this computer only)")
    sp.add_argument(
        "--port", type=whole, default=8080, metavar="PORT", help="port to serve on (default 8080; 0: any free)"
    )
    add_teleop_options(sp)
    sp.add_argument(
        "--timeout",
        type=number,
        metavar="S",
        help="command timeout [s] (default 0.5; 0: none; with --ros the node's cmd_vel_timeout applies)",
    )
    sp.add_argument(
        "--umbmark-side",
        type=number,
        default=UMBMARK_SIDE,
        metavar="M",
        help="side of the UMBmark squares drawn [m] (0: none)",
    )
    sp.add_argument("--duration", type=number, metavar="S", help="stop serving after S seconds (default: Ctrl-C)")
    sp.add_argument(
        "--echo",
        action="store_true",
        help="print each key's action on stdout as it acts: simulated time, action, true pose (as omnikin sim)",
    )
    add_step_option(sp, "time step of the physics engine (--engine physics)")
    add_world_option(sp)
    path = sp.add_argument_group("paths")
    path.add_argument(
        "--path",
        metavar="PATH",
        help="a path to follow: a path file of waypoints (.csv, .yaml, as omnikin track's) or a built-in path "
        "('figure8 1', 'circle 0.5', 'square 1'); the Path folder's Follow starts it",
    )
    path.add_argument("--blend", type=number, metavar="R", help="--path file: cut the corners by arcs of radius R [m]")
    path.add_argument("--smooth", action="store_true", help="--path file: a smooth curve through the waypoints")
    replay = sp.add_argument_group("replay")
    replay.add_argument(
        "--replay",
        metavar="REPORT_DIR|BAG",
        action="append",
        help="play back the runs of an omnikin umbmark report folder, or a ROS 2 bag of ROBOT (see below); "
        "again: the runs of several, shown together",
    )
    for role, default in (("ground-truth", "/ground_truth"), ("odom", "/odom"), ("joint-states", "/joint_states")):
        replay.add_argument(
            f"--{role}-topic", default=default, metavar="TOPIC", help=f"--replay BAG: {role} topic (default {default})"
        )
    add_budget_options(sp, time=False)
    declare_inputs(sp, "replay", "path", "world", robots=("robot",))  # (a built-in path names no file: harmless)
    sp.set_defaults(func=run)


def require_viser():
    """The viewer's library, or one line naming the extra."""
    try:
        import viser
    except ImportError as e:
        from ..errors import InputError

        raise InputError(f'omnikin view needs viser: pip install "omnikin[viewer]" ({e})') from None
    return viser


def run(args) -> int:
    """Serve the page (live, ``--ros`` or ``--replay``) until the user stops it; status 0."""
    from ..errors import InputError

    limits = teleop_limits(args)
    if args.timeout is not None and args.timeout < 0:
        raise InputError(f"--timeout must be >= 0, got {args.timeout:g}")
    if args.umbmark_side != 0:
        from ..evaluation.umbmark import check_side

        check_side(args.umbmark_side, "--umbmark-side (0: none)")
    if args.duration is not None and args.duration <= 0:
        raise InputError(f"--duration must be positive [s], got {args.duration:g}")
    if not 0 <= args.port <= 65535:
        raise InputError(f"--port must be 0 to 65535, got {args.port}")
    waypoints, path_options = _path_of(args)
    if waypoints is not None and (args.replay is not None or args.ros):
        raise InputError(
            "--path is followed by the simulated robot of a live page (not --replay; with --ros the node "
            "follows a nav_msgs/Path on its plan topic)"
        )
    if args.replay is not None:
        if args.ros:
            raise InputError("--ros and --replay are two different views: give one of them")
        if args.echo:
            raise InputError("--echo does not apply to --replay (no keys drive a replay)")
        return _run_replay(args)
    if args.robot is None:
        raise InputError("view: give ROBOT (a preset name or a robot file), or --replay REPORT_DIR")
    if args.stamped and not args.ros:
        raise InputError("--stamped applies only to --ros")
    if args.ros:
        if args.echo:
            raise InputError("--echo does not apply to --ros (the node keeps the time; see its topics)")
        return _run_ros_view(args, limits)
    if args.step is not None and args.engine != "physics":
        raise InputError("--step applies only to --engine physics")
    require_viser()
    robot = load_robot(args.robot)
    engine = engine_of(args, args.engine or "kinematic")  # --step checked
    from ..viewer.live import LiveRobot

    live = LiveRobot(
        robot,
        engine,
        speed=args.speed,
        turn=args.turn,
        limits=limits,
        timeout=0.5 if args.timeout is None else args.timeout,
    )
    live.tell = lambda line: print(f"omnikin view: {line}", file=sys.stderr, flush=True)  # a robot that fell
    live.echo = sys.stdout if args.echo else None
    return serve_live(live, args, f"{robot.name} ({engine.name})", waypoints=waypoints, path_options=path_options)


def _path_of(args):
    """``--path`` as waypoints ``(n, 2|3)`` [m, m, rad] and the Follow options (``smooth``,
    ``blend``), or ``(None, {})``: a path file's waypoints as written (a closed one back to its
    first), corners as ``--blend`` and ``--smooth`` say (default: stopped at, as omnikin track);
    a built-in path's samples every centimetre with their headings, followed as a smooth curve."""
    from ..errors import InputError

    if args.path is None:
        if args.blend is not None or args.smooth:
            raise InputError("--blend and --smooth shape a --path file; give --path")
        return None, {}
    import numpy as np

    from ..control.path import parse_path
    from ..io.path_file import is_path_file, read_waypoints

    if is_path_file(args.path):
        if args.smooth and args.blend:
            raise InputError("--smooth and --blend: a smooth path has no corners to blend; give one")
        if args.blend is not None and not (0 <= args.blend <= 100):
            raise InputError(f"--blend must be in [0, 100] m, got {args.blend:g}")
        xy, theta, closed = read_waypoints(args.path)
        waypoints = xy if theta is None else np.column_stack((xy, theta))
        if closed:
            waypoints = np.vstack((waypoints, waypoints[:1]))
        return waypoints, {"smooth": bool(args.smooth), "blend": args.blend or 0.0}
    if args.blend is not None or args.smooth:
        raise InputError("--blend and --smooth are for path files; a built-in path takes its shape from its numbers")
    path = parse_path(args.path)
    step = max(1, int(round(0.01 / max(float(path.s[-1]) / max(len(path.s) - 1, 1), 1e-9))))
    index = np.unique(np.append(np.arange(0, len(path.s), step), len(path.s) - 1))
    return path.pose[index], {"smooth": True}


def serve_live(live, args, what: str, *, waypoints=None, path_options: dict | None = None) -> int:
    """Serve the live page of ``live`` (a :class:`~omnikin.viewer.live.PageRobot`) until
    --duration or Ctrl-C; ``what`` names it in the line with the address; ``waypoints`` and
    ``path_options`` a path to follow (:func:`_path_of`)."""
    from ..viewer.app import LiveViewer

    try:
        viewer = LiveViewer(
            live, args.host, args.port, umbmark_side=args.umbmark_side, waypoints=waypoints, path_options=path_options
        )
    except BaseException:
        live.close()
        raise
    return serve(viewer, args, what)


def serve(viewer, args, what: str) -> int:
    """Print where ``viewer`` (a live or replay page) is served, run it until --duration or
    Ctrl-C, and close it whatever happens."""
    try:
        print(f"omnikin view: {what} at {viewer.url}  (Ctrl-C stops)", flush=True)
        wildcard_note(args.host, viewer.servers.front.port)
        viewer.run(args.duration)
    finally:
        viewer.close()
        inputs = viewer.servers.inputs
        if inputs.refused:  # what pages sent that was refused (each page was told at the time)
            print(
                f"omnikin view: refused {inputs.refused} input(s) from pages; the last: {inputs.last}", file=sys.stderr
            )
    sys.stdout.flush()
    return 0


def wildcard_note(host: str, port: int) -> None:
    """Say so when the page is served on every network this computer is on."""
    if host in ("", "0.0.0.0", "::"):
        print(
            f"omnikin view: note: serving every network interface: anyone who reaches port {port} can drive "
            "the robot (--host 127.0.0.1 serves this computer only)",
            file=sys.stderr,
        )


def _run_ros_view(args, limits) -> int:
    """``--ros``: the page follows and drives a running node (:mod:`omnikin.viewer.ros_robot`)."""
    import os

    from ..errors import InputError

    for flag, given in (("--engine", args.engine), ("--step", args.step), ("--timeout", args.timeout)):
        if given is not None:
            raise InputError(f"{flag} does not apply to --ros (the node simulates or drives the robot)")
    require_viser()
    from ..viewer.ros_robot import RosRobot, require_ros

    require_ros()
    robot = load_robot(args.robot)
    live = RosRobot(
        robot,
        speed=args.speed,
        turn=args.turn,
        limits=limits,
        stamped=args.stamped,
    )
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    return serve_live(live, args, f"the ROS node of {robot.name} (ROS_DOMAIN_ID {domain})")


def _run_replay(args) -> int:
    from ..errors import InputError
    from ..io.bags import check_topic

    if args.engine is not None or args.step is not None or args.timeout is not None:
        flag = "--step" if args.step is not None else ("--engine" if args.engine is not None else "--timeout")
        raise InputError(f"{flag} does not apply to --replay (the runs are recorded, not simulated)")
    require_viser()
    from ..viewer.replay_page import ReplayViewer
    from ..viewer.replay_sources import BAG_TOPICS, combine, load_replay

    topics = {
        role: check_topic(getattr(args, f"{role}_topic"), f"--{role.replace('_', '-')}-topic")
        for role in ("ground_truth", "odom", "joint_states")
    }
    named = tuple(role for role, topic in topics.items() if topic != BAG_TOPICS[role])  # must be in the bag

    robot = load_robot(args.robot) if args.robot is not None else None
    budget = Budget.of(args)
    files = len(args.replay)  # --max-memory is shared by the files
    source = combine(
        [
            load_replay(
                path,
                robot,
                topics,
                required=named,
                max_messages=max(1, budget.messages(POSE_BYTES) // files),
                max_message_bytes=int(budget.memory // (LARGEST_MESSAGE_SHARE * files)),
            )
            for path in args.replay
        ]
    )
    for note in source.notes:
        print(f"omnikin view: {note}", file=sys.stderr)
    viewer = ReplayViewer(source, args.host, args.port)
    runs = len(source.tracks)
    return serve(viewer, args, f"replay of {source.label} ({source.robot.name}, {runs} run{'s' if runs != 1 else ''})")
