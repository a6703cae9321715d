"""The Python API: the command-line tools as functions, with the command line's defaults.

Each function takes what its command takes (a robot as a preset name, a robot file or a
:class:`~omnikin.kinematics.robot.Robot`; error and noise profiles by name or as objects) and returns a
result object that plots itself (``result.plot()`` returns a matplotlib ``Figure``; matplotlib
is imported only then, with an error naming the ``viz`` extra when it is missing)::

    import omnikin

    run = omnikin.simulate("diff-drive", "square cw rotate 4")         # omnikin simulate
    report = omnikin.run_umbmark("tomasi-omni3", trials=20)            # omnikin umbmark
    report.write("umbmark-report")                                     #   its report folder
    fit = omnikin.calibrate("tomasi-omni3", "runs.csv")                # omnikin calibrate
    res = omnikin.analyze_umbmark("measured.csv", robot="diff-drive")  # omnikin umbmark analyze
    omnikin.plot_layout("mecanum4").savefig("layout.pdf")              # omnikin show --plot
    study = omnikin.run_sweep("examples/tolerance.yaml", "study")      # omnikin sweep (extra sweep)
    done = omnikin.track("tomasi-omni3", "figure8 1")                 # omnikin track
    done.summary()["rms_error_m"]; done.plot()                         #   its --json and --plot

Lengths in metres, angles in radians, unless a name says otherwise (``_deg``, ``_mm``).
"""

from __future__ import annotations

from .calibration import Calibration, calibrate, calibration_plan
from .common import dumps, robot_of
from .simulation import DEFAULT_PATH, Simulation, SimulationCost, simulate
from .tracking import Tracking, track
from .umbmark import DEFAULT_ROBOT, UMBmarkAnalysis, UMBmarkReport, analyze_umbmark, run_umbmark


def plot_layout(robot):
    """The wheel layout of ``robot`` (a matplotlib ``Figure``; ``omnikin show --plot``).

    Parameters
    ----------
    robot : str, os.PathLike or Robot
        A preset name, a robot file or a :class:`~omnikin.kinematics.robot.Robot`.

    Returns
    -------
    matplotlib.figure.Figure
        The wheels at zero steering in the body frame (x forward, y left) [m], each with its
        drive direction and, for Swedish wheels, its roller axis.

    Raises
    ------
    ImportError
        matplotlib is missing (the message names the ``viz`` extra).
    RobotFileError
        As :func:`omnikin.load_robot`.
    """
    from ..viz.layout import layout_figure
    from .common import require_viz

    require_viz()
    return layout_figure(robot_of(robot))


def run_sweep(
    spec, out, *, scheduler=None, workers=None, task_trials=None, force: bool = False, progress=None, tls=None
):
    """``omnikin sweep SPEC -o OUT``: the study of the study file ``spec`` (or a loaded
    :class:`~omnikin.sweep.study.Study`) run on Dask into the folder ``out`` (resumed when it holds
    the study); returns a :class:`~omnikin.sweep.execution.SweepResult`. The embedded cluster starts
    worker processes: call it under ``if __name__ == "__main__":`` (docs/sweeps.md).

    Parameters
    ----------
    spec : str, os.PathLike or Study
        A study file (YAML; docs/sweeps.md) or a loaded study.
    out : str or os.PathLike
        The study folder: created, or resumed when it holds this study (only missing trials are
        computed).
    scheduler : str, optional
        Address of a running Dask scheduler (``tls://HOST:8786``); default an embedded cluster on
        this machine.
    workers : int, optional
        Worker processes of the embedded cluster (1 .. 1024); default one per core.
    task_trials : int, optional
        Trials per task (1 .. 1000); default sized to about
        :data:`~omnikin.sweep.execution.TASK_SECONDS` of work.
    force : bool, default False
        Start over in a folder that holds a study of another seed or other omnikin or NumPy
        versions (a folder omnikin did not write is refused even so).
    progress : Progress, optional
        Told where the study runs and of each task finished (:class:`~omnikin.sweep.execution.Progress`:
        ``start``, ``advance``); default none.
    tls : TLSFiles, optional
        The credentials of a ``tls://`` ``scheduler`` (:class:`~omnikin.sweep.cluster.TLSFiles`);
        default Dask's configuration.

    Returns
    -------
    SweepResult
        The study, its folder, the trials computed now, found on disk and failed, and the files
        written.

    Raises
    ------
    StudyFileError
        A study file that cannot be read or breaks its schema.
    InputError
        An argument of the wrong kind (a ``spec`` that is neither a path nor a study, a
        ``progress`` without ``start`` and ``advance``, ...), a bad ``workers`` or
        ``task_trials``; Dask or pyarrow missing (the message names the ``sweep`` extra).
    OutputExistsError
        A folder omnikin did not write, or (without ``force``) one that holds another study.
    """
    from ..sweep.execution import execute_study
    from ..sweep.study import Study

    _check_sweep_arguments(spec, out, scheduler, progress, tls, Study)
    if not isinstance(spec, Study):
        from ..sweep.spec import load_study

        spec = load_study(spec)
    return execute_study(
        spec,
        out,
        scheduler=scheduler,
        workers=workers,
        task_trials=task_trials,
        force=force,
        progress=progress,
        tls=tls,
    )


def _check_sweep_arguments(spec, out, scheduler, progress, tls, study_class) -> None:
    """Refuse an argument of :func:`run_sweep` of the wrong kind in one
    :class:`~omnikin.errors.InputError` naming it, before anything starts (else a TypeError or
    AttributeError from deep inside the sweep)."""
    import os

    from ..common.messages import shorten
    from ..errors import InputError

    def refuse(name: str, value, wanted: str):
        raise InputError(f"{name} must be {wanted}, got {shorten(value)}")

    if not isinstance(spec, (str, os.PathLike, study_class)):
        refuse("spec", spec, "a study file (str or os.PathLike) or a Study")
    if not isinstance(out, (str, os.PathLike)):
        refuse("out", out, "a folder (str or os.PathLike)")
    if scheduler is not None and not isinstance(scheduler, str):
        refuse("scheduler", scheduler, "an address such as 'tls://HOST:8786' (str) or None")
    if progress is not None and not all(callable(getattr(progress, m, None)) for m in ("start", "advance")):
        refuse("progress", progress, "None or an object with start() and advance() (omnikin.sweep.run.Progress)")
    if tls is not None:
        from ..sweep.cluster import TLSFiles

        if not isinstance(tls, TLSFiles):
            refuse("tls", tls, "None or a TLSFiles (omnikin.sweep.cluster.TLSFiles)")


__all__ = [
    "Calibration",
    "DEFAULT_PATH",
    "DEFAULT_ROBOT",
    "Simulation",
    "SimulationCost",
    "Tracking",
    "UMBmarkAnalysis",
    "UMBmarkReport",
    "analyze_umbmark",
    "calibrate",
    "calibration_plan",
    "dumps",
    "plot_layout",
    "robot_of",
    "run_sweep",
    "run_umbmark",
    "simulate",
    "track",
]
