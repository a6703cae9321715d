"""omnikin simulate --imu-log --scan-log: what the sensors read, in plain files, the same for the
same seed bit for bit; one-line refusals where there is nothing to read."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from support.cli import run_cli
from support.paths import ROOT

ROOM = ROOT / "examples" / "worlds" / "room.yaml"


def _simulate(capsys, tmp_path, *extra):
    imu, scans = tmp_path / "imu.csv", tmp_path / "scans.npz"
    rc, out, err = run_cli(
        capsys, "simulate", "tomasi-omni3-lidar", "--imu-log", imu, "--scan-log", scans, "--force", *extra
    )
    assert rc == 0, err
    return imu, scans


def test_the_first_scan_in_the_room_reads_the_distances_to_its_walls_and_furniture(capsys, tmp_path):
    _, scans = _simulate(capsys, tmp_path, "--world", ROOM, "--path", "line 1", "--errors", "none", "--noise", "none")
    with np.load(scans, allow_pickle=False) as data:
        ranges = data["laser.ranges"]
        assert data["laser.t"][0] == 0.0
        assert data["laser.angle_min"] == pytest.approx(-math.pi)
        assert data["laser.angle_increment"] == pytest.approx(math.radians(1.0))
        first = ranges[0]
    # room.yaml by hand, from the start (-4, 0) facing +x, walls 0.1 m thick:
    # beam 180 (0 deg) runs through the 1 m door and the corridor to the east room's far wall at x = 5.45
    assert first[180] == pytest.approx(5.45 + 4.0, abs=1e-5)
    assert first[270] == pytest.approx(1.95, abs=1e-5)  # +90 deg: the north wall's face at y = 1.95
    assert first[0] == pytest.approx(2.45, abs=1e-5)  # 180 deg: the west wall's face at x = -6.45
    assert first[90] == pytest.approx(1.2, abs=1e-5)  # -90 deg: the sofa's near side at y = -1.2


def test_a_robot_at_rest_reads_gravity_and_no_turn_and_sees_nothing_on_an_empty_floor(capsys, tmp_path):
    imu, scans = _simulate(capsys, tmp_path, "--path", "spin 0.001", "--errors", "none", "--noise", "none")
    with open(imu, newline="") as handle:
        rows = [r for r in csv.reader(line for line in handle if not line.startswith("#"))]
    assert rows[0] == ["sensor", "t", "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"]
    table = np.array([[float(v) for v in r[1:]] for r in rows[1:]])
    assert {r[0] for r in rows[1:]} == {"imu"}
    np.testing.assert_allclose(table[:, 0], np.arange(1, len(table) + 1) / 200.0)  # 200 Hz
    np.testing.assert_array_equal(table[:, 6], 9.81)
    with np.load(scans, allow_pickle=False) as data:
        assert np.all(np.isposinf(data["laser.ranges"]))


def test_the_same_seed_writes_the_same_readings_bit_for_bit_and_another_seed_others(capsys, tmp_path):
    first = tmp_path / "a"
    second = tmp_path / "b"
    third = tmp_path / "c"
    for folder, seed in ((first, "3"), (second, "3"), (third, "4")):
        folder.mkdir()
        _simulate(capsys, folder, "--world", ROOM, "--path", "line 1", "--seed", seed)
    assert (first / "imu.csv").read_bytes() == (second / "imu.csv").read_bytes()
    assert (first / "scans.npz").read_bytes() == (second / "scans.npz").read_bytes()
    assert (first / "imu.csv").read_bytes() != (third / "imu.csv").read_bytes()


def test_a_log_the_robot_cannot_fill_is_refused_before_the_run(capsys, tmp_path):
    rc, _, err = run_cli(capsys, "simulate", "tomasi-omni3", "--imu-log", tmp_path / "i.csv")
    assert rc == 2 and "robot 'tomasi-omni3' has no IMU" in err and err.count("\n") == 1
    rc, _, err = run_cli(capsys, "simulate", "diff-drive", "--scan-log", tmp_path / "s.npz")
    assert rc == 2 and "robot 'diff-drive' has no lidar" in err and err.count("\n") == 1
    assert not (tmp_path / "i.csv").exists() and not (tmp_path / "s.npz").exists()


def test_the_physics_engine_writes_the_same_logs_its_first_scan_within_the_range_noise(capsys, tmp_path):
    """The physics engine takes no --noise: its sensors read with their robot file's errors
    (the preset's 0.01 m range noise, 1 % dropouts) around what MuJoCo's rays measure."""
    pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")
    imu, scans = _simulate(capsys, tmp_path, "--world", ROOM, "--path", "line 0.3", "--engine", "physics")
    with np.load(scans, allow_pickle=False) as data:
        first = data["laser.ranges"][0]
        assert data["laser.t"][0] == 0.0 and len(data["laser.t"]) >= 5
    # room.yaml by hand, as above: 0.01 m of noise stays within 6 standard deviations
    for beam, expected in ((180, 9.45), (270, 1.95), (0, 2.45), (90, 1.2)):
        assert np.isnan(first[beam]) or abs(first[beam] - expected) < 0.06, (beam, first[beam])
    assert np.mean(np.isnan(first)) < 0.05  # 1 % of the beams lost, on average
    with open(imu, newline="") as handle:
        rows = [r for r in csv.reader(line for line in handle if not line.startswith("#"))][1:]
    accel_z = np.array([float(r[7]) for r in rows[:100]])  # the first 0.5 s, driving on the level floor
    assert abs(accel_z.mean() - 9.81) < 0.2 and accel_z.std() > 1e-3  # gravity, the preset's bias and noise


def test_the_sensors_count_in_the_run_budget_and_a_run_without_sensor_outputs_reads_none(tmp_path):
    """A 2000 Hz IMU and a 100 Hz lidar of 10,000 beams over a 3 m line (about 10 s): 21,000 IMU
    samples and 1e7 ranges, some 330 MB by the measured costs per sample (IMU_SAMPLE_BYTES,
    RANGE_BYTES): refused under 20 MB before the run; the same robot with only the tick log
    reads no sensors, and its estimate is the robot's alone."""
    import dataclasses

    from omnikin import load_robot
    from omnikin.api import simulate
    from omnikin.errors import InputError
    from omnikin.kinematics.sensors import Imu, Lidar, Mount
    from omnikin.sensors.readings import IMU_SAMPLE_BYTES, RANGE_BYTES

    base = load_robot("tomasi-omni3")
    heavy = dataclasses.replace(
        base, name="heavy", sensors=(Imu("i", rate=2000.0), Lidar("l", Mount(z=0.1), rate=100.0, beams=10000))
    )
    seen = []
    with pytest.raises(InputError, match=r"more than max_memory .*sensors' rates or beams"):
        simulate(heavy, "line 3", max_memory=20e6, on_cost=seen.append)
    duration = seen[0].duration
    sensed = math.floor(duration * 2000) * IMU_SAMPLE_BYTES + (math.floor(duration * 100) + 1) * 10000 * RANGE_BYTES
    bare = simulate(base, "line 3", on_cost=(plain := []).append)
    assert seen[0].memory == pytest.approx(plain[0].memory + sensed, rel=1e-9)
    quiet = simulate(heavy, "line 3", sensors=False, on_cost=(few := []).append)
    assert quiet.run.sensing is None and few[0].memory == pytest.approx(plain[0].memory, rel=1e-9)
    assert bare.run.sensing is None
