"""A robot whose encoders declare ``counter_bits`` is simulated with the readings such counters
output (wrapped, unsigned), and everything downstream reads them back.

Before the fix a 12-bit robot could not be simulated once a count left 0 .. 4095 ("tick
reading -2051 outside the range of a 12-bit counter"), neither by ``omnikin simulate --log``
nor by ``omnikin umbmark``. Expected values: the readings are the counts modulo 2**12 (NumPy
here), the poses the closed form of the true increments (``support.tomasi.tomasi_poses``), and
a 12-bit robot must give exactly what the same robot without a counter width gives.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from omnikin import batch_odometry, load_robot
from omnikin.io.logs import read_tick_log
from omnikin.motion.plans import umbmark_square
from omnikin.simulation.error_models import NoiseModel
from omnikin.simulation.kinematic import counter_output, simulate_kinematic
from support.cli import run_entry_point
from support.tomasi import assert_poses_close, read_csv_traj, tomasi_file, tomasi_poses


def counter_robot_file(path, bits):
    """tomasi-omni3 as a robot file whose encoders are ``bits``-bit counters."""
    return tomasi_file(path.parent, f", counter_bits: {bits}", name=path.name)


def run(*args, cwd):
    return run_entry_point(*args, cwd=cwd, timeout=300)


def test_simulate_log_of_a_12_bit_robot_then_odometry(tmp_path):
    """omnikin simulate cb12.yaml --log x.csv, then omnikin odometry cb12.yaml x.csv: the log holds
    the counts modulo 4096, and its odometry is the closed form of the true increments, ending
    where the simulator's own odometry ended and where the same run of tomasi-omni3 ends."""
    robot = counter_robot_file(tmp_path / "cb12.yaml", 12)
    common = ["--path", "square cw rotate 1", "--rate", "50", "--seed", "4", "--json"]
    sim = run("simulate", robot, "--log", "x.csv", *common, cwd=tmp_path)
    assert sim.returncode == 0, sim.stderr
    plain = run("simulate", "tomasi-omni3", "--log", "plain.csv", *common, cwd=tmp_path)
    assert plain.returncode == 0, plain.stderr
    wrapped = read_tick_log(tmp_path / "x.csv", load_robot(robot))
    counts = read_tick_log(tmp_path / "plain.csv", load_robot("tomasi-omni3"))
    assert counts.ticks.min() < 0  # the counts leave 0 .. 4095: the counter must wrap
    assert wrapped.ticks.min() >= 0 and wrapped.ticks.max() < 4096
    np.testing.assert_array_equal(wrapped.ticks, counts.ticks % 4096)
    odo = run("odometry", robot, "x.csv", "-o", "traj.csv", cwd=tmp_path)
    assert odo.returncode == 0, odo.stderr
    traj = read_csv_traj(tmp_path / "traj.csv")[:, 1:]
    assert_poses_close(traj, tomasi_poses(np.diff(counts.ticks, axis=0)), atol=1e-8)
    assert traj[-1].tolist() == pytest.approx(json.loads(sim.stdout)["odometry_end"], abs=1e-9)
    assert json.loads(sim.stdout)["odometry_end"] == json.loads(plain.stdout)["odometry_end"]
    # read without the width the same log is refused, naming a line and the width to give
    refused = run("odometry", "tomasi-omni3", "x.csv", "-o", "t2.csv", cwd=tmp_path)
    assert refused.returncode == 2 and "read as a 12-bit counter" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_umbmark_of_a_12_bit_robot_matches_the_robot_without_a_width(tmp_path):
    """omnikin umbmark cb12.yaml runs, and its results are those of tomasi-omni3 (same seed):
    the counter width changes the readings, never the odometry."""
    robot = counter_robot_file(tmp_path / "cb12.yaml", 12)
    out = {}
    for name, r in (("cb12", robot), ("plain", "tomasi-omni3")):
        proc = run("umbmark", r, "-o", name, "--runs", "2", "--json", "--figures", "svg", cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        out[name] = json.loads(proc.stdout)
    for key in ("before", "after", "systematic"):
        assert out["cb12"][key] == out["plain"][key]


@pytest.mark.parametrize("bits", [8, 16, 32, 64])
def test_simulated_readings_are_the_counts_modulo_the_counter(tmp_path, bits):
    """SimulatedRun.readings: counts modulo 2**bits in [0, 2**bits) (uint64 for 64 bits),
    SimulatedRun.ticks the counts themselves; the odometry of the readings is the closed form."""
    robot = load_robot(counter_robot_file(tmp_path / "r.yaml", bits))
    sim = simulate_kinematic(umbmark_square("ccw", 1.0, "rotate"), robot, robot, rate=100.0, noise=NoiseModel(), rng=1)
    counts = np.asarray(sim.ticks, dtype=object)
    expected = counts % (2**bits)
    assert np.asarray(sim.readings, dtype=object).tolist() == expected.tolist()
    assert counts.min() < 0
    poses = tomasi_poses(np.diff(sim.ticks, axis=0))
    assert_poses_close(sim.odometry, poses, atol=1e-9)
    assert_poses_close(batch_odometry(robot, sim.t, sim.readings).poses, poses, atol=1e-9)


def test_unquantised_readings_of_a_12_bit_robot_wrap_as_floats(tmp_path):
    """Without quantisation the simulated counts are real numbers: they wrap to the signed range, and
    the odometry reads them back exactly as the robot without a width reads the counts."""
    robot = load_robot(counter_robot_file(tmp_path / "r.yaml", 12))
    plain = load_robot("tomasi-omni3")
    plan = umbmark_square("cw", 2.0, "rotate")
    sim = simulate_kinematic(plan, robot, robot, rate=50.0, noise=NoiseModel(quantise=False), rng=1)
    ref = simulate_kinematic(plan, plain, plain, rate=50.0, noise=NoiseModel(quantise=False), rng=1)
    assert sim.readings.dtype == np.float64 and sim.readings.min() >= -2048 and sim.readings.max() <= 2048
    assert sim.ticks.max() > 2048 or sim.ticks.min() < -2048  # they wrapped
    np.testing.assert_array_equal(sim.ticks, ref.ticks)
    assert_poses_close(sim.odometry, ref.odometry, atol=1e-9)


def test_counter_output_mixes_widths():
    ticks = np.array([[0, 0, 0], [-1, 70000, -5], [2**40, -(2**40), 3]], dtype=np.int64)
    out = counter_output(ticks, [8, None, 64])
    assert out.tolist() == [[0, 0, 0], [255, 70000, 2**64 - 5], [0, -(2**40), 3]]
    assert counter_output(ticks, [None, None, None]) is ticks
    assert counter_output(ticks, [8, 16, None]).dtype == np.int64


def test_an_odometry_robot_without_the_width_reads_the_counts_right(tmp_path):
    """The readings of a 12-bit robot read by an odometry robot without a counter width (and the
    other way round) are not misread: each reads the counts as its own counters output them."""
    cb12 = load_robot(counter_robot_file(tmp_path / "r.yaml", 12))
    plain = load_robot("tomasi-omni3")
    plan = umbmark_square("cw", 2.0, "rotate")
    for command, odometry in ((cb12, plain), (plain, cb12)):
        sim = simulate_kinematic(plan, command, command, rate=50.0, noise=NoiseModel(), rng=1, odometry_robot=odometry)
        assert_poses_close(sim.odometry, tomasi_poses(np.diff(sim.ticks, axis=0)), atol=1e-9)


def test_systematic_errors_keep_the_encoder_fields_they_do_not_change(tmp_path):
    """A robot as built with a ticks-per-revolution error is still the robot of the file: its
    12-bit counters, gearbox, direction, max_speed, description stay (before the fix the error
    model rebuilt the Encoder from three fields and the counters lost their width). The only
    change: ticks_per_rev 600 * (1 + 0.01) = 606."""
    from dataclasses import fields

    from omnikin.simulation.error_models import ErrorProfile, SystematicErrors, WheelErrors

    path = tomasi_file(tmp_path, ", gear_ratio: 2.5, invert: true, counter_bits: 12", ", max_speed: 40")
    robot = load_robot(path)
    drawn = ErrorProfile(ticks=0.01).sample(robot, np.random.default_rng(3))
    for errors in (SystematicErrors({w.name: WheelErrors(ticks=0.01) for w in robot.wheels}), drawn):
        true = errors.apply(robot)
        for nominal, built in zip(robot.wheels, true.wheels, strict=True):
            assert built.encoder.ticks_per_rev != 600.0
            for f in fields(built.encoder):
                if f.name != "ticks_per_rev":
                    assert getattr(built.encoder, f.name) == getattr(nominal.encoder, f.name), f.name
            assert (built.encoder.counter_bits, built.encoder.gear_ratio, built.encoder.invert) == (12, 2.5, True)
            assert (built.max_speed, built.steer) == (40.0, None)
    exact = SystematicErrors({"w1": WheelErrors(ticks=0.01)}).apply(robot)
    assert exact.wheels[0].encoder.ticks_per_rev == pytest.approx(606.0, rel=1e-15)


def test_a_robot_as_built_or_calibrated_keeps_every_field_the_errors_do_not_change():
    """Every field of the Robot but its name and wheels, and of each Wheel but the six the errors
    move (x, y, drive, roller, radius, encoder), comes through SystematicErrors.apply, Borenstein's
    correction and the least-squares calibration as it was: the physical fields of a physics
    engine (mass, centre of mass, wheel width), the description and references, max_speed, the
    motor. A re-built Robot(name, wheels, description, references) dropped the body's physical
    fields. The robot as built remembers its design: the robot itself."""
    from dataclasses import fields, replace

    from omnikin.evaluation.calibration import borenstein_calibrate, least_squares_calibration
    from omnikin.evaluation.umbmark import simulate_umbmark
    from omnikin.kinematics.physical import PhysicalBody, PhysicalWheel
    from omnikin.motion.plans import CalibrationRun, line, spin
    from omnikin.simulation.error_models import SystematicErrors, WheelErrors

    diff = load_robot("diff-drive")
    robot = replace(
        diff,
        physical=PhysicalBody(mass=12.0, com=(0.01, 0.0, 0.05), height=0.1),
        references=("Borenstein and Feng 1996",),
        wheels=tuple(replace(w, physical=PhysicalWheel(width=0.03, mass=0.4), max_speed=30.0) for w in diff.wheels),
    )
    moved = {"x", "y", "drive", "roller", "radius", "encoder"}
    true = SystematicErrors({"left": WheelErrors(radius=0.01, dy=0.002, ticks=0.001)}).apply(robot)
    assert true.design is robot
    umb = simulate_umbmark(true, robot, side=1.0, mode="rotate", runs=1, noise=NoiseModel(quantise=False), rate=20.0)
    runs = [CalibrationRun(line(1.0), (1.001, 0.002, 0.0)), CalibrationRun(spin(3.0), (0.0, 0.0, 3.01))]
    for out, kept in (
        (true, {f.name for f in fields(robot)} - {"name", "wheels", "design"}),
        (borenstein_calibrate(robot, umb[0]), {f.name for f in fields(robot)} - {"wheels"}),
        (least_squares_calibration(robot, runs).robot, {f.name for f in fields(robot)} - {"wheels", "description"}),
    ):
        for name in kept:
            assert getattr(out, name) == getattr(robot, name), name
        for nominal, built in zip(robot.wheels, out.wheels, strict=True):
            for f in fields(nominal):
                if f.name not in moved:
                    assert getattr(built, f.name) == getattr(nominal, f.name), (nominal.name, f.name)
