"""``omnikin``: command-line entry point.

Every sub-command takes ROBOT = a preset name (``omnikin presets``) or a robot file. The parser
is built from the command modules (:data:`COMMANDS`, in the order ``omnikin --help`` lists
them; their shape: :mod:`omnikin.cli`); the process around a command (one-line errors and exit
statuses, signals, standard streams) is :mod:`omnikin.cli.process`.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from .._version import __version__
from ..presets import PRESET_NAMES
from . import process
from .parser import CommandParser

EPILOG = """examples:
  omnikin presets                          list the robots shipped with omnikin
  omnikin show tomasi-omni3                geometry, IK/FK matrices, mobility analysis
  omnikin show my_robot.yaml --plot layout.png
  omnikin ik tomasi-omni3 0.2 0 0.5        wheel speeds [rad/s] for vx vy omega
  omnikin ik ackermann 1 0 0.3 --json      steering angles too
  omnikin fk tomasi-omni3 10 -5 -5         body twist from wheel speeds
  omnikin odometry tomasi-omni3 log.csv -o traj.tum --format tum
  omnikin umbmark                          the main job: UMBmark, calibration, report
  omnikin umbmark analyze measured.csv --robot diff-drive
  omnikin calibrate tomasi-omni3 runs.csv -o calibrated.yaml
  omnikin simulate tomasi-omni3 --bag sim.bag      simulated run recorded to a ROS 2 bag
  omnikin track tomasi-omni3 'figure8 1' --plot fig.svg   drive a path at the wheels' limits
  omnikin bag odometry tomasi-omni3 run.bag -o odom.bag
  omnikin bag export sim.bag --topic /ground_truth --format tum -o truth.tum
  omnikin metrics truth.tum odom.tum --align       ATE and RPE (evo's definitions)
  omnikin ros tomasi-omni3                         the ROS 2 base driver (extra ros)
  omnikin sweep examples/tolerance.yaml -o study/  tolerance study on Dask (extra sweep)

units: SI and radians; degrees only where an option or column ends in -deg/_deg.
frames: body x forward, y left, angles counter-clockwise (REP-103).
negative numbers are values: omnikin ik tomasi-omni3 -2.5e-3 0 -1e-1 (-1E3, -.5 too).
options may come before, between or after the positional arguments.

output files: no command writes over one of its inputs, --force or not. An existing file is
  replaced only with --force; an existing folder only if omnikin wrote it (a report folder is
  replaced by the next run, a bag only with --force); omnikin never deletes anything else.
  Files are written whole or not at all (a temporary file beside them, renamed when complete).
  '-' is standard output, which then carries the data only: messages and tables go to stderr.
  The outputs of a command are checked together before it starts: no two on one path, none
  inside another, none the current folder, at most one on standard output (--json counts).
limits: commands whose size you choose (umbmark --trials/--runs, simulate --rate/--path, bags,
  trajectory files) are sized first and refused beyond --max-memory (default 2G) or --max-time
  (default 1h).
errors: one line 'omnikin: error: ...' on stderr; exit status 2 for bad input or usage, 1 when
  something fails while running (writing an output, a hardware link).
stopping: view, sim and ros serve until stopped: Ctrl-C or SIGTERM ends them normally (status 0,
  'omnikin view: stopped (Ctrl-C)'). Any other command stopped before it finished says
  'omnikin: interrupted' (status 130, Ctrl-C) or 'omnikin: terminated (SIGTERM)' (143: timeout,
  kill) and leaves no partial output (omnikin sweep keeps the tasks it finished, to resume from)."""


COMMANDS = (
    "presets",
    "show",
    "ik",
    "fk",
    "odometry",
    "umbmark",
    "calibrate",
    "bag",
    "simulate",
    "track",
    "metrics",
    "ros",
    "sim",
    "view",
    "sweep",
    "mjcf",
    "urdf",
    "tf2_msgs",
)
"""The command modules of :mod:`omnikin.cli` by name, each adding its command(s) with
``add_parser(sub, robot_help)``. They are imported by :func:`build_parser`, which
:mod:`omnikin.cli.process` calls while it handles Ctrl-C and SIGTERM: importing them (the
Python API behind them) is part of running a command, so a user who stops omnikin while it
starts gets ``omnikin: interrupted`` (130) rather than a traceback, and ``import
omnikin.cli.main`` stays as light as ``import omnikin``."""


def build_parser() -> CommandParser:
    """The parser of ``omnikin``: every command of :data:`COMMANDS` as a sub-command."""
    p = CommandParser(
        prog="omnikin",
        description="Kinematics and exact odometry for wheeled mobile robots of any wheel layout.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"omnikin {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    robot_help = (
        f"preset name ({', '.join(PRESET_NAMES)}) or robot file path (YAML/JSON, schema 1); a preset "
        "name always means the preset: write ./NAME for a file of the current folder named like one"
    )
    for name in COMMANDS:
        importlib.import_module(f"{__package__}.{name}").add_parser(sub, robot_help)
    return p


def main(argv=None) -> int:
    """Run ``omnikin`` with ``argv`` (default ``sys.argv[1:]``); returns the exit status
    (:func:`omnikin.cli.process.run`: one-line errors, signals, streams)."""
    return process.run(argv, build_parser)


if __name__ == "__main__":
    sys.exit(main())
