"""``omnikin mjcf``: the robot's physical model as MuJoCo's MJCF (:func:`omnikin.physics.mjcf.mjcf`).

The model of :func:`omnikin.physics.description.describe` (``docs/physics.md``), written
without MuJoCo; the file goes through the output policy (:mod:`omnikin.io.output`: never an
input, an existing file only with ``--force``, written whole or not at all; ``-`` is standard
output).
"""

from __future__ import annotations

import argparse

from .common import add_output, add_output_options, add_step_option, declare_inputs, load_robot, write_model

MJCF_EPILOG = """examples:
  omnikin mjcf tomasi-omni3 -o tomasi.xml
  python -m mujoco.viewer --mjcf tomasi.xml
  omnikin mjcf my_robot.yaml -o - --step 0.001 | head

The model: a floor, the chassis on a free joint (its frame the robot's body frame, origin on
the floor), wheel joints named as the wheels, steering joints NAME_steer, ellipsoid rollers on
Swedish wheels, velocity servos with the motors' torque and speed limits (docs/physics.md)."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``mjcf`` to ``sub``."""
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
    sp.set_defaults(func=run)


def run(args) -> int:
    """Write the MJCF model; status 0."""
    from ..physics.mjcf import mjcf, time_step

    robot = load_robot(args.robot)
    return write_model(args, mjcf(robot, time_step(args.step, "--step")), f"MJCF model of {robot.name}")
