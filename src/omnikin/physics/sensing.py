"""What a robot's IMUs and lidars read in the physics engine (``docs/sensors.md``, "In the
physics engine").

:class:`PhysicsSensors` watches the chassis of a :class:`~omnikin.physics.simulator.PhysicsSim`
(its free joint: the body origin's position and quaternion ``q`` in the world frame, its
velocity ``v`` in world axes and angular velocity ``w`` in body axes, MuJoCo's ``qpos`` and
``qvel``, current after each step) and keeps a snapshot of that state at the time steps around
each sample time ``t*`` of a sensor: ``t* = j / rate`` for ``j = 1, 2, ...`` (an IMU, each
reading covering the interval before it) or ``j = 0, 1, ...`` (a lidar, a scan at the start).
A sample time between steps ``k`` and ``k + 1`` (a fraction ``a`` of the step past ``k``) gets
the state in between: ``q = q_k exp(a log(q_k^-1 q_{k+1}))``, ``v`` and ``w`` linear in time, so
sensors of any rate run on any time step.

- An IMU's frame is the body's turned by its mount's yaw, ``q_s = q R_z(yaw)``; its mount point
  moves at ``v_p = v + R(q) (w x p)``. Reading ``j`` over ``dt = 1 / rate`` is the mean angular
  rate ``log(q_s,j-1^-1 q_s,j) / dt`` (exact for rotation about a fixed axis, as on a floor) and
  the mean specific force ``R(q_mid)^T ((v_p,j - v_p,j-1) / dt - g)``, with ``g`` MuJoCo's
  gravity and ``q_mid`` halfway between the two orientations; on a circle the rotation of the
  force within the interval makes that ``sinc(omega dt / 2)`` of the true mean (1e-6 short at
  1 rad/s and 200 Hz). The first reading starts from the state after settling, at rest.
- A lidar's beams leave its mount (at least :data:`BEAM_LOWEST` above the floor) at the state of
  the scan time, turned with the chassis (a tilted robot tilts its scan plane), and are cast by
  MuJoCo's ``mj_multiRay`` against the world's walls and obstacles as they stand at the step
  after the scan time (geom group :data:`~omnikin.physics.mjcf.WORLD_GROUP`, which neither the
  robot nor the floor is in); a miss or a hit beyond ``range_max`` reads ``inf``.

The errors are added afterwards, from the run's sensor stream, by the same function as the
kinematic engine's (:func:`omnikin.sensors.readings.measured_readings`).
"""

from __future__ import annotations

import math

import numpy as np

from ..kinematics.robot import Robot
from ..kinematics.sensors import Imu, Lidar
from ..sensors.readings import ImuTruth, ScanTruth
from .mjcf import WORLD_GROUP

BEAM_LOWEST = 5e-4
"""The lowest height [m] a lidar's beams leave from in the physics engine, half the lowest body a
world may hold (1 mm): a lidar mounted lower (the default mount is on the floor) casts from
here, since beams along the floor's surface meet the walls' bottom edges only by chance; the
kinematic engine sees every body taller than the mount, as from here."""
FLUSH = 256
"""An IMU's completed samples are interpolated in batches of this many (and when read)."""
FRACTION_SNAP = 1e-9
"""A sample time within this fraction of a step of a time step is taken at that step."""


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products of quaternions ``(..., 4)`` (w, x, y, z), MuJoCo's order."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def quat_conj(q: np.ndarray) -> np.ndarray:
    """Conjugates (inverses of unit quaternions) ``(..., 4)``."""
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` [rad] of unit quaternions ``(..., 4)``, the shorter way round."""
    q = np.where(q[..., :1] < 0.0, -q, q)
    xyz = q[..., 1:]
    norm = np.linalg.norm(xyz, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(norm, q[..., :1])
    scale = np.divide(angle, norm, out=np.full_like(norm, 2.0), where=norm > 1e-300)
    return xyz * scale


def quat_exp(v: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` of rotation vectors ``(..., 3)`` [rad]."""
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    half = angle / 2.0
    scale = np.where(angle > 1e-12, np.sin(half) / np.where(angle > 1e-12, angle, 1.0), 0.5)
    return np.concatenate([np.cos(half), v * scale], axis=-1)


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``R(q) v`` for unit quaternions ``(..., 4)`` and vectors ``(..., 3)``."""
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def interpolate(a: np.ndarray, b: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """Chassis states ``(n, 13)`` a ``fraction`` ``(n,)`` of the way from ``a`` to ``b`` (module
    docstring): the quaternion along the rotation from one to the other, the rest linearly."""
    f = fraction[:, None]
    out = a + f * (b - a)
    turn = quat_log(quat_mul(quat_conj(a[:, :4]), b[:, :4]))
    out[:, :4] = quat_mul(a[:, :4], quat_exp(f * turn))
    return out


class PhysicsSensors:
    """The IMUs and lidars of ``robot`` in a MuJoCo model (module docstring). ``mujoco`` the
    module, ``model`` and ``data`` the simulation, ``free``/``free_dof`` the addresses of the
    chassis' free joint in ``qpos``/``qvel``, ``step`` [s] the time step. Made at step 0 (the
    state after settling, at rest), it is told of every later step whose number :attr:`due`
    names (:meth:`take`); :meth:`truths` gives what the sensors read so far without errors.
    ``keep`` [s]: hold at most that much of each sensor's latest samples (a live robot's that
    nobody drains, :meth:`drain`, stays in bounded memory; the older ones are counted in
    :attr:`dropped`); None: all of them (a run's)."""

    def __init__(
        self, mujoco, model, data, robot: Robot, free: int, free_dof: int, step: float, keep: float | None = None
    ):
        self._mj, self._model, self._data = mujoco, model, data
        self._free, self._free_dof = int(free), int(free_dof)
        self._step = float(step)
        self._sensors = [s for s in robot.sensors if isinstance(s, (Imu, Lidar))]
        self._next = [1 if isinstance(s, Imu) else 0 for s in self._sensors]  # next sample number
        self._states: dict[int, np.ndarray] = {}  # step -> (13,) q (4), v (3), w (3), p (3)
        self._samples: list[list[np.ndarray]] = [[] for _ in self._sensors]  # IMU states, lidar ranges
        # an IMU's samples complete but not yet interpolated: (state before, state after, fraction)
        self._pending: list[list[tuple[np.ndarray, np.ndarray, float]]] = [[] for _ in self._sensors]
        self._upcoming = [self._next_sample(i) for i in range(len(self._sensors))]
        self._group = np.zeros(6, dtype=np.uint8)
        self._group[WORLD_GROUP] = 1
        self._rays = {i: _Rays(s) for i, s in enumerate(self._sensors) if isinstance(s, Lidar)}  # buffers of each lidar
        self.due = 0
        """The number of the next step whose state a sensor needs (a huge number when none)."""
        self._base = [np.zeros(13) for _ in self._sensors]  # an IMU's state before its first kept sample
        self._drained = [0] * len(self._sensors)  # samples handed out by drain() or dropped
        self._keep = [None if keep is None else max(1, math.ceil(keep * s.rate)) for s in self._sensors]
        self.dropped = 0
        """Samples let go undrained beyond ``keep``."""
        self.take(0)

    @property
    def active(self) -> bool:
        """True when the robot has an IMU or a lidar."""
        return bool(self._sensors)

    def _sample_steps(self, i: int) -> tuple[int, float, int]:
        """Sensor ``i``'s next sample: the step at or before its time, the fraction of the step
        past it, and the last step it needs."""
        return self._upcoming[i]

    def _next_sample(self, i: int) -> tuple[int, float, int]:
        """:meth:`_sample_steps` computed from the sample's number."""
        sensor = self._sensors[i]
        steps = self._next[i] / (sensor.rate * self._step)
        k = math.floor(steps + FRACTION_SNAP)
        fraction = max(0.0, steps - k)
        if fraction <= FRACTION_SNAP:
            return k, 0.0, k
        return k, fraction, k + 1

    def _plan(self) -> None:
        """Set :attr:`due`: the first step whose state a sample still needs."""
        states = self._states
        self.due = min((last if k in states else k for k, _, last in self._upcoming), default=2**62)

    def take(self, steps: int) -> None:
        """Keep the chassis state after step ``steps`` and complete every sample it finishes."""
        d = self._data
        q = d.qpos[self._free : self._free + 7]
        self._states[steps] = np.concatenate((q[3:7], d.qvel[self._free_dof : self._free_dof + 6], q[:3]))
        if steps == 0:
            self._base = [self._states[0]] * len(self._sensors)
        for i, sensor in enumerate(self._sensors):
            while True:
                k, fraction, last = self._sample_steps(i)
                if last > steps:
                    break
                if isinstance(sensor, Imu):
                    self._pending[i].append((self._states[k], self._states[last], fraction))
                else:
                    self._samples[i].append(self._cast(i, self._state_at(k, fraction)))
                self._next[i] += 1
                self._upcoming[i] = self._next_sample(i)
            if len(self._pending[i]) >= FLUSH:
                self._flush(i)
            self._let_go(i)
        if len(self._states) > 3:  # the states no sample needs any more
            oldest = min(min(u[0] for u in self._upcoming), steps)
            for k in [k for k in self._states if k < oldest]:
                del self._states[k]
        self._plan()

    def _flush(self, i: int) -> None:
        """Interpolate IMU ``i``'s pending samples, all at once (module docstring)."""
        pending = self._pending[i]
        if not pending:
            return
        a = np.array([p[0] for p in pending])
        b = np.array([p[1] for p in pending])
        fraction = np.array([p[2] for p in pending])
        self._samples[i].extend(interpolate(a, b, fraction))
        pending.clear()

    def _state_at(self, k: int, fraction: float) -> np.ndarray:
        """The chassis state (13,) a ``fraction`` of a step after step ``k`` (module docstring)."""
        a = self._states[k]
        if fraction == 0.0:
            return a
        return interpolate(a[None], self._states[k + 1][None], np.array([fraction]))[0]

    def _cast(self, i: int, state: np.ndarray) -> np.ndarray:
        """The true ranges ``(beams,)`` [m] of lidar ``i`` at the chassis ``state``."""
        mj, m, d = self._mj, self._model, self._data
        lidar = self._sensors[i]
        assert isinstance(lidar, Lidar)
        rays = self._rays[i]
        mount = lidar.mount
        q = state[:4]
        height = max(mount.z, BEAM_LOWEST)
        origin = state[10:13] + quat_rotate(q, np.array([mount.x, mount.y, height]))
        rays.vec[:] = quat_rotate(q, rays.directions).ravel()
        mj.mj_kinematics(m, d)  # the world's movable bodies where this step left them
        mj.mj_multiRay(
            m, d, origin, rays.vec, self._group, 1, -1, rays.geomid, rays.dist, None, lidar.beams, mj.mjMAXVAL
        )
        out = rays.dist.copy()
        out[(rays.geomid < 0) | (out > lidar.range_max)] = math.inf
        return out

    def truths(self) -> dict[str, ImuTruth | ScanTruth]:
        """What each IMU and lidar read without errors since it was made or last drained
        (:meth:`drain`), by sensor name."""
        out: dict[str, ImuTruth | ScanTruth] = {}
        for i, sensor in enumerate(self._sensors):
            self._flush(i)
            self._let_go(i)
            samples, before = self._samples[i], self._drained[i]
            if isinstance(sensor, Lidar):
                ranges = np.array(samples).reshape(len(samples), sensor.beams)
                out[sensor.name] = ScanTruth(sensor, (before + np.arange(len(samples))) / sensor.rate, ranges)
            else:
                out[sensor.name] = self._imu_truth(i, sensor)
        return out

    def _let_go(self, i: int) -> None:
        """Drop sensor ``i``'s oldest samples beyond its ``keep``."""
        limit, samples = self._keep[i], self._samples[i]
        if limit is None or len(samples) <= limit:
            return
        extra = len(samples) - limit
        if isinstance(self._sensors[i], Imu):
            self._base[i] = samples[extra - 1]
        del samples[:extra]
        self._drained[i] += extra
        self.dropped += extra

    def drain(self) -> dict[str, ImuTruth | ScanTruth]:
        """:meth:`truths`, then forget them: the next call gives the samples taken after this
        one (a live robot's sensors, read cycle by cycle in bounded memory)."""
        out = self.truths()
        for i, samples in enumerate(self._samples):
            if samples and isinstance(self._sensors[i], Imu):
                self._base[i] = samples[-1]
            self._drained[i] += len(samples)
            samples.clear()
        return out

    def _imu_truth(self, i: int, imu: Imu) -> ImuTruth:
        states = np.array([self._base[i], *self._samples[i]])
        n = len(states) - 1
        dt = 1.0 / imu.rate
        m = imu.mount
        q = states[:, :4]
        p = np.array([m.x, m.y, m.z])
        v_p = states[:, 4:7] + quat_rotate(q, np.cross(states[:, 7:10], p))
        yaw = np.array([math.cos(m.yaw / 2.0), 0.0, 0.0, math.sin(m.yaw / 2.0)])
        q_s = quat_mul(q, yaw)
        turn = quat_log(quat_mul(quat_conj(q_s[:-1]), q_s[1:]))  # (n, 3) in the frame at the start
        q_mid = quat_mul(q_s[:-1], quat_exp(turn / 2.0))
        gravity = np.asarray(self._model.opt.gravity, dtype=float)
        world = np.diff(v_p, axis=0) / dt - gravity
        forces = quat_rotate(quat_conj(q_mid), world)
        times = (self._drained[i] + np.arange(1, n + 1)) / imu.rate
        return ImuTruth(imu, times, turn.reshape(n, 3) / dt, forces.reshape(n, 3))


class _Rays:
    """One lidar's ray buffers for ``mj_multiRay``: unit directions in the body frame
    ``(beams, 3)`` and the flat directions, distances and geom ids it fills."""

    def __init__(self, lidar: Lidar):
        angles = lidar.angles() + lidar.mount.yaw
        self.directions = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(lidar.beams)])
        self.vec = np.empty(3 * lidar.beams)
        self.dist = np.empty(lidar.beams)
        self.geomid = np.empty(lidar.beams, dtype=np.int32)
