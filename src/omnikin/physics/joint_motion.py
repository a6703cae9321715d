"""The joints of the robot's URDF that no sensor measures, moved as the body motion implies.

``joint_states`` carries every movable joint of :func:`omnikin.physics.urdf.urdf` so that a
viewer (rviz2) turns every wheel and roller. The encoded wheels' angles and the steering angles
are measured (the back-end's reading); the rest follows from the odometry's body increment
``xi = (dx, dy, dtheta)`` over each control interval (its twist times the interval, body axes
[m, m, rad]; the kinematic rows of :mod:`omnikin.kinematics.wheels`):

* a rolling wheel without encoder (an Ackermann car's front wheels, a passive wheel) turns by
  its rolling row: ``dphi = [cos(a) dx + sin(a) dy + (x sin(a) - y cos(a)) dtheta] / (r cos
  gamma)``, ``a`` its drive direction at its measured steering angle;
* a castor (joints ``NAME_steer``, ``NAME``) swivels as its trailing contact does not slide
  sideways, ``d beta' = n . v_p - d omega`` (``d`` the trail, ``n = (-sin a, cos a)``, ``v_p``
  the velocity of the floor point under the swivel axis; :meth:`~omnikin.kinematics.wheels.Wheel.swivel_row`),
  integrated with one Euler step per interval while the axis moves less than ``d`` in it (the
  step is then stable and does not overshoot: the swivel's rate changes by at most ``|v_p| / d``
  per radian), else set to the trailing steady angle ``atan2(v_p) - asin(d omega / |v_p|)`` (the
  swivel settles within the interval; the contact trails the axis); a castor without trail
  points along ``v_p`` (:meth:`~omnikin.kinematics.wheels.Wheel.align`, the way round nearer its angle).
  It rolls by its rolling row at that swivel angle;
* each roller ``NAME_roller_ROW_K`` of a Swedish wheel spins about its own axis ``e`` (the
  URDF joint axis; at the bottom of the wheel ``e`` lies on the floor along ``a = delta +
  gamma``). The wheel's rim point at the contact moves with ``v_p - r omega_i u`` (``u`` the
  drive direction, ``omega_i`` the wheel speed of the rolling row); the rolling row makes its
  component along ``e`` zero, and the roller's spin ``w`` cancels the rest without slip: the
  roller's surface at the contact, ``b`` below its axis, moves at ``w e x (-b z) = w b n``
  relative to the rim, ``n = z x e = (-sin a, cos a)``, so

      w = -s / b,  s = n . v_p + r omega_i sin(gamma)

  with ``s`` the roller surface speed of :meth:`~omnikin.kinematics.wheels.Wheel.roller_row` [m/s] and
  ``b`` the roller's radius at its middle, where it touches the floor
  (:class:`omnikin.physics.description.RollerSet` ``radius``). The angle turned over an
  interval is ``-(roller_row . xi) / b`` [rad]. Every roller of a wheel is given that angle (a
  roller off the floor spins freely in reality; the picture shows the one in contact on all).

Angles are counted from zero at the start [rad], unwrapped, as the encoders' are.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..kinematics.robot import Robot
from ..kinematics.se2 import wrap_angle
from .description import PhysicalRobot, describe


class JointMotion:
    """Positions [rad] and speeds [rad/s] of the URDF joints of ``robot`` that ``joint_states``
    does not read from the back-end (module docstring), in the order of :attr:`names`.

    ``encoded`` names the measured wheels (the odometry's); ``description`` is the physical
    description the URDF was written from (default :func:`describe` of ``robot``)."""

    def __init__(self, robot: Robot, encoded: Sequence[str], description: PhysicalRobot | None = None):
        body = describe(robot) if description is None else description
        measured = set(encoded)
        steer_index = {name: i for i, name in enumerate(robot.steer_names)}
        self._spun = [w for w in robot.rolling if w.name not in measured]
        self._spun_steer = [steer_index.get(w.name) for w in self._spun]
        self._castors = [w for w in robot.wheels if w.is_castor]
        self._swivel = np.zeros(len(self._castors))
        swedish = [robot.wheel(b.name) for b in body.wheels if b.rollers is not None]
        rollers = [b.rollers for b in body.wheels if b.rollers is not None]
        radius = np.array([r.radius for r in rollers if r is not None], dtype=float)
        # roller angle per unit body increment, one row per Swedish wheel: -roller_row / b
        self._roller_rows = -np.array([w.roller_row() for w in swedish], dtype=float).reshape(-1, 3) / radius[:, None]
        self._per_wheel = np.array([len(r.rollers) for r in rollers if r is not None], dtype=int)
        roller_names = [
            f"{b.name}_roller_{r.row}_{r.index}"
            for b in body.wheels
            if b.rollers is not None
            for r in b.rollers.rollers
        ]
        self.names = (
            [w.name for w in self._spun]
            + [f"{c.name}_steer" for c in self._castors]
            + [c.name for c in self._castors]
            + roller_names
        )
        self._spin = np.zeros(len(self._spun))
        self._castor_spin = np.zeros(len(self._castors))
        self._roller_angle = np.zeros(len(swedish))
        self._roller_rate = np.zeros(len(swedish))
        self._t: float | None = None

    @property
    def castor_names(self) -> list[str]:
        """The castors (file order) whose swivel and spin :attr:`castor_swivels` and
        :attr:`castor_angles` give."""
        return [c.name for c in self._castors]

    @property
    def castor_swivels(self) -> np.ndarray:
        """Swivel angles [rad] of the castors, relative to their mounting drive direction."""
        return self._swivel.copy()

    @property
    def castor_angles(self) -> np.ndarray:
        """Wheel angles [rad] the castors have rolled since the start."""
        return self._castor_spin.copy()

    @property
    def roller_angles(self) -> np.ndarray:
        """Roller angle [rad] of each Swedish wheel (description order; every roller of a wheel
        has it, module docstring)."""
        return self._roller_angle.copy()

    @property
    def roller_rates(self) -> np.ndarray:
        """Roller speed [rad/s] of each Swedish wheel (description order) over the last interval."""
        return self._roller_rate.copy()

    def update(self, t: float, twist, steer=None) -> tuple[np.ndarray, np.ndarray]:
        """Advance to time ``t`` [s] with the odometry's ``twist`` ``(vx, vy, omega)`` over the
        interval since the previous call [m/s, m/s, rad/s], ``steer`` the measured steering
        angles (``robot.steer_names`` order) [rad]; returns ``(positions, velocities)``."""
        tw = np.asarray(twist, dtype=float)
        dt = 0.0 if self._t is None or not t > self._t else t - self._t
        if self._t is None or t > self._t:
            self._t = t
        steer_now = np.zeros(0) if steer is None else np.asarray(steer, dtype=float)
        spin_rate = np.array(
            [
                float(w.rolling_row(0.0 if i is None else steer_now[i]) @ tw)
                for w, i in zip(self._spun, self._spun_steer, strict=True)
            ]
        )
        swivel_rate = np.zeros(len(self._castors))
        castor_rate = np.zeros(len(self._castors))
        for k, c in enumerate(self._castors):
            after = before = self._swivel[k]
            vx, vy = c.hub_velocity(tw)
            speed = math.hypot(vx, vy)
            if c.offset == 0.0:  # no trail: along the motion, either way round (the nearer)
                after = float(c.align(tw, before, strict=False)[0])
            elif speed * dt <= c.offset:  # one Euler step; stable, no overshoot, while |v_p| dt <= d
                after = before + dt * float(c.swivel_row(before) @ tw) / c.offset
            elif abs(c.offset * tw[2]) <= speed:  # settles within the interval: the trailing steady angle
                after = math.atan2(vy, vx) - math.asin(c.offset * tw[2] / speed) - c.drive
            after = before + float(wrap_angle(after - before))  # unwrapped: the nearest turn
            self._swivel[k] = after
            swivel_rate[k] = (after - before) / dt if dt > 0.0 else 0.0
            castor_rate[k] = float(c.rolling_row(after) @ tw)
        roller_rate = self._roller_rows @ tw
        self._roller_rate = roller_rate
        self._spin += spin_rate * dt
        self._castor_spin += castor_rate * dt
        self._roller_angle += roller_rate * dt
        positions = np.concatenate(
            [self._spin, self._swivel, self._castor_spin, np.repeat(self._roller_angle, self._per_wheel)]
        )
        velocities = np.concatenate([spin_rate, swivel_rate, castor_rate, np.repeat(roller_rate, self._per_wheel)])
        return positions, velocities
