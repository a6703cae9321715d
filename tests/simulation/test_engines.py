"""The engine interface: the kinematic and the physics engine do the same things for a robot as
built (drive a plan, make a wheel back-end, estimate a run, refuse what they cannot do), and a
name becomes an engine in one place.

Expected values from closed forms, not from the code under test:

* ``line 1`` for diff-drive (no wheel speed limit) under the default motion limits (0.3 m/s,
  0.5 m/s^2) is a trapezoid: 0.6 s to reach 0.3 m/s over 0.09 m, the same to stop, and
  (1 - 0.18) / 0.3 = 2.7333 s at speed, 3.9333 s in all. Sampled at 100 Hz from t = 0 it takes
  ceil(393.33) = 394 intervals, 395 samples; the estimate made without sampling is the duration
  times the rate plus one, 394.33 (an upper bound of the intervals, within one sample).
* each wheel (radius 0.0825 m, 500 ticks per revolution behind a 19.7:1 gear) rolls 1 m:
  1 / 0.0825 rad, ``1 / 0.0825 / (2 pi) * 500 * 19.7`` = 19001.9 ticks, counted 19002.
* a kinematic back-end whose wheels both turn at 2 rad/s for 1 s moves diff-drive straight
  ahead by 2 * 0.0825 = 0.165 m.
"""

import math

import numpy as np
import pytest

import omnikin
from omnikin import load_robot
from omnikin.errors import InputError
from omnikin.motion.plans import parse_plan
from omnikin.physics.engines import ENGINE_NAMES, PhysicsEngine, as_engine, engine_class, engine_named
from omnikin.simulation.engine import Engine, KinematicEngine
from omnikin.simulation.error_models import NOISE

DURATION = 2 * 0.6 + (1.0 - 0.5 * 0.6**2) / 0.3  # [s], line 1 (module docstring)
TICKS = 1.0 / 0.0825 / (2 * math.pi) * 500 * 19.7  # per wheel, line 1


def test_both_engines_implement_the_interface_and_are_named_by_the_one_list():
    engines = [engine_named(name) for name in ENGINE_NAMES]
    assert sorted(e.name for e in engines) == ["kinematic", "physics"]
    for engine in engines:
        assert isinstance(engine, Engine)
        assert engine_class(engine.name) is type(engine)
    assert isinstance(KinematicEngine(), Engine) and isinstance(PhysicsEngine(), Engine)
    assert not isinstance("physics", Engine)


def test_making_an_engine_does_not_import_mujoco():
    import subprocess
    import sys

    code = (
        "import sys, omnikin\n"
        "from omnikin import PhysicsEngine, engine_named\n"
        "engine_named('physics', step=0.001); PhysicsEngine()\n"
        "print('mujoco' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


@pytest.mark.parametrize("name", ["mujoco", "Physics", "", 3, None])
def test_an_unknown_engine_is_refused_in_one_line_naming_the_choices(name):
    with pytest.raises(InputError) as info:
        engine_named(name)
    message = str(info.value)
    assert "\n" not in message and "kinematic, physics" in message


def test_each_engine_refuses_the_other_engines_option_in_one_line():
    with pytest.raises(InputError, match=r"time step of the physics engine") as info:
        engine_named("kinematic", step=0.001)
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match=r"physics engine has no random error model") as info:
        engine_named("physics", noise="typical")
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match=r"must be a time step"):
        engine_named("physics", step=1.0)


def test_an_engine_carries_the_options_it_was_made_with():
    assert engine_named("physics", step=0.001).options == {"step": 0.001}
    assert engine_named("physics").options == {"step": 0.002}  # the documented default, 2 ms
    assert engine_named("kinematic").options == {}
    assert engine_named("physics", step=0.001) == PhysicsEngine(0.001) != PhysicsEngine(0.002)


def test_a_name_or_an_engine_object_is_accepted_where_the_api_takes_an_engine():
    engine = PhysicsEngine(0.001)
    assert as_engine(engine) is engine
    assert as_engine("physics", step=0.001) == engine
    with pytest.raises(InputError, match="engine object"):
        as_engine(engine, step=0.002)
    with pytest.raises(InputError, match="kinematic, physics"):
        as_engine(object())


def test_noise_belongs_to_the_kinematic_engine_alone():
    assert KinematicEngine().noise_model(None) == NOISE["typical"]
    assert KinematicEngine().noise_model("none") == NOISE["none"]
    assert PhysicsEngine().noise_model(None) is None
    with pytest.raises(InputError, match="no random error model"):
        PhysicsEngine().noise_model("none")


def test_kinematic_estimate_and_run_agree_with_the_closed_form_sample_count():
    robot = load_robot("diff-drive")
    plan = parse_plan("line 1")
    engine = KinematicEngine()
    cost = engine.cost(plan, robot, robot, rate=100.0)
    assert cost.samples == pytest.approx(DURATION * 100.0 + 1.0, rel=1e-12)
    assert engine.cost(plan, robot, robot, rate=100.0, timed=False) == cost
    run = engine.drive(plan, robot, robot, rate=100.0, noise=NOISE["none"])
    assert len(run.t) == math.ceil(DURATION * 100.0) + 1 == 395
    assert cost.samples <= len(run.t) < cost.samples + 1
    assert run.t[-1] == pytest.approx(394 / 100.0)
    np.testing.assert_allclose(run.ticks[-1], [TICKS, TICKS], rtol=1e-9)
    np.testing.assert_allclose(run.truth[0, -1], [1.0, 0.0, 0.0], atol=1e-12)
    assert engine.problems(run) == [] and engine.summary(run) == {}


def test_the_kinematic_engine_checks_the_rate_range_only():
    engine = KinematicEngine()
    assert engine.check_rate(300.0) == 300.0
    with pytest.raises(InputError, match="--rate"):
        engine.check_rate(0.0, "--rate")


def test_a_kinematic_back_end_moves_the_robot_as_its_wheels_turn():
    robot = load_robot("diff-drive")
    backend = KinematicEngine().backend(robot)
    backend.write(0.0, np.full(len(robot.rolling_names), 2.0))
    backend.read(1.0)
    np.testing.assert_allclose(backend.truth, [2.0 * 0.0825, 0.0, 0.0], atol=1e-12)
    backend.close()


def test_the_api_takes_an_engine_object_and_gives_the_run_its_name_gives():
    by_name = omnikin.simulate("diff-drive", "line 1", errors="none", noise="none", seed=3)
    by_object = omnikin.simulate("diff-drive", "line 1", errors="none", noise="none", seed=3, engine=KinematicEngine())
    np.testing.assert_array_equal(by_name.run.truth, by_object.run.truth)
    np.testing.assert_array_equal(by_name.run.readings, by_object.run.readings)


# --- the physics engine (extra physics) ---------------------------------------------------------------
physics = pytest.mark.skipif(
    __import__("importlib").util.find_spec("mujoco") is None, reason="needs the physics extra (MuJoCo)"
)


@physics
def test_the_physics_engine_reads_encoders_only_at_whole_time_steps():
    engine = PhysicsEngine(0.002)
    assert engine.check_rate(100.0) == 100.0  # 10 ms: 5 steps
    with pytest.raises(InputError, match=r"whole number of physics time\s+steps"):
        engine.check_rate(300.0)  # 3.33 ms is not a whole number of 2 ms steps


@physics
def test_physics_estimate_bounds_its_run_and_the_run_reads_the_closed_form_ticks():
    """The plan is the kinematic engine's (395 samples); the run goes on after it until the robot
    rests, at most TAIL_MAX (5 s): the estimate's simulated time is that bound, 3.94 + 5 s."""
    from omnikin.physics.run import TAIL_MAX

    robot = load_robot("diff-drive")
    plan = parse_plan("line 1")
    engine = PhysicsEngine()
    quick = engine.cost(plan, robot, robot, rate=100.0, timed=False)
    assert quick.samples == pytest.approx(DURATION * 100.0 + 1.0, rel=1e-12) and math.isnan(quick.seconds)
    cost = engine.cost(plan, robot, robot, rate=100.0)
    assert cost.simulated == pytest.approx(394 / 100.0 + TAIL_MAX, rel=1e-12)
    assert cost.samples == pytest.approx(cost.simulated * 100.0, rel=1e-12) and cost.seconds > 0
    run = engine.drive(plan, robot, robot, rate=100.0)
    assert 395 <= len(run.t) <= cost.samples + 1 and run.t[-1] <= cost.simulated + 1e-9
    np.testing.assert_allclose(run.ticks[-1], [TICKS, TICKS], rtol=0.005)  # the servos end on the command
    assert abs(run.truth[0, -1, 0] - 1.0) < 0.01
    assert engine.problems(run) == run.problems() and engine.summary(run) == run.summary()


@physics
def test_the_physics_engines_random_stream_draws_the_roller_phases():
    """Same seed, same run; the roller phases are the only randomness (diff-drive has standard
    wheels, no rollers: every phase gives the same run)."""
    robot = load_robot("tomasi-omni3")
    plan = parse_plan("line 0.2")
    engine = PhysicsEngine()
    one = engine.drive(plan, robot, robot, rate=50.0, rng=np.random.default_rng(7))
    again = engine.drive(plan, robot, robot, rate=50.0, rng=np.random.default_rng(7))
    other = engine.drive(plan, robot, robot, rate=50.0, rng=np.random.default_rng(8))
    np.testing.assert_array_equal(one.truth, again.truth)
    assert not np.array_equal(one.truth, other.truth)


@physics
def test_a_physics_back_end_is_a_wheel_back_end_with_a_true_pose():
    robot = load_robot("diff-drive")
    backend = PhysicsEngine().backend(robot)
    try:
        backend.write(0.0, np.full(len(robot.rolling_names), 2.0))
        backend.read(1.0)
        assert backend.truth.shape == (3,) and 0.0 < backend.truth[0] < 2.0 * 0.0825
    finally:
        backend.close()
