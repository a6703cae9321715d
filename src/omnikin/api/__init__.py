"""The Python API: the command-line tools as functions, with the command line's defaults.

Each function takes what its command takes (a robot as a preset name, a robot file or a
:class:`~omnikin.model.Robot`; error and noise profiles by name or as objects) and returns a
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

Lengths in metres, angles in radians, unless a name says otherwise (``_deg``, ``_mm``).
"""

from __future__ import annotations

from .calibration import Calibration, calibrate, calibration_plan
from .common import dumps, robot_of
from .simulation import DEFAULT_PATH, Simulation, SimulationCost, simulate
from .umbmark import DEFAULT_ROBOT, UMBmarkAnalysis, UMBmarkReport, analyze_umbmark, run_umbmark


def plot_layout(robot):
    """The wheel layout of ``robot`` (a matplotlib ``Figure``; ``omnikin show --plot``)."""
    from ..viz.layout import layout_figure
    from .common import require_viz

    require_viz()
    return layout_figure(robot_of(robot))


def run_sweep(
    spec, out, *, scheduler=None, workers=None, task_trials=None, force: bool = False, progress=None, tls=None
):
    """``omnikin sweep SPEC -o OUT``: the study of the study file ``spec`` (or a loaded
    :class:`~omnikin.sweep.study.Study`) run on Dask into the folder ``out`` (resumed when it holds
    the study); returns a :class:`~omnikin.sweep.run.SweepResult`. The embedded cluster starts
    worker processes: call it under ``if __name__ == "__main__":`` (docs/sweeps.md).

    ``progress``: told where the study runs and of each task finished
    (:class:`~omnikin.sweep.run.Progress`: ``start``, ``advance``); ``tls``: the credentials of a
    ``tls://`` ``scheduler`` (:class:`~omnikin.sweep.engine.TLSFiles`; default: Dask's
    configuration)."""
    from ..sweep.run import run_sweep as run
    from ..sweep.study import Study

    if not isinstance(spec, Study):
        from ..sweep.spec import load_study

        spec = load_study(spec)
    return run(
        spec,
        out,
        scheduler=scheduler,
        workers=workers,
        task_trials=task_trials,
        force=force,
        progress=progress,
        tls=tls,
    )


__all__ = [
    "Calibration",
    "DEFAULT_PATH",
    "DEFAULT_ROBOT",
    "Simulation",
    "SimulationCost",
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
]
