"""What a physics run will take, estimated before it starts (:mod:`omnikin.physics.cost`), and
the refusal of ``--max-time`` / ``max_time`` built on it.

Expected values: the run itself, counted here (its time steps, samples and simulated time), which
the estimate's counts must bound; the estimate's seconds as docs/physics.md ("Computing time")
composes them. How the measured cost per step compares with a run's computing time depends on the
machine's pace, so it is measured in benchmarks/bench_physics.py, not asserted here.
"""

from __future__ import annotations

import math

import pytest
import yaml

import omnikin
from omnikin import load_robot
from omnikin.errors import ResourceLimitError
from omnikin.motion.plans import parse_plan
from omnikin.motion.timing import sample_plan
from omnikin.physics.cost import physics_run_cost, real_time_shortfall, simulated_bound
from omnikin.physics.run import simulate_physics
from omnikin.physics.simulator import PhysicsSim
from omnikin.presets import preset_path
from support.cli import run_cli

pytest.importorskip("mujoco")


def robot_with(tmp_path, preset: str, physical: dict, name: str = "variant"):
    """``preset`` with ``physical`` fields on every wheel, as a robot file."""
    doc = yaml.safe_load(preset_path(preset).read_text())
    for wheel in doc["wheels"]:
        wheel["physical"] = dict(physical)
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return load_robot(path)


def estimated_and_run(robot, path: str, rate: float, step: float, taken: list[int] | None = None):
    """The estimate for ``path`` and the run's simulated time and samples; ``taken``
    (:func:`count_time_steps`) set to zero between the two (the estimate drives the model too,
    to measure a step's cost), so that it counts the run's steps."""
    parts = [parse_plan(part) for part in path.split(";")]
    plan = parts[0]
    for part in parts[1:]:
        plan = plan + part
    sampled = sample_plan(plan, robot, rate)
    estimate = physics_run_cost(sampled, robot, robot, step)
    if taken is not None:
        taken[0] = 0
    run = simulate_physics(sampled, robot, robot, rate=rate, step=step)
    return estimate, float(run.t[-1]), sampled


@pytest.mark.parametrize(
    ("preset", "physical", "path", "rate", "step"),
    [
        ("tomasi-omni3", {}, "line 6", 50.0, 0.002),
        ("tomasi-omni3", {}, "line 1", 100.0, 0.0005),  # a smaller step: more steps per second
        ("tomasi-omni3", {"rollers": 24, "rows": 4}, "line 2", 50.0, 0.002),  # 288 rollers
        ("mecanum4", {}, "spin 360", 20.0, 0.002),
        ("diff-drive", {}, "line 3", 200.0, 0.001),
    ],
)
def test_the_estimate_counts_every_time_step_and_sample_the_run_takes(
    tmp_path, monkeypatch, preset, physical, path, rate, step
):
    # a flat 5 ms per simulated second, whatever the model and step, would ignore both: the
    # estimate's counts must bound what the run does, step for step (how the measured seconds per
    # step compare with a run's computing time is a matter of the machine's pace:
    # benchmarks/bench_physics.py, "estimate against the run")
    robot = robot_with(tmp_path, preset, physical) if physical else load_robot(preset)
    taken = count_time_steps(monkeypatch)
    estimate, simulated, sampled = estimated_and_run(robot, path, rate, step, taken)
    assert simulated <= estimate.simulated
    assert taken[0] == pytest.approx(simulated / step, abs=1)  # the count is the run's own
    assert taken[0] <= estimate.steps
    assert len(sampled.t) - 1 <= estimate.samples
    # the steps are the bound on simulated time over the step, not a fixed rate per second
    assert estimate.steps == pytest.approx(estimate.simulated / step, abs=1)


def test_the_estimate_adds_construction_steps_and_samples_at_their_measured_costs():
    # docs/physics.md "Computing time": built + steps x (seconds per step) + samples x 25 us
    robot = load_robot("tomasi-omni3")
    sampled = sample_plan(parse_plan("line 1"), robot, 50.0)
    built, per_step = 0.125, 3e-5
    estimate = physics_run_cost(sampled, robot, robot, 0.002, measured=(per_step, built))
    steps = math.ceil((float(sampled.t[-1]) + 5.0) / 0.002)  # the plan plus the 5 s tail bound
    assert estimate.steps == steps
    assert estimate.step_seconds == per_step
    assert estimate.seconds == pytest.approx(built + steps * per_step + estimate.samples * 25e-6)


def count_time_steps(monkeypatch) -> list[int]:
    """Counts the time steps every :class:`PhysicsSim` of this test is driven (the ``n`` of
    each :meth:`PhysicsSim.step`; the settling on the floor before time 0 is not a step of the
    run), in a one-element list."""
    taken = [0]
    real_step = PhysicsSim.step

    def counted(self, n=1):
        taken[0] += n
        return real_step(self, n)

    monkeypatch.setattr(PhysicsSim, "step", counted)
    return taken


def test_steering_waits_are_counted_in_the_simulated_bound(tmp_path):
    # motors too weak to drive: every segment waits for its steering and rest, up to ALIGN_MAX
    robot = robot_with(tmp_path, "synchro", {"max_torque": 1e-5})
    path = "; ".join(["line 0.01 90; line 0.01 0"] * 3)
    estimate, simulated, sampled = estimated_and_run(robot, path, 50.0, 0.002)
    assert simulated > 4.0 * float(sampled.t[-1])  # the waits dominate the run
    assert simulated <= simulated_bound(sampled, robot) == estimate.simulated


def never_run(monkeypatch, *targets) -> list:
    """Stand-ins for the expensive work (``(module, name)`` pairs) that note a call and fail: a
    refusal up front comes before that work, whatever the pace of the machine."""
    import importlib

    calls: list = []
    for module, name in targets:

        def stand_in(*args, _name=f"{module}.{name}", **kwargs):
            calls.append(_name)
            raise AssertionError(f"{_name} ran before the refusal")

        monkeypatch.setattr(importlib.import_module(module), name, stand_in)
    return calls


PHYSICS_RUN = (("omnikin.physics.run", "simulate_physics"),)


def test_simulate_refuses_a_run_over_max_time_up_front_for_a_small_step(tmp_path, capsys, monkeypatch):
    # line 1 at 10 us steps takes about 10 s: refused before simulating
    ran = never_run(monkeypatch, *PHYSICS_RUN)
    rc, _, err = run_cli(
        capsys,
        "simulate",
        "tomasi-omni3",
        "--engine",
        "physics",
        "--errors",
        "none",
        "--path",
        "line 1",
        "--step",
        "1e-5",
        "--max-time",
        "3",
        "--log",
        tmp_path / "o.csv",
    )
    assert ran == [] and rc == 2
    assert err.count("\n") == 1 and "more than --max-time 3 s" in err and "--step" in err
    assert not (tmp_path / "o.csv").exists()


def test_the_python_api_refuses_a_heavy_model_over_max_time(tmp_path):
    robot = robot_with(tmp_path, "tomasi-omni3", {"rollers": 24, "rows": 4})
    with pytest.raises(ResourceLimitError, match="max_time"):
        omnikin.simulate(robot, "line 4", errors="none", engine="physics", max_time=0.2)


def weak_synchro_path(tmp_path):
    """synchro whose motors cannot move it, and a path of 20 segments each steering anew: every
    segment waits up to ALIGN_MAX (5 s) for its steering and rest, 82 s simulated in all."""
    robot = robot_with(tmp_path, "synchro", {"max_torque": 1e-5}, name="weak")
    return tmp_path / "weak.yaml", "; ".join(["line 0.01 90; line 0.01 0"] * 10), robot


def test_simulate_checks_the_bag_s_stamps_against_the_steering_waits_before_simulating(tmp_path, capsys, monkeypatch):
    # the plan lasts 13 s, the run 82 s: 30 s of room left in the bag's times is too little
    pytest.importorskip("rosbags")
    file, path, _ = weak_synchro_path(tmp_path)
    ran = never_run(monkeypatch, *PHYSICS_RUN)
    rc, _, err = run_cli(
        capsys,
        "simulate",
        file,
        "--engine",
        "physics",
        "--errors",
        "none",
        "--path",
        path,
        "--bag",
        tmp_path / "o.bag",
        "--start",
        str(2**31 - 1 - 30),
    )
    assert rc == 2 and "do not fit a ROS 2 bag" in err and err.count("\n") == 1
    assert ran == []  # refused before simulating


@pytest.mark.parametrize(
    "argv",
    [
        ("--seed", "-1"),
        ("diff-drive", "--mode", "translate"),
        ("--runs", "0"),
        ("--errors", "none", "--true-robot", str(preset_path("omni4"))),
        ("--step", "0.0015"),  # 100 Hz is not a whole number of 1.5 ms steps
    ],
)
def test_umbmark_physics_refuses_bad_settings_in_one_line_before_its_cost_note(tmp_path, capsys, argv):
    rc, _, err = run_cli(capsys, "umbmark", "--engine", "physics", "-o", tmp_path / "report", *argv)
    assert rc == 2 and err.count("\n") == 1 and err.startswith("omnikin: error:")
    assert not (tmp_path / "report").exists()


def test_the_robot_as_built_drawn_out_of_range_is_named_as_the_draw(tmp_path, capsys):
    # radius 0.1 mm, the least a file may give: the typical draw makes it smaller
    doc = yaml.safe_load(preset_path("tomasi-omni3").read_text())
    for wheel in doc["wheels"]:
        wheel["radius"] = 0.0001
        wheel["distance"] = 0.0003
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(doc))
    rc, _, err = run_cli(capsys, "umbmark", tmp_path / "tiny.yaml", "-o", tmp_path / "report")
    assert rc == 2 and err.count("\n") == 1
    assert "as built" in err and "--errors" in err and "radius must lie in" in err


def ring_of_roller_wheels(tmp_path, count: int):
    """``count`` omni wheels of 64 x 4 rollers on a ring, as a robot file."""
    wheels = [
        {
            "name": f"w{i + 1}",
            "type": "omni",
            "distance": 0.05 * count,
            "angle_deg": 360.0 * i / count,
            "radius": 0.04125,
            "encoder": {"ticks_per_rev": 600},
            "physical": {"rollers": 64, "rows": 4},
        }
        for i in range(count)
    ]
    path = tmp_path / f"rollers{count}.yaml"
    path.write_text(yaml.safe_dump({"omnikin": 1, "name": "rollers", "wheels": wheels}))
    return path


def test_a_model_too_large_for_max_time_is_refused_without_building_it(tmp_path, capsys, monkeypatch):
    # 64 wheels of 256 rollers: 16 450 bodies, 21 s to compile, ten times that to drive a metre
    built = [
        (module, "PhysicsSim") for module in ("omnikin.physics.cost", "omnikin.physics.run", "omnikin.physics.backend")
    ]
    ran = never_run(monkeypatch, *built, *PHYSICS_RUN)
    rc, _, err = run_cli(
        capsys, "simulate", ring_of_roller_wheels(tmp_path, 64), "--engine", "physics", "--errors", "none",
        "--path", "line 1", "--max-time", "1", "--log", tmp_path / "o.csv",
    )  # fmt: skip
    assert rc == 2 and "more than --max-time 1 s" in err and err.count("\n") == 1
    assert ran == []  # neither built nor run


def test_a_model_too_slow_for_real_time_is_named_before_a_real_time_run(tmp_path):
    # 24 omni wheels of 64 x 4 rollers: a quarter of real time here, 8 times short of the margin
    message = real_time_shortfall(load_robot(ring_of_roller_wheels(tmp_path, 24)), "it will run slower")
    assert message is not None and "x real time on this machine" in message and "\n" not in message
    assert real_time_shortfall(load_robot("tomasi-omni3"), "it will run slower") is None
