"""The physics engine's edges: a diverged simulation is one line naming the simulated time at
which MuJoCo found it (MuJoCo's own text, captured here, is the reference), nothing of MuJoCo's
reaches standard error and no MUJOCO_LOG.TXT is written; hostile API arguments (unbounded times,
start poses, non-numeric commands, NumPy scalars) get one-line input errors; a sample rate whose
period is not a whole number of time steps is refused, naming the rates that are."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from omnikin import load_robot
from omnikin.errors import DivergedError, InputError
from omnikin.motion.plans import parse_plan
from omnikin.physics.mjcf import time_step
from omnikin.physics.run import check_rate_steps, simulate_physics
from omnikin.physics.simulator import ADVANCE_MAX, PhysicsSim
from support.cli import run_cli, run_entry_point
from support.paths import omnikin_env

KICK = """
import sys
import numpy as np
from omnikin import load_robot
from omnikin.physics.simulator import PhysicsSim, DivergedError
sim = PhysicsSim(load_robot("diff-drive"))
sim.advance(0.5)
sim.data.qvel[0] = 1e11  # beyond MuJoCo's bound on a velocity (1e10): it resets the state
try:
    sim.step(10)
except DivergedError as exc:
    print(exc.time, exc.settling)
    print(exc, file=sys.stderr)
"""


def test_a_diverged_run_is_one_line_at_mujocos_time_with_no_log_file(tmp_path):
    done = subprocess.run([sys.executable, "-c", KICK], cwd=tmp_path, capture_output=True, text=True,
                          env=omnikin_env(), timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT in the working folder
    assert done.stderr.count("\n") == 1 and "WARNING" not in done.stderr, done.stderr
    t, settling = done.stdout.split()
    # MuJoCo's own account of the same kick, its warning captured: "... Time = 0.5000."
    messages: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        sim = PhysicsSim(load_robot("diff-drive"))
        sim.advance(0.5)
        sim.data.qvel[0] = 1e11
        mujoco.mj_step(sim.model, sim.data)
    finally:
        mujoco.set_mju_user_warning(previous)
    reference = float(re.search(r"Time = (\d+\.\d+)", messages[0]).group(1))
    assert math.isclose(float(t), reference, abs_tol=1e-9) and settling == "False"
    assert f"diverged at t = {reference:.4g} s" in done.stderr


class _KickedWhileSettling(PhysicsSim):
    """A robot whose chassis is thrown down at 1e11 m/s when it is put on the floor."""

    def _settle(self, start):
        self.data.qvel[2] = -1e11
        super()._settle(start)


def test_a_robot_that_diverges_while_settling_says_so_without_option_advice():
    with pytest.raises(DivergedError) as caught:
        _KickedWhileSettling(load_robot("diff-drive"))
    message = str(caught.value)
    assert caught.value.settling and "while settling on the floor, 0 s after it was put down" in message
    assert "\n" not in message and "--step" not in message  # the engine has no option to advise


def test_a_huge_robot_on_small_wheels_fails_in_one_line_without_a_log_file(tmp_path):
    """The tester's file: omni3 with wheels 1000 m from the centre on 5 cm radii. MuJoCo
    diverged while settling at 0.7 s and printed its warning, and MUJOCO_LOG.TXT appeared in the
    working folder. Whatever the model's checks make of it, the command says it in one line; a
    divergence names the settling and suggests a smaller --step (the command has one)."""
    wheels = "\n".join(
        f"- {{name: w{i + 1}, type: omni, distance: 1000, angle_deg: {120 * i}, radius: 0.05, "
        f"encoder: {{ticks_per_rev: 600}}}}"
        for i in range(3)
    )
    (tmp_path / "big.yaml").write_text(f"omnikin: 1\nname: big\nwheels:\n{wheels}\n")
    done = run_entry_point("simulate", "big.yaml", "--engine", "physics", "--errors", "none", "--path", "line 1",
                           "--log", "log.csv", cwd=tmp_path, timeout=300)  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) in (["big.yaml"], ["big.yaml", "log.csv"])
    assert done.stderr.count("\n") <= 1 and "WARNING" not in done.stderr, done.stderr
    if "diverged" in done.stderr:
        assert done.returncode == 1
        assert "while settling on the floor" in done.stderr
        assert done.stderr.rstrip().endswith("or try a smaller time step (--step, now 0.002 s)")


@pytest.fixture(scope="module")
def sim():
    return PhysicsSim(load_robot("diff-drive"))


def test_advance_to_an_unbounded_time_is_refused_at_once(sim):
    for t in (1e300, ADVANCE_MAX + 1.0):
        with pytest.raises(InputError, match=r"^advance: at most 3600 s of simulated time per call"):
            sim.advance(t)
    with pytest.raises(InputError, match=r"^step: the number of steps must be a whole number from 0 to 1800000"):
        sim.step(10**12)
    assert sim.time == 0.0  # refused before any step, whatever the pace of the machine


@pytest.mark.parametrize("value", ["abc", [1.0, "x"], None, [[1.0, 2.0]], [1e400, 0.0]])
def test_non_numeric_wheel_commands_are_input_errors(sim, value):
    with pytest.raises(InputError, match=r"^robot 'diff-drive': expected 2 finite wheel speeds \[rad/s\]"):
        sim.command(value)


@pytest.mark.parametrize("start", [(1e300, 0.0, 0.0), (0.0, 0.0, 1e300), "abc", (0.0, 0.0)])
def test_start_poses_beyond_the_simulations_resolution_are_refused(start):
    with pytest.raises(InputError, match=r"^start pose must be 3 finite numbers \(x, y, theta\) within \+-100000"):
        PhysicsSim(load_robot("diff-drive"), start=start)


def test_a_numpy_time_step_is_a_time_step():
    assert time_step(np.float32(0.001)) == float(np.float32(0.001))
    sim = PhysicsSim(load_robot("diff-drive"), step=np.float32(0.001))
    assert math.isclose(sim.step_size, 0.001, rel_tol=1e-6)
    with pytest.raises(InputError, match=r"must be a time step"):
        time_step("0.001")


@pytest.mark.parametrize(("rate", "valid"), [(300, "500 or 250"), (10000, "500"), (30, "31.25 or 29.4117647")])
def test_a_rate_whose_period_is_not_whole_time_steps_is_refused(tmp_path, capsys, rate, valid):
    """At 2 ms the rates whose period is whole steps are 1 / (n 2 ms) = 500 / n Hz."""
    rc, out, err = run_cli(capsys, "simulate", "tomasi-omni3", "--engine", "physics", "--path", "line 1",
                           "--rate", rate, "--log", tmp_path / "log.csv")  # fmt: skip
    assert rc == 2 and err.count("\n") == 1
    assert f"choose --rate {valid} (1 / (n x step))" in err
    assert not (tmp_path / "log.csv").exists()


def test_the_rates_a_refusal_suggests_are_accepted():
    """1 / (n x 10 us): 2941.18 Hz lies 1.2e-6 off n = 34 and is refused; both rates the message
    names must pass the same check (printed as 2941.18 and 3030.3 they did not all)."""
    with pytest.raises(InputError) as info:
        check_rate_steps(2941.18, 1e-5)
    suggested = re.search(r"choose --rate (\S+) or (\S+) \(", str(info.value)).groups()
    assert [float(r) for r in suggested] == pytest.approx([1e5 / 33, 1e5 / 34], rel=1e-8)
    for rate in suggested:
        check_rate_steps(float(rate), 1e-5)


def test_the_tick_log_stamps_are_the_times_the_encoders_were_read():
    """At 250 Hz (two 2 ms steps per sample) a wheel turning at a constant speed counts the same
    ticks in every interval of its cruise (within one tick of quantisation), as the kinematic
    engine's tick log holds them at its stamps."""
    robot = load_robot("diff-drive")
    run = simulate_physics(parse_plan("line 2"), robot, robot, rate=250.0)
    assert np.allclose(np.diff(run.t)[: len(run.t) // 2], 0.004)
    increments = np.diff(run.ticks[:, 0])
    cruise = increments[len(increments) // 3 : len(increments) // 2]
    assert cruise.max() - cruise.min() <= 1


def test_a_divergence_advises_a_smaller_step_only_where_the_caller_has_one():
    diverged = DivergedError(
        "robot 'r': the physics simulation diverged at t = 0.5 s", time=0.5, settling=False, step=0.002
    )
    assert str(diverged.explained()) == str(diverged)  # ros, sim: no --step to give
    advised = diverged.explained(" (while measured)", step_option=True)
    assert str(advised).endswith("(while measured); or try a smaller time step (--step, now 0.002 s)")
    assert (advised.time, advised.settling, advised.step) == (0.5, False, 0.002)
    smallest = DivergedError("diverged", time=0.5, settling=True, step=1e-5)
    assert str(smallest.explained(step_option=True)) == "diverged"  # no smaller step is accepted
