"""An IMU's readings: the true motion at its mount, the modelled errors drawn in their stated
order, and the Allan deviation of a long static record against its noise density and bias walk."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.kinematics.se2 import compose, exp
from omnikin.kinematics.sensors import Imu, ImuAxes, Mount
from omnikin.sensors.imu import GRAVITY, kinematic_truth, read, with_errors


def _circle(radius: float, speed: float, seconds: float, rate: float = 100.0):
    """Poses on a counter-clockwise circle, heading along it, at ``rate`` [Hz]."""
    n = int(seconds * rate)
    omega = speed / radius
    xi = np.array([speed, 0.0, omega]) / rate
    poses = [np.zeros(3)]
    for _ in range(n):
        poses.append(compose(poses[-1], exp(xi)))
    return np.arange(n + 1) / rate, np.array(poses)


def test_on_a_circle_the_gyro_reads_the_turn_rate_and_the_accelerometer_the_centripetal_force():
    radius, speed = 1.0, 0.5
    t, poses = _circle(radius, speed, 10.0)
    imu = Imu("imu", Mount(0.0, 0.0, 0.05), rate=50.0)
    times, rates, forces = kinematic_truth(t, poses, imu)
    omega = speed / radius
    dt = 1.0 / imu.rate
    assert len(times) == 500 and times[0] == pytest.approx(dt)
    np.testing.assert_allclose(rates[:, 2], omega, rtol=1e-12)
    # in body axes the specific force of uniform circular motion is v omega towards the centre (+y)
    np.testing.assert_allclose(forces[1:, 1], speed * omega, rtol=1e-9)
    np.testing.assert_allclose(forces[1:, 0], 0.0, atol=1e-9)
    # the first reading holds the start from rest to full speed: v / dt forward
    assert forces[0, 0] == pytest.approx(speed / dt)
    np.testing.assert_allclose(forces[:, 2], GRAVITY)


def test_a_mount_ahead_of_the_centre_adds_its_own_centripetal_term():
    t, poses = _circle(1.0, 0.5, 4.0)
    imu = Imu("imu", Mount(0.1, 0.0, 0.0, math.pi / 2), rate=100.0)  # turned a quarter left
    _, _, forces = kinematic_truth(t, poses, imu)
    omega = 0.5
    # in body axes: (-omega^2 0.1, v omega) (a_p = a_o - omega^2 p); the sensor's x is body +y
    body_x, body_y = -(omega**2) * 0.1, 0.5 * omega
    np.testing.assert_allclose(forces[1:, 0], body_y, rtol=1e-9)
    np.testing.assert_allclose(forces[1:, 1], -body_x, rtol=1e-9)


def test_at_rest_the_imu_reads_gravity_up_and_no_rate():
    t = np.arange(11) / 10.0
    poses = np.tile([0.5, -0.5, 1.0], (11, 1))
    _, rates, forces = kinematic_truth(t, poses, Imu("imu", rate=20.0))
    np.testing.assert_array_equal(rates, 0.0)
    np.testing.assert_allclose(forces, np.tile([0.0, 0.0, GRAVITY], (len(forces), 1)), atol=1e-12)


def test_the_gyro_is_the_true_rate_through_its_drawn_scale_plus_its_drawn_bias():
    gyro = ImuAxes(bias=0.01, scale=0.02)
    truth = np.column_stack([np.zeros(200), np.zeros(200), np.linspace(-1.0, 1.0, 200)])
    got = with_errors(truth, gyro, 100.0, np.random.default_rng(5))
    draws = np.random.default_rng(5).standard_normal(12)  # bias (3), scale (3), misalignment (6)
    bias, scale = draws[:3] * 0.01, draws[3:6] * 0.02
    np.testing.assert_allclose(got[:, 2], truth[:, 2] * (1 + scale[2]) + bias[2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(got[:, :2], np.tile(bias[:2], (200, 1)), rtol=0, atol=1e-15)


def _allan(samples: np.ndarray, rate: float, cluster: int) -> float:
    """Allan deviation at tau = cluster / rate from non-overlapping cluster means (its definition,
    sigma^2 = <(y_{k+1} - y_k)^2> / 2), pooled over the columns."""
    n = len(samples) // cluster
    means = samples[: n * cluster].reshape(n, cluster, -1).mean(axis=1)
    return float(np.sqrt(0.5 * np.mean(np.diff(means, axis=0) ** 2)))


def test_a_long_static_record_has_the_allan_deviation_of_its_noise_density_and_bias_walk():
    density, walk, rate = 2e-3, 2e-5, 10.0
    imu = Imu("imu", rate=rate, gyro=ImuAxes(noise_density=density, bias_walk=walk))
    n = 400_000  # 11 hours at 10 Hz
    gyro, _ = read(imu, np.zeros((n, 3)), np.zeros((n, 3)), np.random.default_rng(7))
    for tau in (1.0, 10.0, 1000.0):
        expected = math.sqrt(density**2 / tau + walk**2 * tau / 3.0)  # IEEE Std 952, Annex C
        clusters = n // int(tau * rate)
        tolerance = 4.0 / math.sqrt(2 * 3 * (clusters - 1))  # the estimate's relative spread, 4 sigma
        assert _allan(gyro, rate, int(tau * rate)) == pytest.approx(expected, rel=max(tolerance, 0.02))


def test_no_stream_reads_the_truth_exactly():
    imu = Imu("imu", gyro=ImuAxes(noise_density=1e-3, bias=0.1), accel=ImuAxes(bias=0.5))
    rates, forces = np.ones((5, 3)), np.full((5, 3), 2.0)
    gyro, accel = read(imu, rates, forces, None)
    np.testing.assert_array_equal(gyro, rates)
    np.testing.assert_array_equal(accel, forces)
