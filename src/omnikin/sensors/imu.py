"""An IMU's readings: the true rates and specific forces at its mount, and the errors of IEEE
Std 952's model on each axis (``docs/sensors.md``, "The errors of an IMU").

Readings are **increments over the sample interval** ``dt = 1 / rate``, as an IMU's integrating
front end gives them: the gyro reads the mean angular rate ``(theta(t_j) - theta(t_j - dt)) / dt``,
the accelerometer the mean specific force in its own axes (its delta-velocity over the interval,
divided by it), plus gravity's ``+g`` on z (an IMU at rest reads ``(0, 0, +9.81)``, as MuJoCo's
accelerometer does). On a circle of radius R at speed v the accelerometer at the centre reads the
centripetal ``v^2 / R`` towards the centre, exactly.

Errors, per triad (:class:`~omnikin.kinematics.sensors.ImuAxes`), drawn from the run's stream in
this order: turn-on bias ``b0 ~ N(0, bias^2)`` (3), scale factors ``s ~ N(0, scale^2)`` (3),
misalignments ``m ~ N(0, misalignment^2)`` (6, the off-diagonal terms); then per sample the bias
walk ``b_j = b_{j-1} + bias_walk sqrt(dt) z`` and white noise ``noise_density sqrt(rate) z``:

    reading = (I + diag(s) + M) truth + b0 + b_j + white.

The Allan deviation of a static record is then ``noise_density / sqrt(tau)`` at short
averaging times and ``bias_walk sqrt(tau / 3)`` at long ones (IEEE Std 952, Annex C).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kinematics.se2 import between, log
from ..kinematics.sensors import Imu, ImuAxes

GRAVITY = 9.81
"""Standard gravity [m/s^2], as the physics engine's."""


@dataclass(frozen=True)
class TriadErrors:
    """The errors of one triad drawn for a run: ``bias`` ``(3,)`` and ``matrix`` ``(3, 3)`` =
    ``I + diag(s) + M`` (module docstring)."""

    bias: np.ndarray
    matrix: np.ndarray


def draw_triad(axes: ImuAxes, rng: np.random.Generator) -> TriadErrors:
    """The run's draw of ``axes``' constant errors (module docstring for the order)."""
    bias = rng.standard_normal(3) * axes.bias
    scale = rng.standard_normal(3) * axes.scale
    off = rng.standard_normal(6) * axes.misalignment
    matrix = np.eye(3) + np.diag(scale)
    matrix[[0, 0, 1, 1, 2, 2], [1, 2, 0, 2, 0, 1]] += off
    return TriadErrors(bias, matrix)


class TriadStream:
    """The errors of one triad ``axes`` sampled at ``rate`` [Hz], added to its readings chunk by
    chunk (a live sensor's) or all at once (a run's): the constant errors drawn from ``rng`` at
    the first chunk, the bias walk carried from one chunk to the next (module docstring); one
    chunk of a whole record draws what :func:`with_errors` draws. ``rng`` None: exact."""

    def __init__(self, axes: ImuAxes, rate: float, rng: np.random.Generator | None):
        self.axes, self.rate = axes, float(rate)
        self._rng = None if axes.is_zero else rng
        self._drawn: TriadErrors | None = None
        self._walk = np.zeros(3)

    def apply(self, truth: np.ndarray) -> np.ndarray:
        """``truth`` ``(n, 3)``, the next ``n`` samples, as the triad reads them."""
        truth = np.asarray(truth, dtype=float)
        rng = self._rng
        if rng is None:
            return truth.copy()
        if self._drawn is None:
            self._drawn = draw_triad(self.axes, rng)
        n = len(truth)
        dt = 1.0 / self.rate
        walk = self._walk + np.cumsum(rng.standard_normal((n, 3)) * (self.axes.bias_walk * math.sqrt(dt)), axis=0)
        if n:
            self._walk = walk[-1].copy()
        white = rng.standard_normal((n, 3)) * (self.axes.noise_density * math.sqrt(self.rate))
        return truth @ self._drawn.matrix.T + self._drawn.bias + walk + white


def with_errors(truth: np.ndarray, axes: ImuAxes, rate: float, rng: np.random.Generator | None) -> np.ndarray:
    """``truth`` ``(n, 3)`` as one triad reads it at ``rate`` [Hz] (module docstring); ``rng``
    None: exact."""
    return TriadStream(axes, rate, rng).apply(truth)


class ImuStream:
    """The errors of ``imu`` added chunk by chunk: its gyro's, then its accelerometer's
    (:class:`TriadStream`); one chunk of a whole record draws what :func:`read` draws."""

    def __init__(self, imu: Imu, rng: np.random.Generator | None):
        self.imu = imu
        self._gyro = TriadStream(imu.gyro, imu.rate, rng)
        self._accel = TriadStream(imu.accel, imu.rate, rng)

    def apply(self, rates: np.ndarray, forces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The gyro ``(n, 3)`` [rad/s] and accelerometer ``(n, 3)`` [m/s^2] readings of the next
        ``n`` true mean ``rates`` and specific ``forces`` ``(n, 3)``."""
        return self._gyro.apply(rates), self._accel.apply(forces)


def read(
    imu: Imu, rates: np.ndarray, forces: np.ndarray, rng: np.random.Generator | None
) -> tuple[np.ndarray, np.ndarray]:
    """The gyro ``(n, 3)`` [rad/s] and accelerometer ``(n, 3)`` [m/s^2] readings of ``imu`` given
    the true mean ``rates`` and specific ``forces`` ``(n, 3)`` in its frame; the gyro's errors
    drawn first, then the accelerometer's (``rng`` None: exact)."""
    return ImuStream(imu, rng).apply(rates, forces)


def sample_times(t: np.ndarray, rate: float) -> np.ndarray:
    """The IMU's sample times over the run's ``t`` [s]: ``t[0] + j / rate``, j = 1, 2, ... up
    to ``t[-1]`` (each reading covers the interval before its time)."""
    count = int(math.floor((float(t[-1]) - float(t[0])) * rate + 1e-9))
    return float(t[0]) + np.arange(1, count + 1) / rate


def kinematic_truth(t, poses, imu: Imu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The true readings of ``imu`` on a body that moves through ``poses`` ``(N + 1, 3)`` at
    times ``t`` ``(N + 1,)`` [s] with a constant twist between samples (the kinematic engine's
    motion, exact SE(2) arcs), from rest before ``t[0]``: the sample times ``(n,)``
    (:func:`sample_times`), mean rates ``(n, 3)`` [rad/s] and mean specific forces ``(n, 3)``
    [m/s^2] in the sensor frame (module docstring).

    Within a step the mount point's velocity ``v_p = v + omega x p`` is constant in body axes, so
    its specific force there is ``omega x v_p``; where the twist changes, ``v_p`` jumps, an impulse
    of that jump. A reading is the integral of both over its interval, divided by it."""
    t = np.asarray(t, dtype=float)
    poses = np.asarray(poses, dtype=float)
    steps = log(between(poses[:-1], poses[1:]))  # (N, 3) body increments
    dt = np.diff(t)
    twist = steps / dt[:, None]
    m = imu.mount
    vp = np.column_stack([twist[:, 0] - twist[:, 2] * m.y, twist[:, 1] + twist[:, 2] * m.x])  # (N, 2) body axes
    force = np.column_stack([-twist[:, 2] * vp[:, 1], twist[:, 2] * vp[:, 0]])  # omega x v_p, (N, 2)
    jumps = np.diff(np.vstack([np.zeros(2), vp]), axis=0)  # at t[0], ..., t[N - 1]
    # G(t): the integral of the specific force from t[0], jumps at the knots t[k] <= t (t[0]'s
    # counted just after t[0]); its value at each knot t[k], k = 0..N
    flow = np.vstack([np.zeros(2), np.cumsum(force * dt[:, None], axis=0)])
    kicks = np.vstack([np.zeros(2), np.cumsum(jumps, axis=0)])
    heading = np.unwrap(poses[:, 2])
    times = sample_times(t, imu.rate)
    edges = np.concatenate([[t[0]], times])

    def integral(at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """G and the heading at times ``at``."""
        k = np.clip(np.searchsorted(t, at, side="right") - 1, 0, len(dt) - 1)
        into = at - t[k]
        g = flow[k] + force[k] * into[:, None] + kicks[k + 1]
        g[at <= t[0]] = 0.0
        return g, heading[k] + steps[k, 2] * into / dt[k]

    g, theta = integral(edges)
    interval = np.diff(edges)
    rates = np.zeros((len(times), 3))
    rates[:, 2] = np.diff(theta) / interval
    mean = np.diff(g, axis=0) / interval[:, None]  # body axes
    c, s = math.cos(m.yaw), math.sin(m.yaw)
    forces = np.column_stack(
        [c * mean[:, 0] + s * mean[:, 1], -s * mean[:, 0] + c * mean[:, 1], np.full(len(times), GRAVITY)]
    )
    return times, rates, forces
