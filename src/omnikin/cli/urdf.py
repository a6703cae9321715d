"""``omnikin urdf``: the robot's physical model as URDF (:func:`omnikin.physics.urdf.urdf`).

The model of :func:`omnikin.physics.description.describe` (``docs/physics.md``), written
without ROS; the file goes through the output policy (:mod:`omnikin.io.output`: never an
input, an existing file only with ``--force``, written whole or not at all; ``-`` is standard
output).
"""

from __future__ import annotations

import argparse

from .common import add_output, add_output_options, declare_inputs, load_robot, write_model

URDF_EPILOG = """examples:
  omnikin urdf tomasi-omni3 -o tomasi.urdf
  omnikin urdf ackermann -o - | check_urdf /dev/stdin

Links: base_link (the body frame, origin on the floor), NAME_wheel on a continuous joint NAME
(axis along the axle), NAME_fork on NAME_steer for steered wheels and castors, NAME_roller_ROW_K
for the rollers of Swedish wheels. Joint names are those of the ROS node's joint_states. URDF has
no ellipsoids: tyres are cylinders, rollers cylinders (drawn) and spheres (collision)."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``urdf`` to ``sub``."""
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
    sp.set_defaults(func=run)


def run(args) -> int:
    """Write the URDF; status 0."""
    from ..physics.urdf import urdf

    robot = load_robot(args.robot)
    return write_model(args, urdf(robot), f"URDF of {robot.name}")
