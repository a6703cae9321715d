"""``omnikin tf2-msgs``: build the ROS 2 message package ``tf2_msgs`` for a pip-only ROS 2
install (:func:`omnikin.ros.interfaces.build_tf2_msgs`), so that ``omnikin ros`` publishes
``/tf`` and ``/tf_static``.
"""

from __future__ import annotations

import argparse
import sys

from .common import whole

TF2_EPILOG = """examples:
  python3 -m pip install 'omnikin[ros,ros-build]' && omnikin tf2-msgs
  omnikin tf2-msgs --prefix ~/.cache/omnikin-tf2 --jobs 2     # then run the export lines it prints

The ROS 2 wheels on PyPI (the ros extra) have no tf2_msgs, the package of /tf. This command
builds its one message, tf2_msgs/msg/TFMessage, from its .msg with the rosidl generators of those
wheels (cmake 3.21 or later, make, gcc and g++, the Python headers; the ros-build extra's pip
packages) in about 30 s, and installs it beside the wheels: nothing else to set up. It has the
type hash of the ROS 2 Humble, Jazzy and Kilted TFMessage, so rviz2, slam_toolbox and Nav2 read
it. A second run with the same Python and wheels does nothing (--force builds again). From a
ROS 2 install (source /opt/ros/<distro>/setup.bash) tf2_msgs is there already: no need."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``tf2-msgs`` to ``sub``."""
    sp = sub.add_parser(
        "tf2-msgs",
        help="build tf2_msgs (/tf) for the ROS 2 wheels from PyPI",
        description="Build the ROS 2 message package tf2_msgs (/tf, /tf_static), which the ROS 2 wheels "
        "on PyPI lack, and install it beside them, so that omnikin ros publishes /tf from a pip-only install.",
        epilog=TF2_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument(
        "--prefix",
        metavar="DIR",
        help="install into DIR and print the environment a process needs to use it (default: this "
        "Python's own prefix, which needs none)",
    )
    sp.add_argument("--jobs", type=whole, default=1, metavar="N", help="compile jobs, 1 to 64 (default 1)")
    sp.add_argument("--force", action="store_true", help="build even when an up-to-date build is there")
    sp.set_defaults(func=run)


def run(args) -> int:
    """Build (or find up to date) and say where; the export lines on standard output."""
    from ..ros.interfaces import build_tf2_msgs

    def log(line: str) -> None:
        print(f"omnikin: {line}", file=sys.stderr, flush=True)

    build = build_tf2_msgs(args.prefix, jobs=args.jobs, force=args.force, log=log)
    if build.exports:
        log("to use it, run these lines in the shell that starts ROS 2 processes (before Python starts):")
        for line in build.exports:
            print(line)
    else:
        log("tf2_msgs is importable by this Python: omnikin ros now publishes /tf and /tf_static")
    return 0
