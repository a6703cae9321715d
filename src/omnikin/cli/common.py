"""Helpers shared by the sub-commands: the robot, the console, outputs and JSON.

Outputs (the policy is :mod:`omnikin.io.output`): a command that writes files calls
:func:`add_output_options` on its parser (``--force``), :func:`checked_output` for each output
before any long work (an input is never an output; an existing file needs ``--force``), writes
through the writers of :mod:`omnikin.io` (atomic), and prints its messages with
:func:`messages_console`, which goes to standard error when an output is ``-`` (standard
output then carries the data only). ``--json`` documents are printed with :func:`print_json`
(strict JSON: a non-finite number is an error naming the field).
"""

from __future__ import annotations

from pathlib import Path

from ..io.output import check_output, is_stdout

FORCE_HELP = "replace existing output files (never an input; a folder only if omnikin wrote it)"


def robot_as_built(robot, true_robot: str | None, errors: str, seed):
    """The robot as built and the errors drawn: a ``--true-robot`` file, or ``robot`` with a
    seeded draw of the ``--errors`` profile (:func:`omnikin.api.common.as_built`, the draw the
    Python API and ``omnikin umbmark`` make). ``seed``: a SeedSequence or an int."""
    from ..api.common import as_built

    return as_built(robot, true_robot or None, errors, seed)


def console(width: int = 140, stderr: bool = False):
    """A rich console without markup or highlighting; ``width`` columns when not a terminal."""
    from rich.console import Console

    con = Console(highlight=False, markup=False, stderr=stderr)
    if not con.is_terminal:
        con = Console(highlight=False, markup=False, width=width, stderr=stderr)
    return con


def messages_console(*outputs, width: int = 120):
    """The console for a command's messages and tables: standard error when one of ``outputs``
    is ``-`` (standard output carries the data only), else standard output."""
    return console(width, stderr=any(o is not None and is_stdout(o) for o in outputs))


def load_robot(spec):
    """A preset or robot file (:func:`omnikin.io.robot_file.load_robot`, imported on use)."""
    from ..io.robot_file import load_robot as load

    return load(spec)


# --- outputs -----------------------------------------------------------------------------------------
def add_output_options(parser) -> None:
    """Add ``--force`` to a command that writes files (see the module docstring)."""
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)


def checked_output(args, path, inputs=(), *, folder: bool | str = False) -> Path | None:
    """:func:`omnikin.io.output.check_output` of ``path`` with ``--force`` from ``args``: call it
    before any long work. ``inputs``: every file or folder the command reads (robot files
    included). Returns the path (None for ``-``)."""
    return check_output(
        path, inputs=[i for i in inputs if i is not None], force=bool(getattr(args, "force", False)), folder=folder
    )


def robot_inputs(*specs) -> list:
    """The robot files among robot specs (a preset name is never a file:
    :func:`omnikin.io.robot_file.robot_file_of`)."""
    from ..io.robot_file import robot_file_of

    return [f for f in map(robot_file_of, specs) if f is not None]


# --- JSON ------------------------------------------------------------------------------------------------
def print_json(data, *, nullable=()) -> None:
    """Print ``data`` as strict JSON on standard output (:func:`omnikin.io.jsonfile.to_json`;
    ``nullable``: fields whose non-finite values print as null)."""
    from ..io.jsonfile import to_json

    text = to_json(data, nullable=nullable)
    print(text)


def add_method_option(parser) -> None:
    """``--method exact|midpoint|euler``: the pose integration of the odometry commands."""
    parser.add_argument(
        "--method",
        choices=("exact", "midpoint", "euler"),
        default="exact",
        help="pose integration (default exact; the others exist for comparison)",
    )
