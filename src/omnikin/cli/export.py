"""``omnikin mjcf`` and ``omnikin urdf``: the robot's physical model as MuJoCo's MJCF or as URDF.

Both write the model of :func:`omnikin.physics.description.describe` (``docs/physics.md``):
:func:`omnikin.physics.mjcf.mjcf` and :func:`omnikin.physics.urdf.urdf`, neither of which
needs MuJoCo or ROS. The file goes through the output policy (:mod:`omnikin.io.output`:
never an input, an existing file only with ``--force``, written whole or not at all; ``-``
is standard output).
"""

from __future__ import annotations

import argparse

from .common import add_output, add_output_options, add_step_option, console, declare_inputs, load_robot

MJCF_EPILOG = """examples:
  omnikin mjcf tomasi-omni3 -o tomasi.xml
  python -m mujoco.viewer --mjcf tomasi.xml
  omnikin mjcf my_robot.yaml -o - --step 0.001 | head

The model: a floor, the chassis on a free joint (its frame the robot's body frame, origin on
the floor), wheel joints named as the wheels, steering joints NAME_steer, ellipsoid rollers on
Swedish wheels, velocity servos with the motors' torque and speed limits (docs/physics.md)."""

URDF_EPILOG = """examples:
  omnikin urdf tomasi-omni3 -o tomasi.urdf
  omnikin urdf ackermann -o - | check_urdf /dev/stdin

Links: base_link (the body frame, origin on the floor), NAME_wheel on a continuous joint NAME
(axis along the axle), NAME_fork on NAME_steer for steered wheels and castors, NAME_roller_ROW_K
for the rollers of Swedish wheels. Joint names are those of the ROS node's joint_states. URDF has
no ellipsoids: tyres are cylinders, rollers cylinders (drawn) and spheres (collision)."""


def add_parsers(sub, robot_help: str) -> None:
    """Add ``mjcf`` and ``urdf`` to ``sub``."""
    sp = sub.add_parser(
        "mjcf",
        help="the robot's physical model as MuJoCo XML (MJCF)",
        description="Write the physical model of ROBOT (chassis, wheels, rollers, joints, motors; "
        "docs/physics.md) as a MuJoCo MJCF file that MuJoCo loads as it is.",
        epilog=MJCF_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    add_output(sp, "-o", "--output", required=True, metavar="OUT.xml", help="file to write ('-': standard output)")
    add_step_option(sp, "simulation time step")
    add_output_options(sp)
    declare_inputs(sp, robots=("robot",))
    sp.set_defaults(func=cmd_mjcf)

    sp = sub.add_parser(
        "urdf",
        help="the robot's physical model as URDF",
        description="Write the physical model of ROBOT (chassis, wheels, rollers, joints, masses and "
        "inertias; docs/physics.md) as a URDF file for ROS tools.",
        epilog=URDF_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    add_output(sp, "-o", "--output", required=True, metavar="OUT.urdf", help="file to write ('-': standard output)")
    add_output_options(sp)
    declare_inputs(sp, robots=("robot",))
    sp.set_defaults(func=cmd_urdf)


def _write(args, text: str, what: str) -> int:
    from ..io.output import is_stdout, write_text

    write_text(args.output, text)
    if not is_stdout(args.output):
        console().print(f"{what} written to {args.output}")
    return 0


def cmd_mjcf(args) -> int:
    from ..physics.mjcf import mjcf, time_step

    robot = load_robot(args.robot)
    return _write(args, mjcf(robot, time_step(args.step, "--step")), f"MJCF model of {robot.name}")


def cmd_urdf(args) -> int:
    from ..physics.urdf import urdf

    robot = load_robot(args.robot)
    return _write(args, urdf(robot), f"URDF of {robot.name}")
