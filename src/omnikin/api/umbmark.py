"""``omnikin.run_umbmark`` and ``omnikin.analyze_umbmark``: UMBmark as ``omnikin umbmark`` runs it.

:func:`run_umbmark` runs the study of :mod:`omnikin.evaluation.procedure` and returns a
:class:`UMBmarkReport`: its :meth:`~UMBmarkReport.as_dict` is the ``result.json`` document
(and what ``--json`` prints: one function builds both), :meth:`~UMBmarkReport.plot` draws
it and :meth:`~UMBmarkReport.write` writes the report folder.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from ..common.resource_limits import DEFAULT_MEMORY, DEFAULT_TIME
from ..errors import InputError
from ..evaluation.calibration import ERROR_UNITS, FIT_LIMIT, RECOMMENDED_REPEATS
from ..evaluation.physics_study import physics_cost
from ..evaluation.pipeline import FLOOR_PROCEDURES
from ..evaluation.procedure import (
    Cost,
    UMBmarkStudy,
    check_cost,
    check_settings,
    estimate_cost,
    streams,
    umbmark_study,
)
from ..evaluation.umbmark import LEVEL, UNITS, UMBmarkResult, analyze, require_square
from ..motion.plans import UMBMARK_SIDE
from ..odometry.batch import encoded_wheels
from ..physics.engines import as_engine
from ..physics.mjcf import DEFAULT_STEP
from ..viz import DPI
from .common import as_built, dumps, finite_or_none, require_callable, require_viz, robot_of, setting_name

RESULT_FORMAT = "omnikin-umbmark-result/1"
"""Name and version of the ``result.json`` document (:meth:`UMBmarkReport.as_dict`)."""

STAGES = {"before": "before", "after": "after calibration"}
"""How the figures and tables name the stages."""

DEFAULT_ROBOT = "tomasi-omni3"
"""The robot of ``omnikin umbmark`` without ROBOT (Tomasi and Todt's three-wheeled omni robot)."""


@dataclass(frozen=True)
class UMBmarkReport(UMBmarkStudy):
    """The result of :func:`run_umbmark` (the study of :mod:`omnikin.evaluation.procedure`)
    with the settings it ran with; :meth:`as_dict` is ``result.json``, :meth:`plot` draws it,
    :meth:`write` writes the report folder.

    Lengths in metres, angles in radians; poses in the world frame of each run's start.

    Attributes
    ----------
    robot, true_robot : Robot
        The nominal robot and the robot as built that drove the runs.
    injected : SystematicErrors or None
        The systematic errors drawn; None for a given ``true_robot``.
    before, after : list of UMBmarkResult
        One UMBmark procedure per trial, before and after calibration (``after`` None without
        calibration); each has ``e_max_syst`` [m].
    calibration : CalibrationResult or None
        The calibration between them.
    floor : NoiseFloor
        What E_max,syst a perfectly calibrated robot reaches (:meth:`at_noise_floor`).
    reduction_factor : float or None
        E_max,syst before over after, first procedure.
    settings : dict
        The arguments of :func:`run_umbmark`, as ``result.json`` records them (robots and
        profiles by name).
    """

    settings: dict = field(default_factory=dict)

    # -- numbers ------------------------------------------------------------------------------
    def at_noise_floor(self, result: UMBmarkResult) -> bool:
        """Whether ``result``'s E_max,syst cannot be told from a perfectly calibrated robot's.

        Parameters
        ----------
        result : UMBmarkResult
            One procedure of :attr:`before` or :attr:`after`.

        Returns
        -------
        bool
            True when its E_max,syst [m] is at or below the floor's limit.
        """
        return self.floor.reaches(result.e_max_syst)

    def _stage(self, result: UMBmarkResult) -> dict:
        return {**result.as_dict(self.level), "at_noise_floor": self.at_noise_floor(result)}

    def as_dict(self, files: list | None = None) -> dict:
        """The ``result.json`` document (also what ``omnikin umbmark --json`` prints); lengths
        in metres (``units`` gives every key's unit); ``null`` for an unbounded interval end.

        Parameters
        ----------
        files : list of str, optional
            The files of the report folder, recorded under ``files``.

        Returns
        -------
        dict
            The document (:data:`RESULT_FORMAT`; its ``units`` and ``methods`` say what each key
            holds).
        """
        from ..io.robot_file import robot_to_dict

        doc: dict[str, Any] = {
            "format": RESULT_FORMAT,
            "units": RESULT_UNITS,
            "methods": METHODS if self.engine.has_noise_model else PHYSICS_METHODS,
            "settings": {**self.settings, "confidence_level": self.level},
            "engine": self.engine.name,
            "robot": robot_to_dict(self.robot),
            "true_robot": robot_to_dict(self.true_robot),
        }
        if self.injected is not None:
            doc["injected_errors"] = self.injected.as_dict()
        doc["before"] = self._stage(self.before[0])
        doc["noise_floor"] = self.floor.as_dict()
        doc["systematic"] = {f"e_max_syst_{k}": v for k, v in self.systematic.items()}
        if self.after is not None and self.calibration is not None:
            doc["after"] = self._stage(self.after[0])
            doc["reduction_factor"] = finite_or_none(self.reduction_factor)
            interval = self.reduction_interval
            doc["reduction_factor_interval"] = [finite_or_none(v) for v in interval] if interval else None
            s = self.systematic
            doc["systematic"]["reduction_factor"] = finite_or_none(
                s["before"] / s["after"] if s["after"] > 0 else math.inf
            )
            doc["calibration"] = {
                **self.calibration.as_dict(),
                "repeats": RECOMMENDED_REPEATS,
                "paths": list(dict.fromkeys(r.label for r in self.calibration_runs)),
            }
            doc["calibrated_robot"] = robot_to_dict(self.calibration.robot)
            if self.borenstein is not None:
                doc["borenstein_iterations"] = list(self.borenstein)
        if self.trials > 1:
            doc["monte_carlo"] = {"before": _stats(self.before)}
            if self.after is not None:
                doc["monte_carlo"]["after calibration"] = _stats(self.after)
        if not self.engine.drives_as_commanded:
            doc["physics_problems"] = list(self.problems)  # runs that did not drive as commanded
        doc["files"] = list(files or [])
        return doc

    # -- figures -------------------------------------------------------------------------------
    def figures(self) -> dict:
        """The report's figures by file stem: ``return_errors``, ``euclidean_errors``,
        ``trajectories`` (every run of the first procedure) and, with trials, ``monte_carlo``
        (matplotlib ``Figure`` objects), each captioned with :meth:`caption`."""
        require_viz()
        from ..viz import umbmark as fig

        title = f"UMBmark of {self.robot.name} as built ({self.mode} mode, {self.side:g} m square)"
        caption = self.caption()
        out = {
            "return_errors": fig.return_errors_figure(
                self.first(), title, floor=self.floor.limit, floor_label=self._floor_label, caption=caption
            ),
            "euclidean_errors": fig.euclidean_errors_figure(self.first(), title, caption=caption),
            "trajectories": fig.trajectories_figure(self._paths(), self.side, title, caption=caption),
        }
        if self.trials > 1:
            values: dict[str, Any] = {"before": [r.e_max_syst for r in self.before]}
            if self.after is not None:
                values["after calibration"] = [r.e_max_syst for r in self.after]
            noise_floor = self.engine.has_noise_model  # else the floor is the nominal robot's
            values["perfectly calibrated (noise floor)" if noise_floor else "floor (nominal robot in physics)"] = (
                self.floor.values
            )
            out["monte_carlo"] = fig.monte_carlo_figure(
                values, f"{fig.E_MAX} over {self.trials} procedures of {self.robot.name}", caption=caption
            )
        return out

    def caption(self) -> str:
        """What the figures show, one line from the settings: simulated, the engine, the random
        errors (kinematic engine) and the seed, the robot as built (profile or file), runs."""
        s = self.settings
        if self.engine.has_noise_model:
            how = f"simulated ({self.engine.name} engine), noise {s.get('noise') or 'typical'}"
        else:
            how = "simulated in MuJoCo (physics engine: contacts, whole encoder ticks)"
        built = f"true robot {s['true_robot']}" if s.get("true_robot") else f"errors {s.get('errors') or 'typical'}"
        return f"{how}, seed {s.get('seed')}, {built}; {self.runs} runs per direction"

    def _paths(self) -> dict:
        """Every run of the first procedure by stage and direction (:attr:`run_poses`), for
        :func:`~omnikin.viz.umbmark.trajectories_figure`."""
        out: dict = {}
        for run in self.run_poses:
            out.setdefault(STAGES[run.phase], {"cw": [], "ccw": []})[run.direction].append(run)
        return out

    @property
    def _floor_label(self) -> str:
        if self.engine.has_noise_model:
            return "noise floor (95th percentile)"
        return "floor (nominal robot in physics)"

    def plot(self, kind: str = "return_errors"):
        """One figure of :meth:`figures` (default: the return positions, before and after).

        Parameters
        ----------
        kind : {"return_errors", "euclidean_errors", "trajectories", "monte_carlo"}
            The figure; ``monte_carlo`` only with more than one trial.

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        InputError
            An unknown ``kind``.
        ImportError
            matplotlib is missing (the message names the ``viz`` extra).
        """
        figures = self.figures()
        if kind not in figures:
            raise InputError(f"unknown figure {kind!r}; one of {sorted(figures)}")
        return figures[kind]

    # -- report folder ---------------------------------------------------------------------------
    def write(self, folder, *, figure_format: str = "png", dpi: float = DPI, inputs=()) -> dict:
        """Write the report folder (replaced as a whole if omnikin wrote it; a foreign non-empty
        folder is refused; nothing changes if writing fails: :mod:`omnikin.io.output`).
        Returns the ``result.json`` document written.

        Parameters
        ----------
        folder : str or os.PathLike
            The report folder: ``report.md``, ``result.json``, the measurement, calibration and
            robot files, and the figures (none without matplotlib).
        figure_format : str, default "png"
            File format of the figures (a matplotlib format).
        dpi : float, default DPI
            Resolution of raster figures [dots per inch].
        inputs : sequence of path, default ()
            Files the study read, which the folder may not replace.

        Returns
        -------
        dict
            The ``result.json`` document (:meth:`as_dict`).

        Raises
        ------
        InputError
            A bad ``figure_format`` or ``dpi``, or a missing parent folder.
        OutputExistsError
            A folder omnikin did not write, or one that is an input.
        OutputError
            Writing failed (the folder is left as it was).
        """
        from ..io.output import check_output, report_folder
        from ..io.robot_file import robot_text
        from ..io.run_poses import run_poses_text
        from ..io.runs import calibration_runs_text, umbmark_measurements_text
        from ..viz import check_dpi, save_figure
        from ..viz import figure_format as check_format
        from .report import umbmark_markdown

        check_format("", figure_format)
        check_dpi(dpi)
        target = check_output(folder, inputs=inputs, folder=True)
        try:
            figures = self.figures()
        except ImportError:
            figures = {}
        texts = {
            "true_robot.yaml": robot_text(self.true_robot, "true_robot.yaml"),
            "measurements_before.csv": umbmark_measurements_text(self.before[0], self._measurement_note("before")),
        }
        if self.after is not None and self.calibration is not None:
            texts["measurements_after.csv"] = umbmark_measurements_text(self.after[0], self._measurement_note("after"))
            texts["calibrated_robot.yaml"] = robot_text(self.calibration.robot, "calibrated_robot.yaml")
            texts["calibration_runs.csv"] = calibration_runs_text(self.calibration_runs, self._runs_note())
        if self.run_poses:
            texts["run_poses.csv"] = run_poses_text(self.run_poses, self._poses_note())
        names = [f"{stem}.{figure_format}" for stem in figures]
        files = ["report.md", "result.json", *texts, *names]
        doc = self.as_dict(files)
        texts["result.json"] = dumps(doc)
        texts["report.md"] = umbmark_markdown(self, doc, names)
        with report_folder(target) as stage:  # a write failure: OutputError naming the folder
            for name, text in texts.items():
                (stage / name).write_text(text, encoding="utf-8")
            for name, figure in zip(names, figures.values(), strict=True):
                save_figure(figure, stage / name, dpi=dpi)
        return doc

    def command_line(self) -> str:
        """The command line that reproduces this study."""
        s = self.settings
        robot = s.get("robot") or self.robot.name
        return (
            f"omnikin umbmark {robot} --mode {self.mode} --runs {self.runs} --side {self.side:g} "
            f"--rate {self.rate:g} --seed {s.get('seed')}"
            + (f" --noise {s.get('noise')}" if self.engine.has_noise_model else self._physics_options())
            + (f" --true-robot {s['true_robot']}" if s.get("true_robot") else f" --errors {s.get('errors')}")
            + (f" --trials {self.trials}" if self.trials > 1 else "")
            + ("" if s.get("calibrate", True) else " --no-calibrate")
        )

    def _physics_options(self) -> str:
        step = self.engine.options.get("step")
        return f" --engine {self.engine.name}" + (
            f" --step {step:g}" if step is not None and step != DEFAULT_STEP else ""
        )

    def _measurement_note(self, stage: str) -> str:
        robot = self.settings.get("robot") or self.robot.name
        return (
            f"UMBmark {stage} calibration, simulated by: {self.command_line()}\n"
            f"first procedure, {self.runs} runs per direction; read it with: omnikin umbmark analyze FILE "
            f"--robot {robot} --side {self.side:g}"
        )

    def _poses_note(self) -> str:
        return (
            f"simulated by: {self.command_line()}\n"
            f"replay it with: omnikin view --replay REPORT_FOLDER (robot as built: true_robot.yaml)"
        )

    def _runs_note(self) -> str:
        robot = self.settings.get("robot") or self.robot.name
        return (
            f"calibration runs simulated by: {self.command_line()}\n"
            f"each recommended run driven {RECOMMENDED_REPEATS} times; read it with: omnikin calibrate {robot} "
            f"FILE -o calibrated.yaml"
        )


def _stats(results) -> dict:
    v = np.array([r.e_max_syst for r in results])
    return {
        "procedures": len(v),
        "e_max_syst_mean": float(v.mean()),
        "e_max_syst_median": float(np.median(v)),
        "e_max_syst_p95": float(np.percentile(v, 95)),
        "e_max_syst_max": float(v.max()),
    }


RESULT_UNITS = {
    **UNITS,
    "rate": "Hz",
    "confidence_level": "1",
    "reduction_factor": "1",
    "reduction_factor_interval": "1",
    "e_max_syst_before": "m",
    "e_max_syst_after": "m",
    "e_max_syst_mean": "m",
    "e_max_syst_median": "m",
    "e_max_syst_p95": "m",
    "e_max_syst_max": "m",
    "borenstein_iterations": "m (E_max,syst after each iteration)",
    "residual_rms_before": "measurement sigmas",
    "residual_rms_after": "measurement sigmas",
    "value": "the entry's 'unit'",
    "sigma": "the entry's 'unit'",
    "errors": ERROR_UNITS,
    "injected_errors": ERROR_UNITS,
    "robot": "m, rad (robot file schema 1, docs/conventions.md)",
    "true_robot": "m, rad",
    "calibrated_robot": "m, rad",
}
"""Unit of each key of ``result.json``, by the key's own name (the same name has the same unit
wherever it appears; ``errors``: per error name)."""


METHODS = {
    "e_max_syst": "max(r_cg_cw, r_cg_ccw), r_cg the distance of the centre of gravity of the runs of one direction "
    "from the origin (Borenstein and Feng 1996)",
    "e_max_syst_interval": "conservative confidence interval: per direction the Hotelling T^2 confidence region of "
    "the expected return position at level sqrt(confidence_level), projected onto the "
    "distance from the origin; needs 3 runs per direction (null otherwise)",
    "reduction_factor_interval": "low_before / high_after to high_before / low_after of the E_max,syst intervals at "
    "level sqrt(confidence_level); null upper end: after is consistent with zero",
    "noise_floor": f"E_max,syst of the robot as built commanded by its own exact model (a perfect calibration) under "
    f"the same random errors, {FLOOR_PROCEDURES} procedures; at_noise_floor: E_max,syst at or below "
    f"their 95th percentile",
    "systematic": "E_max,syst without random errors (one run per direction)",
    "calibration": "least squares over the recommended calibration runs, each driven "
    f"{RECOMMENDED_REPEATS} times (omnikin calibrate ROBOT --plan); fits: residual RMS at most "
    f"{FIT_LIMIT:g} measurement sigmas",
}
"""How each reported quantity is defined (copied into ``result.json``)."""

PHYSICS_METHODS = {
    **METHODS,
    "engine": "physics: every run driven in MuJoCo (rollers, motors; omnikin.physics) by the robot as built, "
    "one run at a time; no random error model (the contacts' slip, whole encoder ticks); each run starts every "
    "wheel at a roller phase drawn uniformly over its roller period from the seed (same seed, same runs)",
    "noise_floor": "in the physics engine, E_max,syst of the nominal robot (no systematic errors) "
    "commanded by its own model, trials procedures of the same runs and square, each run at its own roller "
    "phases: what the roller contact alone gives; median and 95th percentile over the procedures, "
    "e_max_syst_interval the confidence interval of the first procedure from its runs' spread; "
    "at_noise_floor: E_max,syst at or below e_max_syst_limit, the larger of the 95th percentile and the "
    "interval's upper end",
    "systematic": "E_max,syst of the first procedure (the physics engine has no random error model)",
    "e_max_syst_interval": METHODS["e_max_syst_interval"] + "; in physics the runs differ by their roller phases",
}
"""How each quantity of a physics study is defined (``result.json`` of ``--engine physics``)."""


def run_umbmark(
    robot=DEFAULT_ROBOT,
    *,
    true_robot=None,
    errors="typical",
    mode: str = "rotate",
    runs: int = 5,
    side: float = UMBMARK_SIDE,
    noise=None,
    rate: float = 100.0,
    seed: int = 1,
    trials: int = 1,
    calibrate: bool = True,
    engine="kinematic",
    step: float | None = None,
    max_memory: float = DEFAULT_MEMORY,
    max_time: float = DEFAULT_TIME,
    progress=None,
    on_cost: Callable[[Cost], None] | None = None,
) -> UMBmarkReport:
    """UMBmark of ``robot`` as built, calibration, UMBmark again (``omnikin umbmark``).

    ``robot``: preset name, robot file or Robot; ``true_robot`` (file or Robot) replaces the
    seeded draw of the ``errors`` profile; ``mode``: ``rotate`` or ``translate``; ``runs`` per
    direction; ``side`` [m]; ``noise``: random errors (default ``typical``; refused by the physics
    engine, whose random errors are its contacts'); ``rate`` [Hz]; ``trials``: repeated
    UMBmark procedures (Monte Carlo over the noise; the robot as built and its calibration
    stay the same); ``calibrate``: run the calibration step (:mod:`omnikin.evaluation.procedure`);
    ``engine``: an :class:`~omnikin.simulation.engine.Engine` or its name, ``kinematic`` or
    ``physics`` (every run in MuJoCo, and the floor of the nominal robot:
    :mod:`omnikin.evaluation.physics_study`) at time step ``step`` [s] (default 2 ms; physics
    only; :func:`~omnikin.physics.engines.engine_named`). ``progress`` is called with the name of each
    step (of each run, in physics). A study estimated to need more than
    ``max_memory`` [bytes] or ``max_time`` [s] is refused up front
    (:func:`~omnikin.evaluation.procedure.check_cost`), after every setting has been checked;
    ``on_cost``, if given, is called with that estimate first (``omnikin umbmark`` checks it
    against its options and says when the study will take long).

    Each run starts at the origin of the world frame (``odom``) heading along +x and drives a
    ``side`` square (Borenstein and Feng 1996; docs/conventions.md); its return error is the true
    end pose minus the odometry end pose.

    Parameters
    ----------
    robot : str, os.PathLike or Robot, default "tomasi-omni3"
        The nominal robot (preset name, robot file or Robot); it needs encoders.
    true_robot : str, os.PathLike or Robot, optional
        The robot as built, with the wheels of ``robot``; replaces the draw from ``errors``.
    errors : str or ErrorProfile, default "typical"
        Systematic-error profile the robot as built is drawn from.
    mode : {"rotate", "translate"}, default "rotate"
        Turn in place at the corners, or translate along the sides (holonomic robots).
    runs : int, default 5
        Runs per direction (cw and ccw) of each procedure.
    side : float, default 4.0
        Side of the square [m].
    noise : str or NoiseModel, optional
        Random errors of the kinematic engine; default ``"typical"``. Refused by the physics
        engine.
    rate : float, default 100.0
        Sample rate [Hz] of encoders and odometry.
    seed : int, default 1
        Seed (>= 0) of the robot as built, the runs and the floor.
    trials : int, default 1
        UMBmark procedures (Monte Carlo over the noise).
    calibrate : bool, default True
        Calibrate and run UMBmark again.
    engine : {"kinematic", "physics"}, default "kinematic"
        The kinematic simulation or MuJoCo.
    step : float, optional
        Physics time step [s]; default 2 ms. Physics only.
    max_memory : float, default DEFAULT_MEMORY
        Largest memory [bytes] the study may be estimated to need.
    max_time : float, default DEFAULT_TIME
        Largest run time [s] the study may be estimated to need.
    progress : callable, optional
        Called with the name of each step.
    on_cost : callable, optional
        Called with the :class:`~omnikin.evaluation.procedure.Cost` estimate before the study.

    Returns
    -------
    UMBmarkReport
        The study and its settings.

    Raises
    ------
    InputError
        A bad setting (the message names its option), a robot without encoders, or a square
        the robot cannot drive in ``mode``.
    ResourceLimitError
        A study estimated to need more than ``max_memory`` or ``max_time``.
    CalibrationFitError
        No robot of the layout explains the calibration runs.
    PhysicsError
        The physics engine failed.
    """
    require_callable(progress=progress, on_cost=on_cost)
    engine = as_engine(engine, noise=noise, step=step)
    nominal = robot_of(robot)
    check_settings(runs=runs, trials=trials, side=side, rate=rate)
    engine.check_rate(rate)  # physics: the encoders read at whole steps
    seeds = streams(seed)
    noise_model = engine.noise_model(noise)
    noise = engine.default_noise if noise is None else noise  # as the settings record it
    encoded_wheels(nominal)  # UMBmark measures with the encoders
    require_square(nominal, side, mode)
    true, injected = as_built(nominal, true_robot, errors, seeds["robot"])
    # every setting checked: only now the estimate (in physics: the model built and timed)
    cost = umbmark_cost(
        nominal,
        mode=mode,
        runs=runs,
        side=side,
        rate=rate,
        trials=trials,
        calibrate=calibrate,
        engine=engine,
        max_time=max_time,
    )
    if on_cost is not None:
        on_cost(cost)
    check_cost(cost, max_memory=max_memory, max_time=max_time)
    common: dict[str, Any] = dict(
        injected=injected,
        side=float(side),
        mode=mode,
        runs=int(runs),
        rate=float(rate),
        trials=int(trials),
        calibrate=calibrate,
        progress=progress,
    )
    study = umbmark_study(nominal, true, noise=noise_model, seed=seed, engine=engine, **common)
    settings = {
        "robot": setting_name(robot),
        "true_robot": setting_name(true_robot),
        "errors": None if true_robot is not None else setting_name(errors),
        "noise": setting_name(noise),
        "engine": engine.name,
        "step": engine.options.get("step"),
        "mode": mode,
        "runs": int(runs),
        "side": float(side),
        "rate": float(rate),
        "seed": seed,
        "trials": int(trials),
        "calibrate": bool(calibrate),
    }
    return UMBmarkReport(**{f.name: getattr(study, f.name) for f in fields(study)}, settings=settings)


def umbmark_cost(
    robot=DEFAULT_ROBOT,
    *,
    mode: str = "rotate",
    runs: int = 5,
    side: float = UMBMARK_SIDE,
    rate: float = 100.0,
    trials: int = 1,
    calibrate: bool = True,
    engine="kinematic",
    step: float | None = None,
    max_time: float | None = None,
) -> Cost:
    """What :func:`run_umbmark` with these settings will take (robot-samples, memory, time):
    :func:`~omnikin.evaluation.procedure.estimate_cost`, or
    :func:`~omnikin.evaluation.physics_study.physics_cost` for an engine whose cost is measured
    on its model (:attr:`~omnikin.simulation.engine.Engine.measured_cost`: physics; it does not
    build a model whose size alone says it takes longer than ``max_time`` [s]).
    ``engine``: an :class:`~omnikin.simulation.engine.Engine` or its name (with ``step``)."""
    engine = as_engine(engine, step=step)
    check_settings(runs=runs, trials=trials, side=side, rate=rate)
    settings: dict[str, Any] = dict(side=side, mode=mode, runs=runs, rate=rate, trials=trials, calibrate=calibrate)
    if engine.measured_cost:  # its runs are timed on its model (physics), not counted in samples
        return physics_cost(robot_of(robot), engine=engine, budget=max_time, **settings)
    return estimate_cost(robot_of(robot), **settings)


# --- analyze ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class UMBmarkAnalysis(UMBmarkResult):
    """UMBmark of measured runs (:func:`analyze_umbmark`) that plots itself.

    Attributes
    ----------
    cw, ccw : DirectionResult
        The runs of each direction: return errors ``epsilon`` ``(n, 3)`` [m, m, rad] (true minus
        calculated end pose, world frame) and their centre of gravity at distance ``r_cg`` [m].
    side : float
        Side of the square [m].
    mode : str
        ``rotate`` or ``translate``.
    borenstein : Borenstein or None
        Borenstein's correction (None unless a differential-drive ``robot`` was given).
    e_max_syst : float
        ``max(r_cg_cw, r_cg_ccw)`` [m] (Borenstein and Feng 1996).
    """

    def plot(self, kind: str = "return_errors"):
        """``return_errors`` (return positions and centres of gravity) or ``euclidean_errors``.

        Parameters
        ----------
        kind : {"return_errors", "euclidean_errors"}

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        InputError
            An unknown ``kind``.
        ImportError
            matplotlib is missing (the message names the ``viz`` extra).
        """
        require_viz()
        from ..viz import umbmark as fig

        makers: dict[str, Callable[..., Any]] = {
            "return_errors": fig.return_errors_figure,
            "euclidean_errors": fig.euclidean_errors_figure,
        }
        if kind not in makers:
            raise InputError(f"unknown figure {kind!r}; one of {sorted(makers)}")
        runs = f"{len(self.cw.epsilon)} cw and {len(self.ccw.epsilon)} ccw runs"
        return makers[kind]({"measured": self}, "UMBmark of measured runs", caption=f"measured on a real robot: {runs}")

    def as_dict(self, level: float = LEVEL) -> dict:
        """The ``omnikin umbmark analyze --json`` document (lengths in metres; ``units``).

        Parameters
        ----------
        level : float, default LEVEL
            Confidence level (0 .. 1, exclusive) of the E_max,syst interval.

        Returns
        -------
        dict
            Side, mode, the return errors per direction, ``e_max_syst`` and its interval [m].
        """
        return {**UMBmarkResult.as_dict(self, level), "confidence_level": level, "units": UNITS}


def analyze_umbmark(measurements, *, robot=None, side: float = UMBMARK_SIDE) -> UMBmarkAnalysis:
    """UMBmark of a real robot's runs (``omnikin umbmark analyze``).

    ``measurements``: a measurements file (columns ``direction, x_abs, y_abs, x_calc, y_calc``
    [m], optional headings; :mod:`omnikin.io.runs`) or ``{"cw": eps, "ccw": eps}`` return
    errors ``(n, 2)`` or ``(n, 3)`` [m, m, rad]; ``robot``: a differential drive also gets
    Borenstein's correction; ``side`` [m] of the square.

    Parameters
    ----------
    measurements : str, os.PathLike or dict
        A measurements file, or ``{"cw": eps, "ccw": eps}`` with ``eps`` array_like of shape
        ``(n, 2)`` or ``(n, 3)``: the return errors ``(x, y[, theta])`` [m, m, rad] of each run,
        true (measured) minus calculated (odometry) end pose, world frame.
    robot : str, os.PathLike or Robot, optional
        The robot measured; a differential drive also gets Borenstein's correction.
    side : float, default 4.0
        Side of the square [m].

    Returns
    -------
    UMBmarkAnalysis
        Centres of gravity per direction and E_max,syst [m].

    Raises
    ------
    RunsFileError
        A measurements file that cannot be read, or runs missing in one direction.
    InputError
        Return errors of a bad shape or not finite, or a bad ``side``.
    """
    if isinstance(measurements, dict):
        eps = measurements
    else:
        from ..io.runs import read_umbmark_measurements

        eps = read_umbmark_measurements(measurements)
    res = analyze(eps["cw"], eps["ccw"], side, robot_of(robot) if robot is not None else None)
    return UMBmarkAnalysis(**{f.name: getattr(res, f.name) for f in fields(res)})
