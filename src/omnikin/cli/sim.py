"""``omnikin sim``: drive a robot from the keyboard in MuJoCo's viewer window (extra ``physics``)."""

from __future__ import annotations

import argparse
import sys

from .common import (
    add_as_built_options,
    add_output,
    add_output_options,
    add_teleop_options,
    add_world_option,
    check_seed,
    declare_inputs,
    load_robot,
    number,
    robot_as_built,
    run_streams,
    teleop_limits,
)
from .process import until_stopped

EPILOG = """keys (the window must have the keyboard focus):
  W / S      drive forward / back at --speed (sets vx; the other components stay)
  A / D *    drive left / right at --speed (sets vy)
  Q / E *    turn counter-clockwise / clockwise at --turn (sets omega)
  space      stop (the target twist becomes zero)
  [ / ]      steer every steerable wheel 15 deg clockwise / counter-clockwise (robot at rest;
             the next move steers as the kinematics needs)
  1 / 2 / 3  camera: free (mouse: left drag rotates, right drag moves, wheel zooms) / top (down
             on where the robot stood) / follow (tracks the chassis from behind)

* not obeyed by every layout (the window marks them and says why when one is pressed):
  A / D      not on robots with fixed wheels, which cannot move sideways (presets: ackermann,
             diff-drive): the command filter drops vy
  Q / E      not alone on robots that cannot turn on the spot (presets: ackermann,
             villasenor-omni3): refused; held with W or S they drive an arc

A move key drives while it is held: letting it go sets its component back to zero, space
stops everything. (Should the window report presses only, a press sets the target until
another key changes it, or with --hold S for S seconds, when the command timeout stops the
robot.) Every target passes the runtime's command filter: speed limits --max-speed and
--max-turn, acceleration limits. The window shows the simulated time and the real-time factor,
true pose, odometry pose, twist, wheel speeds and steering, a green arrow along the robot's true
heading and a narrower magenta one at the pose its wheel odometry estimates (they part on a
robot as built with errors, --errors or --true-robot, and where the wheels slip).

Time: a key acts at the simulated time of its arrival; on a machine that cannot keep up the
simulation falls behind the clock (the window says so) and catches up, so a key held for 2 s
drives 2 s of simulated motion whatever the load. --duration counts simulated seconds.

examples:
  omnikin sim tomasi-omni3
  omnikin sim villasenor-omni3 --camera follow
  omnikin sim diff-drive --errors typical --seed 3      odometry (magenta) beside the truth (green)
  omnikin sim tomasi-omni3 --world examples/worlds/room.yaml     walls, furniture, a crate to push
  xvfb-run -a omnikin sim omni4 --duration 10 --report run.json     without a screen"""


def add_parser(sub, robot_help: str) -> None:
    """Add ``sim`` to ``sub``."""
    sp = sub.add_parser(
        "sim",
        help="interactive simulator: drive a robot from the keyboard in MuJoCo's viewer",
        description="Open the robot's physics model (docs/physics.md) in MuJoCo's viewer window and "
        "drive it from the keyboard through the runtime's command filter and limits.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument(
        "--duration",
        type=number,
        metavar="S",
        help="close the window after S seconds of simulated time (default: never)",
    )
    sp.add_argument("--camera", choices=("free", "top", "follow"), default="free", help="first camera (default free)")
    add_as_built_options(sp, default_errors="none")
    add_world_option(sp)
    add_teleop_options(sp)
    sp.add_argument(
        "--hold", type=number, default=0.0, metavar="S", help="a press drives for S seconds (default 0: until changed)"
    )
    sp.add_argument(
        "--echo",
        action="store_true",
        help="print each key's action on stdout as it acts: simulated time, action, true pose",
    )
    add_output(
        sp,
        "--report",
        metavar="FILE.json",
        help="write what the run did as JSON (final pose and steering, keys pressed)",
    )
    add_output_options(sp)
    declare_inputs(sp, "world", robots=("robot", "true_robot"))
    sp.set_defaults(func=run)


def run(args) -> int:
    """Open the window and drive until it closes or the user stops it, write ``--report``; status 0."""
    from ..errors import InputError
    from ..io.jsonfile import to_json
    from ..io.output import write_text

    if args.duration is not None and args.duration <= 0:
        raise InputError(f"--duration must be positive [s], got {args.duration:g}")
    if args.hold < 0:
        raise InputError(f"--hold must be >= 0 [s], got {args.hold:g}")
    check_seed(args.seed)
    limits = teleop_limits(args)
    from ..io.world_file import load_world
    from ..physics.cost import real_time_shortfall
    from ..physics.interactive import InteractiveSim, require_display

    require_display()  # before the model is built: the one line comes at once
    robot = load_robot(args.robot)
    # the robot as built that `omnikin simulate` and `omnikin ros` draw for the same --seed
    true_robot, _ = robot_as_built(robot, args.true_robot, args.errors, run_streams(args.seed)["robot"])
    slow = real_time_shortfall(robot, "the simulation will run slower than the clock")
    if slow:
        print(f"omnikin: note: sim: {slow}", file=sys.stderr)
    sim = InteractiveSim(
        robot,
        true_robot=true_robot,
        speed=args.speed,
        turn=args.turn,
        hold=args.hold,
        camera=args.camera,
        limits=limits,
        echo=sys.stdout if args.echo else None,
        world=load_world(args.world) if args.world is not None else None,
    )
    reason = "stopped"  # Ctrl-C or SIGTERM: the normal end of a window (the report is still written)
    with until_stopped():
        reason = sim.run(args.duration)
    if args.report:
        write_text(args.report, to_json(sim.report(reason)) + "\n")
    return 0
