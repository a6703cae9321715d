"""``omnikin view``: the robot in 3D in the browser, driven from the page (extra ``viewer``)."""

from __future__ import annotations

import argparse
import sys

from .common import add_step_option, declare_inputs, load_robot, number, whole

EPILOG = """the page (open the printed address in a browser; click the scene so that it has the keys):
  W / S      drive forward / back at --speed while held
  A / D      drive left / right at --speed while held (robots with fixed wheels cannot)
  Q / E      turn counter-clockwise / clockwise at --turn while held
  space      stop
  [ / ]      steer every steerable wheel 15 deg (robot at rest)
  1 / 2 / 3  camera free (mouse) / top / follow
The side panel has the same controls (a twist held until Stop), camera presets, the pose,
twist and forward-kinematics residual, a table of the joints and a plot of the wheel speeds.
Every command passes the runtime's command filter: --max-speed, --max-turn, and --timeout
(a page that falls silent stops the robot).

On a robot's own computer, serve to the network with --host 0.0.0.0 and open
http://ROBOT-ADDRESS:PORT/ on a laptop (anyone who reaches the port can drive the robot).

examples:
  omnikin view tomasi-omni3
  omnikin view mecanum4 --engine physics --port 8081
  omnikin view ackermann --duration 60"""


def add_parsers(sub, robot_help: str) -> None:
    sp = sub.add_parser(
        "view",
        help="3D viewer in the browser: drive the robot with the keyboard, see its wheels and odometry",
        description="Serve a web page with the robot in 3D (drawn from the physical description the "
        "physics engine uses: chassis, wheels, rollers, steering legs), its true and odometry "
        "trails on a ground grid with the UMBmark squares, and drive it with the keyboard or the "
        "page's controls through the runtime's command filter.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument(
        "--engine",
        choices=("kinematic", "physics"),
        default="kinematic",
        help="kinematic: moved exactly by its wheels; physics: MuJoCo with rollers (extra physics)",
    )
    sp.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1: this computer only)")
    sp.add_argument(
        "--port", type=whole, default=8080, metavar="PORT", help="port to serve on (default 8080; 0: any free)"
    )
    sp.add_argument("--speed", type=number, default=0.2, metavar="V", help="speed of W/S/A/D [m/s] (default 0.2)")
    sp.add_argument("--turn", type=number, default=0.5, metavar="W", help="turn rate of Q/E [rad/s] (default 0.5)")
    sp.add_argument("--max-speed", type=number, default=0.3, metavar="V", help="speed limit [m/s] (default 0.3)")
    sp.add_argument("--max-turn", type=number, default=1.0, metavar="W", help="turn rate limit [rad/s] (default 1)")
    sp.add_argument(
        "--timeout", type=number, default=0.5, metavar="S", help="command timeout [s] (default 0.5; 0: none)"
    )
    sp.add_argument(
        "--umbmark-side", type=number, default=4.0, metavar="M", help="side of the UMBmark squares drawn [m] (0: none)"
    )
    sp.add_argument("--duration", type=number, metavar="S", help="stop serving after S seconds (default: Ctrl-C)")
    add_step_option(sp, "time step of the physics engine (--engine physics)")
    declare_inputs(sp, robots=("robot",))
    sp.set_defaults(func=cmd_view)


def require_viser():
    """The viewer's library, or one line naming the extra."""
    try:
        import viser
    except ImportError as e:
        from ..errors import InputError

        raise InputError(f'omnikin view needs viser: pip install "omnikin[viewer]" ({e})') from None
    return viser


def cmd_view(args) -> int:
    from ..errors import InputError
    from ..limits import MotionLimits

    positive = (
        ("--speed", args.speed),
        ("--turn", args.turn),
        ("--max-speed", args.max_speed),
        ("--max-turn", args.max_turn),
    )
    for flag, value in positive:
        if value <= 0:
            raise InputError(f"{flag} must be positive, got {value:g}")
    for flag, value in (("--timeout", args.timeout), ("--umbmark-side", args.umbmark_side)):
        if value < 0:
            raise InputError(f"{flag} must be >= 0, got {value:g}")
    if args.duration is not None and args.duration <= 0:
        raise InputError(f"--duration must be positive [s], got {args.duration:g}")
    if args.port > 65535:
        raise InputError(f"--port must be 0 to 65535, got {args.port}")
    if args.step is not None and args.engine != "physics":
        raise InputError("--step applies only to --engine physics")
    require_viser()
    robot = load_robot(args.robot)
    if args.step is not None:
        from ..physics.mjcf import time_step

        time_step(args.step)
    from ..viewer.app import LiveViewer
    from ..viewer.live import LiveRobot

    live = LiveRobot(
        robot,
        args.engine,
        speed=args.speed,
        turn=args.turn,
        limits=MotionLimits(linear=args.max_speed, angular=args.max_turn),
        timeout=args.timeout,
        step=args.step,
    )
    try:
        viewer = LiveViewer(live, args.host, args.port, umbmark_side=args.umbmark_side)
    except BaseException:
        live.close()
        raise
    try:
        print(f"omnikin view: {robot.name} ({args.engine}) at {viewer.url}  (Ctrl-C stops)", flush=True)
        viewer.run(args.duration)
    finally:
        viewer.close()
    sys.stdout.flush()
    return 0
