"""Helpers shared by the sub-commands: the robot, the console, outputs and JSON.

Outputs (the policy is :mod:`omnikin.io.output`): a command declares each option naming an
output with :func:`add_output` (a file, a report folder or a data folder) and the arguments
naming its inputs with :func:`declare_inputs`; :func:`add_output_options` adds ``--force``.
:mod:`omnikin.cli.process` runs the command in :func:`running`, which checks its declared
outputs together (:func:`check_command_outputs`) before the command runs: never an input, never two outputs on
the same path or one inside another, at most one thing on standard output (``--json``
counts), an existing file only with ``--force``. The command then writes through the writers
of :mod:`omnikin.io` (atomic, checked again) and prints its messages with
:func:`console`, which goes to standard error when an output is ``-`` (standard output then
carries the data only). ``--json`` documents are printed with :func:`print_json`
(strict JSON: a non-finite number is an error naming the field).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import re
from collections.abc import Iterator

import numpy as np

from ..common.messages import shorten
from ..common.number_text import number_problem
from ..errors import InputError
from ..io.output import Output, check_outputs, is_stdout

FORCE_HELP = "replace existing output files (never an input; a folder only if omnikin wrote it)"


def run_streams(seed: int) -> dict:
    """The random streams of ``--seed`` for a simulated robot, by name: ``robot`` (the robot as
    built, the draw ``omnikin simulate``, ``omnikin umbmark`` and the Python API make for the
    same seed) and ``run`` (its random errors), the layout
    :data:`~omnikin.evaluation.pipeline.RUN_STREAMS`."""
    from ..evaluation.pipeline import RUN_STREAMS
    from ..evaluation.procedure import streams

    return streams(seed, RUN_STREAMS)


def robot_as_built(robot, true_robot: str | None, errors: str, stream):
    """The robot as built and the errors drawn: a ``--true-robot`` file, or ``robot`` with a
    draw of the ``--errors`` profile from ``stream`` (a SeedSequence: the ``robot`` stream of
    :func:`run_streams`; :func:`omnikin.api.common.as_built`)."""
    from ..api.common import as_built

    return as_built(robot, true_robot or None, errors, stream)


def check_seed(seed: int | None) -> None:
    """Refuse a negative ``--seed`` (NumPy's seed sequences take whole numbers >= 0) in one line;
    None (not given) passes."""
    if seed is not None and seed < 0:
        raise InputError(f"--seed must be a whole number >= 0, got {seed}")


def as_built_group(parser):
    """The group ``--errors`` and ``--true-robot`` belong to: both give the robot as built, so the
    parser refuses the two together in one line ("argument --true-robot: not allowed with
    argument --errors"), whatever the command (a given ``--errors`` is never silently ignored)."""
    return parser.add_mutually_exclusive_group()


def add_as_built_options(parser, *, defaults: bool = True, scope: str = "", default_errors: str = "typical") -> None:
    """``--errors PROFILE``, ``--true-robot FILE`` and ``--seed N``: the robot as built
    (:func:`robot_as_built`: a seeded draw of the error profile, or a file replacing it).
    ``defaults``: ``default_errors`` and 1 filled in by the parser; else ``None`` (the command
    tells given options from absent ones, and fills in the same defaults). ``scope``: prefix of
    the help naming where the options apply (``"simulated back-ends: "``). The command refuses a
    negative seed with :func:`check_seed`."""
    from ..simulation.error_models import PROFILES

    group = as_built_group(parser)
    group.add_argument(
        "--errors",
        default=default_errors if defaults else None,
        metavar="PROFILE",
        help=f"{scope}systematic error profile of the robot as built: {', '.join(sorted(PROFILES))} "
        f"(default {default_errors})",
    )
    group.add_argument("--true-robot", metavar="FILE", help=f"{scope}the robot as built (replaces --errors)")
    parser.add_argument(
        "--seed",
        type=whole,
        default=1 if defaults else None,
        metavar="N",
        help=f"{scope}random seed (default 1)",
    )


def add_step_option(parser, what: str = "time step of the physics engine") -> None:
    """``--step SEC``, the physics engine's time step (default None: 2 ms, filled in and checked
    by :func:`omnikin.physics.mjcf.time_step`)."""
    from ..physics.mjcf import DEFAULT_STEP, STEP_RANGE

    parser.add_argument(
        "--step",
        type=number,
        metavar="SEC",
        help=f"{what} [s], {STEP_RANGE[0]:g} to {STEP_RANGE[1]:g} (default {DEFAULT_STEP:g})",
    )


def add_world_option(parser) -> None:
    """``--world FILE``: the world the robot drives in (``docs/world.md``), read by :func:`engine_of`."""
    parser.add_argument(
        "--world",
        metavar="FILE",
        help="a world file (docs/world.md): walls, obstacles and floor patches around the robot, which starts "
        "at the world's start pose and stops at walls (default: an empty floor)",
    )


def engine_of(args, name: str | None = None):
    """The :class:`~omnikin.simulation.engine.Engine` the parsed options choose: ``--engine``
    (or ``name``, for a command that names it otherwise) made with ``--noise``, ``--step`` and
    ``--world`` where the command has them (:func:`omnikin.physics.engines.engine_named`: each
    engine refuses the other's option in one line). The one place a command turns the name into
    an engine; everything after holds the object."""
    from ..physics.engines import engine_named

    world = None
    if getattr(args, "world", None) is not None:
        from ..io.world_file import load_world

        world = load_world(args.world)
    return engine_named(
        args.engine if name is None else name,
        noise=getattr(args, "noise", None),
        step=getattr(args, "step", None),
        world=world,
    )


def add_teleop_options(parser) -> None:
    """``--speed``, ``--turn`` (what a held key sets) and ``--max-speed``, ``--max-turn`` (the
    runtime's limits) of the commands driven from the keyboard (``sim``, ``view``)."""
    parser.add_argument("--speed", type=number, default=0.2, metavar="V", help="speed of W/S/A/D [m/s] (default 0.2)")
    parser.add_argument("--turn", type=number, default=0.5, metavar="W", help="turn rate of Q/E [rad/s] (default 0.5)")
    parser.add_argument("--max-speed", type=number, default=0.3, metavar="V", help="speed limit [m/s] (default 0.3)")
    parser.add_argument("--max-turn", type=number, default=1.0, metavar="W", help="turn rate limit [rad/s] (default 1)")


def teleop_limits(args):
    """The :class:`~omnikin.motion.limits.MotionLimits` of :func:`add_teleop_options`, every one of the
    four options checked positive first (one line naming the option as typed)."""
    from ..motion.limits import MotionLimits

    for flag, value in (
        ("--speed", args.speed),
        ("--turn", args.turn),
        ("--max-speed", args.max_speed),
        ("--max-turn", args.max_turn),
    ):
        if value <= 0:
            raise InputError(f"{flag} must be positive, got {value:g}")
    return MotionLimits(linear=args.max_speed, angular=args.max_turn)


def physics_hint(step: float, *changes: str) -> str:
    """What would make a physics run cheaper: ``changes`` (e.g. "shorten --path") and, while the
    time step ``step`` [s] is below the largest accepted, "raise --step"."""
    from ..physics.mjcf import STEP_RANGE

    options = [*changes, *(["raise --step"] if step < STEP_RANGE[1] * (1 - 1e-9) else [])]
    return " or ".join(options) if options else "no setting makes it cheaper: raise --max-time"


class _Stdout:
    """Whether the running command writes data to standard output (an output ``-``), set by
    :func:`running` while the command runs: its messages then go to standard error
    (:func:`console`), whichever command prints them."""

    carries_data = False


def console(width: int = 140, stderr: bool = False):
    """A rich console without markup or highlighting; ``width`` columns when not a terminal. On
    standard error when ``stderr`` or when standard output carries the command's data."""
    from rich.console import Console

    stderr = stderr or _Stdout.carries_data
    con = Console(highlight=False, markup=False, stderr=stderr)
    if not con.is_terminal:
        con = Console(highlight=False, markup=False, width=width, stderr=stderr)
    return con


def load_robot(spec):
    """A preset or robot file (:func:`omnikin.io.robot_file.load_robot`, imported on use)."""
    from ..io import robot_file

    return robot_file.load_robot(spec)


# --- outputs -----------------------------------------------------------------------------------------
def add_output_options(parser) -> None:
    """Add ``--force`` to a command that writes files (see the module docstring)."""
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)


OUTPUTS = "_omnikin_outputs"
"""Namespace attribute (a parser default) listing the declared outputs: ``(dest, label, folder, stdout)``."""

INPUTS = "_omnikin_inputs"
"""Namespace attribute (a parser default) naming the arguments that are inputs."""


def add_output(parser, *flags: str, folder: bool | str = False, stdout: bool = True, **kwargs):
    """``parser.add_argument(*flags, **kwargs)`` for an option naming an output of the command,
    recorded so that :func:`check_command_outputs` checks it with the others before the command
    runs. ``folder``: as for :func:`omnikin.io.output.check_output`; ``stdout``: whether ``-``
    (standard output) may take it (never for a folder)."""
    action = parser.add_argument(*flags, **kwargs)
    declared = parser.get_default(OUTPUTS) or ()
    parser.set_defaults(**{OUTPUTS: (*declared, (action.dest, flags[0], folder, stdout and not folder))})
    return action


def declare_inputs(parser, *files: str, robots: tuple[str, ...] = ()) -> None:
    """Record the arguments (by ``dest``) that name the command's inputs: ``files`` (logs, bags,
    runs files: always paths) and ``robots`` (robot specs: a preset name is not a file,
    :func:`robot_inputs`)."""
    parser.set_defaults(**{INPUTS: (files, robots)})


def command_inputs(args) -> list:
    """The input files and folders of the parsed command (:func:`declare_inputs`)."""
    files, robots = getattr(args, INPUTS, ((), ()))
    given = [getattr(args, dest, None) for dest in files]
    given = [f for g in given for f in (g if isinstance(g, list) else [g])]  # (an option given again)
    return [f for f in given if f is not None] + robot_inputs(*(getattr(args, dest, None) for dest in robots))


def check_command_outputs(args) -> None:
    """Check every output the parsed command declared (:func:`add_output`), together and against
    its inputs (:func:`omnikin.io.output.check_outputs`); ``--json`` counts as a use of standard
    output. Called by :mod:`omnikin.cli.process` before the command runs, so no command can skip
    it; with an output ``-``, the command's messages go to standard error (:func:`console`)."""
    declared = getattr(args, OUTPUTS, ())
    outputs = []
    for dest, label, folder, stdout in declared:
        path = getattr(args, dest, None)
        if path is not None and is_stdout(path) and not stdout:
            raise InputError(f"{label}: '-' (standard output) cannot take it; name a {'folder' if folder else 'file'}")
        outputs.append(Output(label, path, folder))
    check_outputs(
        outputs,
        inputs=command_inputs(args),
        force=bool(getattr(args, "force", False)),
        stdout="--json" if getattr(args, "json", False) is True else None,
    )


@contextlib.contextmanager
def running(args) -> Iterator[None]:
    """The frame ``omnikin.cli.process`` runs every parsed command in: its outputs are checked
    first (:func:`check_command_outputs`), and while it runs, its messages go to standard error
    if one of its outputs is ``-`` (:func:`console`)."""
    check_command_outputs(args)
    previous = _Stdout.carries_data
    _Stdout.carries_data = any(
        is_stdout(getattr(args, dest)) for dest, *_ in getattr(args, OUTPUTS, ()) if getattr(args, dest, None)
    )
    try:
        yield
    finally:
        _Stdout.carries_data = previous


def robot_inputs(*specs) -> list:
    """The robot files among robot specs (a preset name is never a file:
    :func:`omnikin.io.robot_file.robot_file_of`)."""
    from ..io.robot_file import robot_file_of

    return [f for f in map(robot_file_of, specs) if f is not None]


# --- JSON and tables -------------------------------------------------------------------------------------
def print_json(data, *, nullable=()) -> None:
    """Print ``data`` as strict JSON on standard output (:func:`omnikin.io.jsonfile.to_json`;
    ``nullable``: fields whose non-finite values print as null)."""
    from ..io.jsonfile import to_json

    text = to_json(data, nullable=nullable)
    print(text)


def cell(x: float) -> str:
    """A number as a table cell prints it: six significant digits, ``inf`` and ``nan`` as such."""
    return f"{x:.6g}" if np.isfinite(x) else str(x)


def denoised(matrix, scale: float | None = None) -> np.ndarray:
    """A matrix or vector for display (text output only; ``--json`` keeps the numbers): entries
    below 1e-12 of ``scale`` (default: its largest entry) set to 0 (rounding noise such as
    cos(pi/2) = 6e-17)."""
    m = np.array(matrix, dtype=float)
    largest = np.max(np.abs(m), initial=0.0) if scale is None else abs(scale)
    m[np.abs(m) < 1e-12 * max(largest, 1e-300)] = 0.0
    return m


def json_checked(data) -> str:
    """The ``--json`` text of a result, made in text mode too: a non-finite number in a result
    is an error naming its field either way (never a silent ``inf`` in a table)."""
    from ..io.jsonfile import to_json

    return to_json(data)


def write_model(args, text: str, what: str) -> int:
    """Write ``text`` (a robot model: ``omnikin mjcf``, ``omnikin urdf``) to ``args.output``
    through the output policy and say so (unless it went to standard output); status 0.
    ``what``: the model as the message names it (``"URDF of tomasi-omni3"``)."""
    from ..io.output import write_text

    write_text(args.output, text)
    if not is_stdout(args.output):
        console().print(f"{what} written to {args.output}")
    return 0


# --- options of several commands ------------------------------------------------------------------
def add_method_option(parser) -> None:
    """``--method exact|midpoint|euler``: the pose integration of the odometry commands."""
    parser.add_argument(
        "--method",
        choices=("exact", "midpoint", "euler"),
        default="exact",
        help="pose integration (default exact; the others exist for comparison)",
    )


# --- numbers on the command line -------------------------------------------------------------------
WHOLE_NUMBER = re.compile(r"[-+]?[0-9]+")
"""A whole number as options spell it: optional sign and ASCII digits (not ``1_0``, ``0x10``,
non-ASCII digits or blanks, which :class:`int` reads)."""

WHOLE_DIGITS = 20
"""Most digits of a whole-number option: 2**64 has 20, more than any count, width, seed or baud
rate needs (and :class:`int` refuses text of more than 4300 digits with a message of its own)."""


def number(text: str) -> float:
    """An argparse ``type``: a finite plain number (:mod:`omnikin.common.number_text`, the grammar of
    every number omnikin reads from text), else a usage error naming what is wrong."""
    problem = number_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return float(text)


def whole(text: str) -> int:
    """An argparse ``type``: a whole number in ASCII digits (:data:`WHOLE_NUMBER`), at most
    :data:`WHOLE_DIGITS` of them."""
    if not isinstance(text, str) or not WHOLE_NUMBER.fullmatch(text):
        raise argparse.ArgumentTypeError(f"not a whole number: {shorten(text)} (ASCII digits, e.g. 12)")
    digits = len(text.lstrip("+-"))
    if digits > WHOLE_DIGITS:
        raise argparse.ArgumentTypeError(
            f"{shorten(text)}: a whole number of {digits} digits; at most {WHOLE_DIGITS} are taken"
        )
    return int(text)


# --- odometry bounds --------------------------------------------------------------------------------
def _bound(check, what: str):
    """An argparse ``type``: a plain number or ``inf`` that ``check`` (an :mod:`omnikin.odometry.plausibility`
    option check) takes, else a usage error quoting the text as typed."""

    def parse(text: str) -> float:
        if text in ("inf", "+inf"):
            value = math.inf
        elif number_problem(text) is None:
            value = float(text)
        else:
            raise argparse.ArgumentTypeError(f"{shorten(text)} is not a finite plain number ({what})")
        try:
            return check(value)
        except InputError:
            raise argparse.ArgumentTypeError(f"{shorten(text)}: must be {what}") from None

    return parse


def add_wheel_bound_options(parser, *, angles: bool = False) -> None:
    """``--max-wheel-speed RAD_S`` and ``--max-wheel-accel RAD_S2``: the speed and change-of-speed
    rules of the odometry commands (:mod:`omnikin.odometry.plausibility`, ``docs/conventions.md``), passed to
    the estimator as ``max_wheel_speed`` and ``max_wheel_accel`` (None when not given: each
    wheel's own bound). ``angles``: the command reads wheel angles (joint states), which have the
    change-of-speed rule only when ``--max-wheel-accel`` is given; else encoder ticks."""
    from ..odometry.plausibility import (
        DEFAULT_RIM_ACCEL,
        DEFAULT_RIM_SPEED,
        JUMP_MARGIN,
        MAX_WHEEL_ACCEL_TEXT,
        MAX_WHEEL_SPEED_TEXT,
        check_max_wheel_accel,
        check_max_wheel_speed,
    )

    jump = "a wheel-angle jump" if angles else "a tick jump"
    parser.add_argument(
        "--max-wheel-speed",
        type=_bound(check_max_wheel_speed, MAX_WHEEL_SPEED_TEXT),
        metavar="RAD_S",
        help=f"fastest a wheel turns [rad/s]: {jump} needing more than {JUMP_MARGIN:g}x this is refused "
        f"(default: each wheel's max_speed, else {DEFAULT_RIM_SPEED:g} m/s at the rim)",
    )
    default = "no bound for joint states" if angles else f"{DEFAULT_RIM_ACCEL:g} m/s^2 at the rim"
    parser.add_argument(
        "--max-wheel-accel",
        type=_bound(check_max_wheel_accel, MAX_WHEEL_ACCEL_TEXT),
        metavar="RAD_S2",
        help=f"fastest a wheel's speed changes [rad/s^2]: a change between two consecutive intervals "
        f"needing more than {JUMP_MARGIN:g}x this is refused (default: {default}; 'inf': no bound)",
    )
