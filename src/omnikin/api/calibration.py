"""``omnikin.calibrate`` and ``omnikin.calibration_plan``: calibration as ``omnikin calibrate`` does it."""

from __future__ import annotations

import os
from dataclasses import dataclass, fields

import numpy as np

from ..evaluation.calibration import CalibrationResult, predicted_end, recommended_runs
from .common import require_viz, robot_of


@dataclass(frozen=True)
class Calibration(CalibrationResult):
    """A calibration (:func:`calibrate`) with the runs it fitted: ``robot`` is the calibrated
    robot, :meth:`parameters` the fitted values with units; plots the end-position residuals."""

    runs: tuple = ()

    def residuals(self) -> dict:
        """Measured minus predicted end position ``(n_runs, 2)`` [m] of every run, predicted by
        the nominal model (``"nominal"``) and by the calibrated one (``"calibrated"``)."""
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
        ``-`` for standard output, YAML)."""
        from ..io.output import check_output, write_text
        from ..io.robot_file import robot_text

        target = check_output(path, inputs=inputs, force=force)
        write_text(path, robot_text(self.robot, target if target is not None else "robot.yaml"))


def calibrate(robot, runs) -> Calibration:
    """Least-squares calibration of ``robot`` from measured runs (``omnikin calibrate``).

    ``runs``: a runs file (columns ``path, x_abs, y_abs[, theta_abs_deg]``; :mod:`omnikin.io.runs`)
    or a sequence of :class:`~omnikin.motion.plans.CalibrationRun`. A run the robot cannot drive is
    refused, naming it (the check ``simulate`` makes).
    """
    from ..evaluation.calibration import calibrate as fit

    nominal = robot_of(robot)
    if isinstance(runs, (str, os.PathLike)):
        from ..io.runs import read_calibration_runs

        runs = read_calibration_runs(runs)
    runs = tuple(runs)
    res = fit(nominal, runs)
    return Calibration(**{f.name: getattr(res, f.name) for f in fields(res)}, runs=runs)


def calibration_plan(robot, side: float = 4.0) -> list[str]:
    """The runs to drive to calibrate ``robot``: paths in the runs-file grammar, each to be driven
    :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times (``omnikin calibrate --plan``)."""
    return [text for text, _ in recommended_runs(robot_of(robot), side)]
