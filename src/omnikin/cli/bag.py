"""``omnikin bag``: its commands ``bag odometry`` (wheel odometry from joint states into a new bag)
and ``bag export`` (a pose topic as a trajectory file).

Bags are ROS 2 bags (rosbag2 directories with sqlite3 or MCAP storage, or a bare ``.mcap`` /
``.db3`` file), read and written with the ``rosbags`` package (``pip install "omnikin[bags]"``);
see :mod:`omnikin.io.bags`.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from ..errors import InputError
from .budget import LARGEST_MESSAGE_SHARE, MESSAGE_SECONDS, POSE_BYTES, Budget, add_budget_options, explained, require
from .common import (
    add_method_option,
    add_output,
    add_output_options,
    add_wheel_bound_options,
    console,
    declare_inputs,
    load_robot,
    number,
    print_json,
)

JOINT_STATE_BYTES = 400
"""bag odometry: per JointState message read, its odometry and the Odometry written (measured 303;
the costs of reading a bag are in :mod:`omnikin.cli.budget`)."""

BAG_EPILOG = """examples:
  omnikin bag odometry tomasi-omni3 run.bag -o odom.bag
  omnikin bag odometry my_robot.yaml run.mcap -o odom.bag --joint-states-topic /wheels/joint_states \\
      --odom-topic /wheel_odom --method exact --storage mcap
  omnikin bag export odom.bag --topic /odom --format tum -o odom.tum
  omnikin bag export sim.bag --topic /ground_truth --format kitti > truth.kitti

joint names = wheel names of the robot file (positions in rad, positive drives the hub along
its drive direction); a steerable wheel W needs a joint W_steer [rad]. Output: nav_msgs/Odometry
in frame 'odom' with child 'base_link' (REP-105), twist in body axes (REP-103)."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``bag`` to ``sub``, with its commands ``odometry`` and ``export``."""
    bag = sub.add_parser(
        "bag",
        help="ROS 2 bags: wheel odometry from joint states, export of pose topics",
        description="Work with ROS 2 bags (rosbag2: sqlite3 or MCAP); needs the rosbags package "
        '(pip install "omnikin[bags]").',
        epilog=BAG_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    bag.set_defaults(func=run, bag_parser=bag)
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
    sp.set_defaults(func=run_odometry)

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
    sp.set_defaults(func=run_export)


def _covariance(diag):
    return None if diag is None else np.asarray(diag, dtype=float)


# --- bag ----------------------------------------------------------------------------------------------
def run(args) -> int:
    """``omnikin bag`` without a command: an error naming them (status 2)."""
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


def run_odometry(args) -> int:
    """``omnikin bag odometry``: write the odometry bag, print a summary (or ``--json``); status 0."""
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


def run_export(args) -> int:
    """``omnikin bag export``: write the poses of the topic; status 0."""
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
