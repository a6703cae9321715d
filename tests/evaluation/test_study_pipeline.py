"""The one study pipeline: the report's study and a sweep's trial are the same stages with either
engine, each stage draws from its own named stream, and results are built by keyword."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from omnikin.evaluation.pipeline import (
    REPORT,
    REPORT_STREAMS,
    TRIAL,
    TRIAL_STREAMS,
    PipelineResult,
    Square,
    run_pipeline,
    seed_streams,
)
from omnikin.evaluation.procedure import UMBmarkStudy, draw_as_built, streams, umbmark_study
from omnikin.evaluation.tolerance_trial import TrialResult, TrialSettings, tolerance_trial
from omnikin.evaluation.umbmark import NoiseFloor, PhysicsFloor
from omnikin.io.robot_file import load_robot
from omnikin.simulation.engine import KinematicEngine
from omnikin.simulation.error_models import NOISE, PROFILES

SMALL = dict(side=1.0, mode="rotate", runs=2, rate=50.0, trials=1)


def _as_built(name: str, seed: int):
    robot = load_robot(name)
    true_robot, injected = draw_as_built(robot, PROFILES["typical"], streams(seed)["robot"])
    return robot, true_robot, injected


def _kinematic_pipeline(robot, true_robot, streams_, keep=TRIAL):
    square = Square(noise=NOISE["typical"], **SMALL)
    return run_pipeline(
        robot, true_robot, engine=KinematicEngine(), square=square, streams=streams_, calibrate=True, keep=keep
    )


def _trial_streams(seed: int, **replaced: int) -> dict:
    """The trial layout of SeedSequence(seed), with the named streams replaced by fresh ones."""
    out = seed_streams(np.random.SeedSequence(seed), TRIAL_STREAMS)
    out.update({name: np.random.SeedSequence(value) for name, value in replaced.items()})
    return out


def _calibration_ends(found: PipelineResult) -> np.ndarray:
    return np.array([run.measured for run in found.calibration_runs])


def test_the_report_study_is_the_pipeline_keeping_the_report():
    """``umbmark_study`` gives, bit for bit, what the pipeline gives with the report's streams of
    the same seed: the first procedures, the calibration and the floor."""
    robot, true_robot, injected = _as_built("diff-drive", 3)
    study = umbmark_study(robot, true_robot, injected=injected, noise=NOISE["typical"], seed=3, calibrate=True, **SMALL)
    square = Square(noise=NOISE["typical"], **SMALL)
    found = run_pipeline(
        robot, true_robot, engine=KinematicEngine(), square=square, streams=streams(3), calibrate=True, keep=REPORT
    )
    assert study.before[0].e_max_syst == found.before[0].e_max_syst
    assert study.after is not None and found.after is not None
    assert study.after[0].e_max_syst == found.after[0].e_max_syst
    assert study.calibration is not None and found.calibration is not None
    assert study.calibration.robot == found.calibration.robot
    assert found.floor is not None
    np.testing.assert_array_equal(study.floor.values, found.floor.values)
    assert study.borenstein == found.borenstein and study.borenstein is not None  # a differential drive, rotate


def test_a_trial_is_the_pipeline_keeping_its_numbers():
    robot = load_robot("tomasi-omni3")
    settings = TrialSettings(side=1.0, runs=2, rate=50.0)
    trial = tolerance_trial(robot, PROFILES["typical"], settings, np.random.SeedSequence(5))
    streams_ = seed_streams(np.random.SeedSequence(5), TRIAL_STREAMS)
    true_robot, _ = draw_as_built(robot, PROFILES["typical"], streams_["robot"])
    found = _kinematic_pipeline(robot, true_robot, streams_)
    assert found.after is not None
    assert trial.e_max_syst_before == found.before[0].e_max_syst
    assert trial.e_max_syst_after == found.after[0].e_max_syst
    assert trial.systematic_before == found.systematic["before"]
    assert trial.systematic_after == found.systematic["after"]
    assert found.floor is None and found.borenstein is None and found.poses == ()  # a trial keeps none


def test_the_kinematic_and_the_physics_study_give_the_same_keyed_fields():
    pytest.importorskip("mujoco")
    from omnikin.physics.engines import PhysicsEngine

    robot = load_robot("diff-drive")
    settings = dict(SMALL, runs=1, rate=100.0)
    kinematic = umbmark_study(robot, robot, noise=NOISE["typical"], seed=1, calibrate=True, **settings)
    physics = umbmark_study(robot, robot, seed=1, calibrate=True, engine=PhysicsEngine(), **settings)
    assert isinstance(kinematic, UMBmarkStudy) and isinstance(physics, UMBmarkStudy)
    assert (kinematic.engine.name, physics.engine.name) == ("kinematic", "physics")
    for study in (kinematic, physics):
        assert len(study.before) == 1 and study.after is not None and len(study.after) == 1
        assert study.calibration is not None
        assert set(study.systematic) == {"before", "after"}
        assert set(study.trajectories) == {"before", "after"}
        assert all(set(runs) == {"cw", "ccw"} for runs in study.trajectories.values())
        phases = sorted((p.phase, p.direction) for p in study.run_poses)
        assert phases == [("after", "ccw"), ("after", "cw"), ("before", "ccw"), ("before", "cw")]
        assert isinstance(study.floor, NoiseFloor)
    assert isinstance(physics.floor, PhysicsFloor) and len(physics.floor.values) == 1
    assert len(kinematic.floor.values) == 400  # the noise floor's procedures
    assert kinematic.borenstein is not None and physics.borenstein is None  # Borenstein: noise-model engines


def test_changing_the_calibration_stream_changes_only_the_calibration_and_what_follows():
    robot, true_robot, _ = _as_built("tomasi-omni3", 2)
    base = _kinematic_pipeline(robot, true_robot, _trial_streams(8))
    other = _kinematic_pipeline(robot, true_robot, _trial_streams(8, calibration=99))
    assert base.before[0].e_max_syst == other.before[0].e_max_syst
    np.testing.assert_array_equal(base.before[0].cw.epsilon, other.before[0].cw.epsilon)
    assert base.systematic["before"] == other.systematic["before"]
    assert not np.array_equal(_calibration_ends(base), _calibration_ends(other))
    assert base.calibration is not None and other.calibration is not None
    assert base.calibration.robot != other.calibration.robot


def test_changing_the_first_umbmark_stream_leaves_the_calibration_runs_and_the_after_stream_alone():
    robot, true_robot, _ = _as_built("tomasi-omni3", 2)
    base = _kinematic_pipeline(robot, true_robot, _trial_streams(8))
    other = _kinematic_pipeline(robot, true_robot, _trial_streams(8, before=77))
    assert not np.array_equal(base.before[0].cw.epsilon, other.before[0].cw.epsilon)
    np.testing.assert_array_equal(_calibration_ends(base), _calibration_ends(other))
    assert base.after is not None and other.after is not None
    np.testing.assert_array_equal(base.after[0].ccw.epsilon, other.after[0].ccw.epsilon)


def test_the_seed_layouts_name_distinct_children_of_one_seed():
    for layout in (REPORT_STREAMS, TRIAL_STREAMS):
        assert len(set(layout)) == len(layout) and layout[0] == "robot"
        children = seed_streams(np.random.SeedSequence(4), layout)
        assert list(children) == list(layout)
        states = [tuple(child.generate_state(4)) for child in children.values()]
        assert len(set(states)) == len(states)
        assert [child.spawn_key for child in children.values()] == [(k,) for k in range(len(layout))]


def _values(cls) -> list:
    return [0.0] * len([f for f in dataclasses.fields(cls) if f.init])


@pytest.mark.parametrize("cls", [UMBmarkStudy, TrialResult, PipelineResult, NoiseFloor, PhysicsFloor, Square])
def test_a_result_built_by_position_is_refused(cls):
    with pytest.raises(TypeError):
        cls(*_values(cls))


def test_a_trial_result_built_by_keyword_keeps_its_numbers():
    result = TrialResult(e_max_syst_before=0.4, e_max_syst_after=0.1, systematic_before=0.3, systematic_after=math.nan)
    assert result.reduction == pytest.approx(4.0)
    assert math.isnan(result.as_dict()["systematic_after"])
