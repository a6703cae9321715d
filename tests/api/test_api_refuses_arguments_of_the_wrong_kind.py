"""The Python API refuses an argument of the wrong kind in one omnikin error naming the argument
(an :class:`~omnikin.errors.InputError` or the reader's own error), before any work starts, never
with a TypeError or AttributeError from deep inside."""

from __future__ import annotations

import numpy as np
import pytest

import omnikin
from omnikin.errors import InputError, RunsFileError, StudyFileError
from omnikin.physics.engines import PhysicsEngine
from omnikin.simulation.engine import KinematicEngine

ROBOT = "diff-drive"


@pytest.mark.parametrize("engine_class", [KinematicEngine, PhysicsEngine])
def test_an_engine_class_instead_of_an_engine_is_refused(engine_class):
    with pytest.raises(InputError, match=rf"engine object, e\.g\. {engine_class.__name__}\(\)"):
        omnikin.simulate(ROBOT, "line 0.2", engine=engine_class)
    with pytest.raises(InputError, match="engine object"):
        omnikin.run_umbmark(ROBOT, engine=engine_class)


@pytest.mark.parametrize("callback", ["progress", "on_cost"])
@pytest.mark.parametrize("entry", [omnikin.simulate, omnikin.run_umbmark])
def test_a_callback_that_cannot_be_called_is_refused(entry, callback):
    with pytest.raises(InputError, match=rf"^{callback} must be a function"):
        entry(ROBOT, **{callback: 5})


@pytest.mark.parametrize(
    ("runs", "named"),
    [(None, "None"), (5, "5"), (np.zeros((3, 3)), r"an array of shape \(3, 3\)"), (b"runs.csv", "b'runs.csv'")],
)
def test_calibration_runs_of_the_wrong_kind_are_refused(runs, named):
    with pytest.raises(InputError, match=rf"^runs must be a runs file or a sequence of CalibrationRun, got {named}"):
        omnikin.calibrate(ROBOT, runs)


def test_a_calibration_run_of_the_wrong_kind_is_named_by_its_index():
    with pytest.raises(InputError, match=r"^runs\[0\] must be a CalibrationRun, got 'square'"):
        omnikin.calibrate(ROBOT, ["square"])


@pytest.mark.parametrize(
    ("arguments", "named"),
    [
        ({"spec": None}, "spec"),
        ({"spec": {"omnikin_sweep": 1}}, "spec"),
        ({"out": None}, "out"),
        ({"out": 5}, "out"),
        ({"scheduler": 5}, "scheduler"),
        ({"progress": 5}, "progress"),
        ({"tls": "ca.pem"}, "tls"),
    ],
)
def test_sweep_arguments_of_the_wrong_kind_are_refused_before_a_cluster_starts(tmp_path, arguments, named):
    pytest.importorskip("dask")
    given = {"spec": tmp_path / "study.yaml", "out": tmp_path / "study", **arguments}
    spec, out = given.pop("spec"), given.pop("out")
    with pytest.raises(InputError, match=rf"^{named} must be "):
        omnikin.run_sweep(spec, out, **given)
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing made


@pytest.mark.parametrize(
    ("read", "error"),
    [
        (lambda: omnikin.analyze_umbmark(None), RunsFileError),
        (lambda: omnikin.analyze_umbmark(5), RunsFileError),
        (lambda: __import__("omnikin.sweep.spec", fromlist=["load_study"]).load_study(None), StudyFileError),
    ],
)
def test_a_reader_given_no_path_says_so(read, error):
    with pytest.raises(error, match=r"not a path to .* \(give a str or os\.PathLike\)"):
        read()
