"""Every exception and warning omnikin raises on purpose, in one tree.

Each branch also derives from the built-in exception that says what kind of failure it is
(``also`` below), so that a caller can catch what it means: ``except ValueError`` takes every
bad input, ``except omnikin.InputError`` only omnikin's. Every class is exported from the
package (``omnikin.BagError``); the messages' text helpers are in :mod:`omnikin.common.messages`.

The tree (checked by ``tests/core/test_error_tree.py``; a class's first base is its parent)::

    Exception
    └── OmnikinError: every error omnikin raises on purpose
        ├── InputError (also ValueError): bad input, the caller's to fix
        │   ├── RobotFileError: a robot file or dict breaks the schema
        │   ├── StudyFileError: a study file of omnikin sweep is bad
        │   ├── RunsFileError: a measurement file cannot be read
        │   ├── RunPosesFileError: a run-poses file cannot be read
        │   ├── TrajectoryFileError: a trajectory file cannot be read or written
        │   ├── PathFileError: a path file cannot be read
        │   ├── WorldFileError: a world file or World breaks the schema
        │   ├── BagError: a ROS 2 bag cannot be read or written as asked
        │   ├── ReplayError: something to replay in the viewer cannot be
        │   ├── ProtocolError: a wheel-link protocol description or frame is bad
        │   ├── SingularLayoutError: a wheel layout cannot realise its motion
        │   ├── InfeasibleTwistError: a twist breaks a no-side-slip constraint
        │   ├── InfeasibleRunError: a calibration run the robot cannot drive
        │   ├── CalibrationFitError: no robot of the layout explains the runs
        │   ├── OdometryInputError: encoder samples that cannot be integrated
        │   ├── MetricsInputError: trajectories the metrics cannot be computed on
        │   ├── RobotMismatch: the ROS node drives another robot than the viewer's
        │   ├── NonFiniteValueError: a result to write as JSON holds NaN or inf
        │   ├── OutputExistsError: an output exists and may not be replaced
        │   ├── ResourceLimitError: a job would need more memory or time than allowed
        │   ├── UsageError: the command line is wrong
        │   └── CliError: a usage problem found after argument parsing
        ├── OutputError (also OSError): writing an output failed
        ├── LinkError (also RuntimeError): a link failed while running
        │   ├── LinkLostError: a wheel controller went silent
        │   └── WorkerMismatch: a sweep worker runs another omnikin or NumPy
        └── PhysicsError (also RuntimeError): the physics simulation failed
            └── DivergedError: MuJoCo's state diverged
    BaseException
    └── Terminated: a termination signal ends a command
    UserWarning
    └── PresetShadowWarning: a preset name is also a local file's name

Messages are one line: they name what is wrong and where (file, line, wheel, field, sample
index) and never quote an unbounded value (:func:`omnikin.common.messages.shorten`). Errors may carry
where they happened as attributes (``sample``, ``line``, ``wheel``, ...), so that an edge (the
command line) can add its own context without parsing the message.

This module imports nothing of omnikin: it is the bottom layer, with :mod:`omnikin.common.messages`.
"""

from __future__ import annotations

SMALLEST_STEP = 1e-5
"""The smallest time step [s] the physics engine accepts (the lower end of
:data:`omnikin.physics.mjcf.STEP_RANGE`, which is defined from this): a
:class:`DivergedError` at this step has no smaller one to advise."""


# --- the roots ---------------------------------------------------------------------------------------


class OmnikinError(Exception):
    """Base class of every error omnikin raises on purpose. Catching it catches nothing of
    Python's or another library's own failures (a bug is not turned into a message)."""


class InputError(OmnikinError, ValueError):
    """Bad input: an argument, a file, a sample, a message of a peer. The caller's to fix; the
    message names what is wrong and where, in one line. Raised throughout the library for input
    without a class of its own below; the command line prints it as ``omnikin: error: ...``
    and exits with status 2."""


# --- bad input: files --------------------------------------------------------------------------------


class RobotFileError(InputError):
    """A robot file (or dict) breaks schema version 1 of ``docs/conventions.md``: raised by
    :func:`omnikin.load_robot` and :mod:`omnikin.io.robot_file` (``robot_from_dict``, the strict
    YAML reader); the message names the file, the line when known, and the field."""


class StudyFileError(InputError):
    """A study file of ``omnikin sweep`` is bad: raised by :mod:`omnikin.sweep.spec`. The
    message names the file, the line and the field.

    ``line``: the 1-based line of the problem; ``field``: the dotted field
    (``factors.scale.count``); each None when the problem is not tied to one (an unreadable
    file), so that an edge can point at them without parsing the message.
    """

    def __init__(self, message: str, *, line: int | None = None, field: str | None = None):
        super().__init__(message)
        self.line = line
        self.field = field


class RunsFileError(InputError):
    """A measurement file (calibration runs, UMBmark end poses) that cannot be read: raised by
    :mod:`omnikin.io.runs`; the message names the file, the line and the column."""


class RunPosesFileError(InputError):
    """A run-poses file (poses along recorded runs) that cannot be read: raised by
    :mod:`omnikin.io.run_poses`; the message names the file and the line."""


class TrajectoryFileError(InputError):
    """A trajectory file (``t, x, y, theta`` in s, m, rad) that cannot be read or written:
    raised by :mod:`omnikin.io.trajectories`; the message names the file (and the line)."""


class PathFileError(InputError):
    """A path file (waypoints ``x, y[, theta]`` in m and rad, CSV or YAML) that cannot be read:
    raised by :mod:`omnikin.io.path_file`; the message names the file and the line or waypoint."""


class WorldFileError(InputError):
    """A world file (or a :class:`omnikin.world.World` built in Python) breaks schema version 1
    of ``docs/world.md``: raised by :mod:`omnikin.world.model` (the fields and how the bodies
    lie) and :mod:`omnikin.io.world_file` (the file, its line); the message names the file, the
    line, the body and the field.

    ``field``: the field of the body at fault (``thickness``, ``points``) or None; ``body``:
    the 0-based index of the wall, obstacle, patch or mark in its list, with ``group`` the name
    of that list (``walls``), each None when the problem is the whole world's.
    """

    def __init__(self, message: str, *, field: str | None = None, group: str | None = None, body: int | None = None):
        super().__init__(message)
        self.field = field
        self.group = group
        self.body = body


class BagError(InputError):
    """A ROS 2 bag that cannot be read or written as asked (missing, unreadable, a topic of
    another type, joints missing, stamps out of order): raised by :mod:`omnikin.io.bags` and
    the viewer's replay of a bag; the message names the bag and the topic (and the message)."""


class ReplayError(InputError):
    """Something the viewer is asked to replay that cannot be (``omnikin view`` with a log, a
    trajectory or a bag): raised by :mod:`omnikin.viewer.replay_sources`; the message names the
    file or the topic."""


class ProtocolError(InputError):
    """A wheel-link protocol description that breaks its rules, a frame that cannot be encoded
    (a value out of its field's range), or a generated block of ``docs/protocol.md`` that is
    unknown: raised by :mod:`omnikin.runtime.protocol` (also exported there)."""


# --- bad input: motion -------------------------------------------------------------------------------


class SingularLayoutError(InputError):
    """The wheel layout cannot realise or observe the motion its type promises (a rank-deficient
    kinematic matrix): raised by :class:`omnikin.Robot` when it is built or asked to solve."""


class InfeasibleTwistError(InputError):
    """A commanded twist violates a no-side-slip constraint or a steering limit: raised by
    :meth:`omnikin.Robot.ik` (and the wheels' inverse kinematics) with ``on_infeasible='raise'``.

    ``detail``: the message without the library's way out (``on_infeasible='return'``), so
    that an edge can name its own (the command line's ``--allow-infeasible``).
    """

    def __init__(self, message: str, *, detail: str | None = None):
        super().__init__(message)
        self.detail = detail if detail is not None else message


class InfeasibleRunError(InputError):
    """A calibration run the robot cannot drive (its path needs a motion the layout does not
    allow): raised by :func:`omnikin.evaluation.calibration.least_squares_calibration` (``omnikin calibrate``).

    ``run``: the index (0-based) of the run in the runs given.
    """

    def __init__(self, message: str, *, run: int):
        super().__init__(message)
        self.run = run


class CalibrationFitError(InputError):
    """The least-squares fit of :func:`omnikin.evaluation.calibration.least_squares_calibration` left the ranges
    a robot file allows: the runs are not explained by the robot's radii [m], hub positions [m]
    and drive directions (bad measurements, or the robot did not drive as commanded)."""


class OdometryInputError(InputError):
    """Encoder samples that cannot be integrated (time order, jumps, NaN, shape): raised by
    :func:`omnikin.batch_odometry`, :class:`omnikin.Odometry` and the tick-log readers.

    ``sample``: index of the offending sample (0-based, counting every sample given), or
    None when the problem is not tied to one sample; ``detail``: the message without the
    sample, so that an edge can name the sample its own way (a file line).
    """

    def __init__(self, message: str, *, sample: int | None = None, detail: str | None = None):
        super().__init__(message)
        self.sample = sample
        self.detail = detail if detail is not None else message


class MetricsInputError(InputError):
    """Trajectories that the metrics cannot be computed on (empty, mismatched, NaN, unsorted, no
    common timestamps): raised by :mod:`omnikin.evaluation.metrics` (ATE, RPE, their checks)."""


class RobotMismatch(InputError):
    """The ROS node the viewer connects to drives another robot than the one given to the
    viewer: raised by :mod:`omnikin.viewer.ros_robot` (``omnikin view --ros``)."""


# --- bad input: outputs and limits -------------------------------------------------------------------


class NonFiniteValueError(InputError):
    """A result to be written as JSON holds NaN or an infinity (JSON has neither): raised by
    :mod:`omnikin.io.jsonfile`.

    ``field``: where the value sits in the result (a path such as ``rpe.rotation_deg.std`` or ``runs[2].x``; empty
    for the top level).
    """

    def __init__(self, message: str, *, field: str):
        super().__init__(message)
        self.field = field


class OutputExistsError(InputError):
    """An output path exists and the user did not ask to replace it, or it is one of the
    inputs: raised by :mod:`omnikin.io.output` and the sweep's study folder."""


class ResourceLimitError(InputError):
    """A job would need more memory or time than allowed (a simulation too long, a bag too
    large): raised by :mod:`omnikin.common.resource_limits` and the readers that check it; the message
    names the limit and the way to change it.

    ``needed`` and ``limit``: what the job needs and what is allowed, in the unit named by
    ``unit`` (``"bytes"``, ``"seconds"``, ``"messages"``, ...); None when not computed.
    """

    def __init__(self, message: str, *, needed: float | None = None, limit: float | None = None, unit: str = ""):
        super().__init__(message)
        self.needed = needed
        self.limit = limit
        self.unit = unit


# --- bad input: the command line ---------------------------------------------------------------------


class UsageError(InputError):
    """The command line itself is wrong (an unknown option, a missing or malformed argument):
    raised by the argument parser of :mod:`omnikin.cli` instead of argparse's exit; exit status 2.

    ``command``: the sub-command's name (``"ik"``, ``"bag odometry"``; empty for ``omnikin``
    itself), for the ``--help`` hint (:attr:`help_hint`).
    """

    def __init__(self, message: str, *, command: str = ""):
        super().__init__(message)
        self.command = command

    @property
    def help_hint(self) -> str:
        """The command that shows the help of :attr:`command` (``"omnikin ik --help"``)."""
        return f"omnikin {self.command} --help" if self.command else "omnikin --help"


class CliError(InputError):
    """A usage problem found by a command after argument parsing (values that do not fit the
    robot, an unknown drawing format): raised by :mod:`omnikin.cli`; exit status 2."""


# --- failures while running --------------------------------------------------------------------------


class OutputError(OmnikinError, OSError):
    """Writing an output failed (disk full, read-only folder, ...): raised by
    :mod:`omnikin.io.output` and the sweep's store; the message names the path. Not an input
    error: the same command may succeed elsewhere."""


class LinkError(OmnikinError, RuntimeError):
    """A link failed while running (to hardware, or to the workers of a sweep): not the
    caller's fault; retrying may help. Raised by :mod:`omnikin.runtime` and :mod:`omnikin.sweep`."""


class LinkLostError(LinkError):
    """A wheel controller went silent or its serial port failed; the wheels were commanded to
    zero: raised by :class:`omnikin.runtime.serial_backend.SerialBackend` on every read until
    the link is back.

    ``wheel`` and ``port``: the first wheel found silent and its port (None when unknown).
    """

    def __init__(self, message: str, wheel: str | None = None, port: str | None = None):
        super().__init__(message)
        self.wheel = wheel
        self.port = port


class WorkerMismatch(LinkError):
    """A sweep result computed by a Dask worker whose omnikin or NumPy version differs from the
    client's (or that gave no versions): refused by :mod:`omnikin.sweep.cluster`."""


class PhysicsError(OmnikinError, RuntimeError):
    """The physics simulation (extra ``physics``, MuJoCo) failed while running: the robot
    cannot stand or tipped over, a wheel spun implausibly, or the state diverged
    (:class:`DivergedError`). Raised by :mod:`omnikin.physics`; the message names the robot and
    the simulated time."""


class DivergedError(PhysicsError):
    """MuJoCo found the state not finite (or huge) and reset it: raised by
    :class:`omnikin.physics.simulator.PhysicsSim`. The message gives no advice about an option: a
    caller that has a ``--step`` adds it (:meth:`explained`).

    ``time`` [s]: the simulated time at which it did (counted from the start of settling when
    ``settling``); ``settling``: it happened while the robot was put down, before the run;
    ``step`` [s]: the time step; ``min_step`` [s]: the smallest time step the engine accepts
    (:data:`SMALLEST_STEP`).
    """

    def __init__(self, message: str, *, time: float, settling: bool, step: float, min_step: float = SMALLEST_STEP):
        super().__init__(message)
        self.time = time
        self.settling = settling
        self.step = step
        self.min_step = min_step

    def explained(self, note: str = "", *, step_option: bool = False) -> DivergedError:
        """This error with ``note`` appended and, for callers that have a ``--step`` option
        (``step_option``), the advice to try a smaller time step while one is accepted
        (``step`` above ``min_step``)."""
        text = str(self) + note
        if step_option and self.step > self.min_step * 1.0001:
            text += f"; or try a smaller time step (--step, now {self.step:g} s)"
        return DivergedError(text, time=self.time, settling=self.settling, step=self.step, min_step=self.min_step)


# --- not errors --------------------------------------------------------------------------------------


class Terminated(BaseException):
    """A termination signal arrived (SIGTERM, SIGHUP: ``timeout``, ``kill``, systemd, a closed
    terminal). Raised by the signal handler the command line (:mod:`omnikin.cli`) installs while
    a command runs, it unwinds the command like ``KeyboardInterrupt`` does, so every cleanup runs
    (a temporary file, a staging folder: :mod:`omnikin.io.output`). Not an :class:`Exception`:
    no ``except Exception`` swallows it.

    ``signum``: the signal's number (``signal.SIGTERM``).
    """

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class PresetShadowWarning(UserWarning):
    """A preset name given as ROBOT is also the name of a file or folder in the current folder:
    the preset is used (:func:`omnikin.load_robot`), and the warning says how to name the file.
    Warned by :mod:`omnikin.io.robot_file`; the command line prints it as one line on stderr."""
