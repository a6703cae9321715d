"""omnikin: kinematics, exact odometry and UMBmark for wheeled mobile robots.

Packages (each imports only those below it; ``pyproject.toml``, ``[tool.importlinter]``;
``docs/architecture.md``): the core ``errors`` -> ``common`` -> ``kinematics`` (SE(2), wheels,
robot) -> ``motion`` (plans, limits) -> ``odometry``; the runtime and the engines
(``simulation``, ``physics``) above it; the studies (``evaluation``); the edges (``io``,
``viz``, ``ros``, ``viewer``, ``sweep``); the Python API ``api``; the command line ``cli``.
:mod:`omnikin.se2` is the SE(2) module (:mod:`omnikin.kinematics.se2`).

Entry points (the command-line tools as functions, with their defaults; imported on first
use, so ``import omnikin`` loads neither SciPy nor matplotlib):

- :func:`simulate` (``omnikin simulate``), :func:`run_umbmark` (``omnikin umbmark``),
  :func:`run_sweep` (``omnikin sweep``),
  :func:`analyze_umbmark` (``omnikin umbmark analyze``), :func:`calibrate` and
  :func:`calibration_plan` (``omnikin calibrate``), :func:`plot_layout` (``omnikin show --plot``);
- their results plot themselves: ``result.plot()`` returns a matplotlib ``Figure`` (extra ``viz``).

Engines (what simulates a robot as built): :class:`Engine`, the interface; :class:`KinematicEngine`
and :class:`PhysicsEngine` (MuJoCo, extra ``physics``); :func:`engine_named` makes one from a name
of :data:`ENGINE_NAMES`. ``simulate`` and ``run_umbmark`` take an engine or its name.

Errors: every exception and warning omnikin raises on purpose is exported here and defined in
:mod:`omnikin.errors`, whose docstring draws their tree (``except omnikin.InputError``: bad input).
"""

from ._version import __version__
from .errors import (
    BagError,
    CalibrationFitError,
    CliError,
    DivergedError,
    InfeasibleRunError,
    InfeasibleTwistError,
    InputError,
    LinkError,
    LinkLostError,
    MetricsInputError,
    NonFiniteValueError,
    OdometryInputError,
    OmnikinError,
    OutputError,
    OutputExistsError,
    PathFileError,
    PhysicsError,
    PresetShadowWarning,
    ProtocolError,
    ReplayError,
    ResourceLimitError,
    RobotFileError,
    RobotMismatch,
    RunPosesFileError,
    RunsFileError,
    SingularLayoutError,
    StudyFileError,
    Terminated,
    TrajectoryFileError,
    UsageError,
    WorkerMismatch,
    WorldFileError,
)
from .kinematics import se2
from .kinematics.encoder import Encoder
from .kinematics.robot import FKResult, IKResult, Robot
from .kinematics.wheels import Steer, Wheel
from .odometry.batch import OdometryResult, batch_odometry, batch_odometry_from_angles
from .odometry.streaming import Odometry
from .presets import PRESET_NAMES

_API = (
    "simulate",
    "run_umbmark",
    "se2",
    "run_sweep",
    "analyze_umbmark",
    "calibrate",
    "calibration_plan",
    "plot_layout",
    "Simulation",
    "UMBmarkReport",
    "UMBmarkAnalysis",
    "Calibration",
    "track",
    "Tracking",
)
"""Names served lazily from :mod:`omnikin.api`."""

_ENGINES = {
    "Engine": "simulation.engine",
    "KinematicEngine": "simulation.engine",
    "PhysicsEngine": "physics.engines",
    "ENGINE_NAMES": "physics.engines",
    "engine_named": "physics.engines",
}
"""The engine interface, its two engines and the factory by name, served lazily from their
modules (:mod:`omnikin.simulation.engine`, :mod:`omnikin.physics.engines`; neither imports
``mujoco``: a physics run does, when it builds its model)."""


def load_robot(spec):
    """Load a robot from a preset name or a robot file (YAML or JSON).

    Parameters
    ----------
    spec : str or os.PathLike
        A preset name given as a string (:data:`PRESET_NAMES`; always the shipped preset), or
        the path of a robot file (docs/conventions.md, "Naming a robot: preset or file").

    Returns
    -------
    Robot
        The robot, its lengths in metres and angles in radians (the file's ``_deg`` fields
        converted).

    Raises
    ------
    RobotFileError
        No such preset or file, a file that cannot be read, one that breaks the schema, or a
        layout that cannot realise or measure its motion (the message names the file, the wheel
        and the field).

    Warns
    -----
    PresetShadowWarning
        A preset name that is also a file or folder in the current folder.
    """
    from .io import robot_file

    return robot_file.load_robot(spec)


def __getattr__(name: str):
    """The API's entry points (:data:`_API`) and the engines (:data:`_ENGINES`), imported on
    first use (PEP 562)."""
    if name in _ENGINES:
        import importlib

        value = getattr(importlib.import_module(f".{_ENGINES[name]}", __name__), name)
        globals()[name] = value
        return value
    if name in _API:
        from . import api

        value = getattr(api, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'omnikin' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_API) | set(_ENGINES))


__all__ = [
    "BagError",
    "Calibration",
    "CalibrationFitError",
    "CliError",
    "DivergedError",
    "ENGINE_NAMES",
    "Encoder",
    "Engine",
    "FKResult",
    "IKResult",
    "InfeasibleRunError",
    "InfeasibleTwistError",
    "InputError",
    "KinematicEngine",
    "LinkError",
    "LinkLostError",
    "MetricsInputError",
    "NonFiniteValueError",
    "Odometry",
    "OdometryInputError",
    "OdometryResult",
    "OmnikinError",
    "OutputError",
    "OutputExistsError",
    "PRESET_NAMES",
    "PathFileError",
    "PhysicsEngine",
    "PhysicsError",
    "PresetShadowWarning",
    "ProtocolError",
    "ReplayError",
    "ResourceLimitError",
    "Robot",
    "RobotFileError",
    "RobotMismatch",
    "RunPosesFileError",
    "RunsFileError",
    "Simulation",
    "SingularLayoutError",
    "Steer",
    "StudyFileError",
    "Terminated",
    "Tracking",
    "TrajectoryFileError",
    "UMBmarkAnalysis",
    "UMBmarkReport",
    "UsageError",
    "Wheel",
    "WorkerMismatch",
    "WorldFileError",
    "analyze_umbmark",
    "batch_odometry",
    "batch_odometry_from_angles",
    "calibrate",
    "calibration_plan",
    "engine_named",
    "load_robot",
    "plot_layout",
    "run_sweep",
    "run_umbmark",
    "se2",
    "simulate",
    "track",
    "__version__",
]
