"""``omnikin.calibrate`` and ``omnikin.calibration_plan``: calibration as ``omnikin calibrate`` does it."""

from __future__ import annotations

import os
from dataclasses import dataclass, fields

import numpy as np

from ..errors import InputError
from ..evaluation.calibration import CalibrationResult, predicted_end, recommended_runs
from ..motion.plans import UMBMARK_SIDE
from .common import require_viz, robot_of


@dataclass(frozen=True)
class Calibration(CalibrationResult):
    """A calibration (:func:`calibrate`) with the runs it fitted: ``robot`` is the calibrated
    robot, :meth:`parameters` the fitted values with units; plots the end-position residuals.

    Attributes
    ----------
    nominal : Robot
        The robot calibrated, as given.
    robot : Robot
        The calibrated robot: ``nominal`` with the fitted errors applied.
    errors : SystematicErrors
        The fitted systematic errors per wheel
        (:data:`~omnikin.evaluation.calibration.ERROR_UNITS`).
    values : dict of str to float
        The fitted parameters by name (``"w1.radius"``), in the units of
        :data:`~omnikin.evaluation.calibration.PARAMETER_UNITS`.
    residual_before, residual_after : float
        RMS of the weighted end-pose residuals [measurement sigmas] of the nominal and the
        calibrated model.
    identifiability : Identifiability
        Which parameters the runs determine, and their standard deviations.
    fits : bool
        Whether ``residual_after`` is at most :data:`~omnikin.evaluation.calibration.FIT_LIMIT`.
    runs : tuple of CalibrationRun
        The runs fitted, each a plan with its measured end pose ``(x, y, theta)``
        [m, m, rad] in the world frame of its start.
    """

    runs: tuple = ()

    def residuals(self) -> dict:
        """Measured minus predicted end position ``(n_runs, 2)`` [m] of every run, predicted by
        the nominal model (``"nominal"``) and by the calibrated one (``"calibrated"``).

        Returns
        -------
        dict of str to ndarray, shape (n_runs, 2)
            ``{"nominal": ..., "calibrated": ...}``: end-position residual ``(x, y)`` [m] of each
            run, in the world frame of its start, runs in the order of :attr:`runs`.
        """
        out = {}
        for label, model in (("nominal", self.nominal), ("calibrated", self.robot)):
            plans = dict.fromkeys(r.plan for r in self.runs)
            ends = {plan: predicted_end(plan, model, self.nominal)[:2] for plan in plans}
            out[label] = np.array([np.asarray(r.measured[:2]) - ends[r.plan] for r in self.runs])
        return out

    def plot(self):
        """End-position residual of each run [mm], nominal and calibrated model (a ``Figure``)."""
        require_viz()
        from ..viz.calibration import residuals_figure

        return residuals_figure(
            self.residuals(),
            [r.label for r in self.runs],
            f"calibration of {self.nominal.name} from {len(self.runs)} runs",
        )

    def write_robot(self, path, *, force: bool = False, inputs=()) -> None:
        """Write the calibrated robot file (JSON for ``.json``, else YAML) by the output policy
        (:func:`omnikin.io.output.check_output`: never an input, ``force`` to replace a file;
        ``-`` for standard output, YAML).

        Parameters
        ----------
        path : str or os.PathLike
            The robot file to write (``.json``: JSON, else YAML), or ``-``.
        force : bool, default False
            Replace an existing file.
        inputs : sequence of path, default ()
            Files read, which ``path`` may not be.

        Raises
        ------
        OutputExistsError
            ``path`` exists (without ``force``) or is an input.
        InputError
            An empty path, one naming a folder, or a missing parent folder.
        OutputError
            Writing failed.
        """
        from ..io.output import check_output, write_text
        from ..io.robot_file import robot_text

        target = check_output(path, inputs=inputs, force=force)
        write_text(path, robot_text(self.robot, target if target is not None else "robot.yaml"))


def calibrate(robot, runs) -> Calibration:
    """Least-squares calibration of ``robot`` from measured runs (``omnikin calibrate``).

    ``runs``: a runs file (columns ``path, x_abs, y_abs[, theta_abs_deg]``; :mod:`omnikin.io.runs`)
    or a sequence of :class:`~omnikin.motion.plans.CalibrationRun`. A run the robot cannot drive is
    refused, naming it (the check ``simulate`` makes).

    Parameters
    ----------
    robot : str, os.PathLike or Robot
        The nominal robot: a preset name, a robot file or a :class:`~omnikin.kinematics.robot.Robot`.
    runs : str, os.PathLike or sequence of CalibrationRun
        The runs driven by the nominal model, each with its measured end pose ``(x, y, theta)``
        [m, m, rad] in the world frame of its start (``theta`` NaN when not measured; a file
        gives the heading in degrees).

    Returns
    -------
    Calibration
        The calibrated robot, the fitted errors, the residuals and the runs.

    Raises
    ------
    InputError
        No run with a measured end pose, or ``runs`` neither a runs file nor a sequence of
        :class:`~omnikin.motion.plans.CalibrationRun`.
    RunsFileError
        A runs file that cannot be read (the message names the line and column).
    InfeasibleRunError
        A run the robot cannot drive (the first one is named).
    CalibrationFitError
        No robot of this layout, within the robot file's ranges, explains the runs.
    """
    from ..evaluation.calibration import least_squares_calibration as fit

    nominal = robot_of(robot)
    if isinstance(runs, (str, os.PathLike)):
        from ..io.runs import read_calibration_runs

        runs = read_calibration_runs(runs)
    runs = _calibration_runs(runs)
    res = fit(nominal, runs)
    return Calibration(**{f.name: getattr(res, f.name) for f in fields(res)}, runs=runs)


def _calibration_runs(runs) -> tuple:
    """``runs`` as a tuple of :class:`~omnikin.motion.plans.CalibrationRun`, else an
    :class:`~omnikin.errors.InputError` naming what was given instead."""
    from ..common.messages import shorten
    from ..motion.plans import CalibrationRun

    given = f"an array of shape {runs.shape}" if isinstance(runs, np.ndarray) else shorten(runs)
    if isinstance(runs, (bytes, np.ndarray)) or not hasattr(runs, "__iter__"):
        raise InputError(f"runs must be a runs file or a sequence of CalibrationRun, got {given}")
    runs = tuple(runs)
    for k, run in enumerate(runs):
        if not isinstance(run, CalibrationRun):
            raise InputError(f"runs[{k}] must be a CalibrationRun, got {shorten(run)} (runs: {given})")
    return runs


def calibration_plan(robot, side: float = UMBMARK_SIDE) -> list[str]:
    """The runs to drive to calibrate ``robot``: paths in the runs-file grammar, each to be driven
    :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times (``omnikin calibrate --plan``).

    Parameters
    ----------
    robot : str, os.PathLike or Robot
        A preset name, a robot file or a :class:`~omnikin.kinematics.robot.Robot`.
    side : float, default 4.0
        Side [m] of the UMBmark squares and length of the straight runs; the half circles
        have radius ``side / 2`` (:func:`~omnikin.evaluation.calibration.recommended_runs`).

    Returns
    -------
    list of str
        The paths the robot can drive, in the runs-file grammar (:func:`omnikin.motion.plans.parse_plan`,
        e.g. ``"square cw rotate 4"``, ``"spin 180"``); measure x, y and the heading at the end
        of each.
    """
    return [text for text, _ in recommended_runs(robot_of(robot), side)]
