"""A robot stepped in MuJoCo: :class:`PhysicsSim` (extra ``physics``).

The model is the MJCF of :mod:`omnikin.physics.mjcf`. The simulation

- **settles** the robot at the start: each wheel turned to its **roller phase** (a fraction
  of its roller period, the wheel angle after which its rollers repeat, :func:`roller_period`;
  0 by default: a roller of the first row straight below the axle; :func:`roller_offsets`), it
  is put down with its lowest roller (or tyre) on the floor, held with zero wheel commands until
  the contacts have taken its weight (the chassis stops moving vertically), then moved back to
  the start pose with zero velocity, so the run
  starts at rest without a bounce; the clock and the encoders start there at zero;
- takes **wheel commands** (:meth:`PhysicsSim.command`): speeds [rad/s] of the rolling wheels in
  file order (as :meth:`omnikin.kinematics.robot.Robot.ik` returns them; entries of passive wheels are
  ignored) and steering angles [rad] of the steerable wheels. A command is reached through a
  **ramp**: each step the wheels' set-points move together along the straight line towards
  it, each by at most its motor's acceleration limit times the step
  (:class:`~omnikin.physics.description.Motor`; why: a step command asks for an infinite
  acceleration, the servo saturates at the torque limit and the wheel spins on the floor; why
  together: set-points on that line stay consistent with one body motion, where wheels ramped
  one by one would disagree and fight), steering by at most its rate limit. Speeds beyond a motor's limit are held at
  the limit and steering angles beyond their wheel's limits at the limit, as the hardware does.
  Each step the engine closes the integral part of the PI controllers: the velocity servo of a
  wheel (MuJoCo's ``velocity`` actuator, the proportional part, integrated implicitly) gets the
  set-point plus ``z``, ``dz/dt = (set-point - speed) / integral_time``, ``|z|`` at most the
  speed error at which the motor gives its full torque; the steering servos likewise on angles;
- turns the driven wheels by their **motors** (:attr:`omnikin.kinematics.wheels.Wheel.motor`,
  docs/conventions.md, "Motors"): a stepper's joint follows the commanded speed; a dc motor's
  speed loop closes on its encoder, so its joint follows the command times
  ``rpt_true / rpt_controller`` (:attr:`PhysicsSim.loop_turn`): the counts of the encoder as
  built (``rpt_true`` [rad/tick]) follow the command over the scale its controller was told
  (``controller``, default the robot's design), as in the kinematic engine
  (:func:`omnikin.simulation.kinematic.wheel_motion`);
- reads **encoders** from the wheel joint angles, quantised to whole ticks of each encoder
  (``ticks_per_rev`` and ``gear_ratio``, sign of ``invert``) and wrapped like the hardware
  counter when the encoder has ``counter_bits``
  (:func:`omnikin.simulation.kinematic.counter_output`);
- gives the **ground truth**: pose ``(x, y, theta)`` of the chassis (its frame is the robot's
  body frame; ``theta`` counted continuously, not wrapped) and body twist ``(vx, vy, omega)``
  of ``docs/conventions.md``, from MuJoCo's ``mj_objectVelocity`` for the chassis *frame*
  (``mjOBJ_XBODY``; ``mjOBJ_BODY`` would give the velocity of its centre of mass), rotated
  from world axes into the body's heading.
"""

from __future__ import annotations

import contextlib
import math
import numbers

import numpy as np

from ..common.messages import shorten
from ..errors import DivergedError, InputError, PhysicsError
from ..kinematics.robot import Robot
from ..kinematics.se2 import wrap_angle
from ..kinematics.sensors import Imu, Lidar
from ..simulation.kinematic import counter_output
from ..world.collision import Contact
from ..world.model import World
from .description import PhysicalRobot, describe
from .mjcf import DEFAULT_STEP, STEP_RANGE, mjcf
from .sensing import PhysicsSensors

SETTLE_MIN = 0.05
"""Shortest settling time [s] at the start."""
SETTLE_MAX = 5.0
"""Longest settling time [s]: a robot still moving then is reported as unable to stand. A
four-wheel base whose wheels start at different roller phases stands on uneven contact heights
(the rollers' ripple) and rocks down into them: mecanum4 took up to 2.4 s in 200 draws of
phases (median 0.05 s)."""
SETTLE_SPEED = 1e-4
"""Vertical speed [m/s] and tilt rate [rad/s] of the chassis below which it has settled."""
UNWRAP_CHUNK = 10
"""Steps between two updates of the continuous heading: below pi per chunk up to 150 rad/s at 2 ms."""
START_MAX = 1e5
"""Largest ``|x|``, ``|y|`` [m] and ``|theta|`` [rad] of a start pose: there doubles still resolve
1.5e-11 m (rad), a millionth of the contacts' sinking; at 1e300 MuJoCo's contacts diverge."""
ADVANCE_MAX = 3600.0
"""Longest simulated time [s] one call of :meth:`PhysicsSim.advance` or :meth:`PhysicsSim.step`
runs (about a minute of computing for a preset at 2 ms): a longer run is several calls, and a
hostile ``advance(1e300)`` is refused instead of stepping for ever."""
TRACK_TIME = 0.1
"""Window [s] of the wheels' tracking error: the root mean square of the rim speed error
``r (set-point - speed)`` over an exponential window of this length (20 time constants of the
5 ms speed servo, which closes an error it has the torque for within a few) is what
:data:`TRACK_ERROR` bounds."""
TRACK_ERROR = 0.02
"""Bound [m/s] on a driven wheel's root mean square rim speed error over :data:`TRACK_TIME`:
beyond it the wheel does not follow its set-points (torque-limited, or oscillating); the presets'
wheels stay below a fifth of it (docs/physics.md, "Runs that do not drive as commanded")."""


TIPPED = 0.2
"""Tilt [rad] of the chassis beyond which the robot has tipped over (it stands level within
milliradians: the contacts sink 0.01-0.1 % of a wheel's radius)."""


def _loop_turn(robot: Robot, controller: Robot | None, names: list[str]) -> np.ndarray:
    """Per wheel of ``names``, the joint speed its motor turns per unit of commanded speed
    (module docstring, "motors"): ``rpt_true / rpt_controller`` for a wheel whose speed loop closes
    on its encoder (:attr:`omnikin.kinematics.wheels.Wheel.counts_close_loop`), ``controller`` the robot
    whose encoder scale its controller counts by (default ``robot.design``, else ``robot``); 1
    otherwise."""
    controller = controller if controller is not None else (robot.design or robot)
    out = np.ones(len(names))
    for i, name in enumerate(names):
        wheel = robot.wheel(name)
        told = controller.wheel(name).encoder if name in controller.wheel_names else None
        if wheel.counts_close_loop and told is not None and wheel.encoder is not None:
            out[i] = wheel.encoder.rad_per_tick / told.rad_per_tick
    return out


def _ignore_warning(message: str) -> None:
    """MuJoCo's warning handler while omnikin steps it: the warnings are counted in ``data.warning``
    (read by :meth:`PhysicsSim._check`); MuJoCo's default handler would print them on standard
    output and append them to ``MUJOCO_LOG.TXT`` in the current folder."""


@contextlib.contextmanager
def _quiet(mujoco):
    """MuJoCo's warnings routed to :func:`_ignore_warning` for the block, the caller's handler back
    after it (``mujoco.set_mju_user_warning`` is process-wide)."""
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(_ignore_warning)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)


def finite_vector(value, size: int) -> np.ndarray | None:
    """``value`` as ``size`` finite floats, or None when it is not that (a string, a nested list,
    a wrong length, NaN): the caller refuses it in its own words."""
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        return None
    return array if array.shape == (size,) and np.all(np.isfinite(array)) else None


def _mujoco():
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - the extra is installed wherever tests run
        raise InputError(f'the physics engine needs MuJoCo: pip install "omnikin[physics]" ({e})') from None
    return mujoco


def roller_period(wheel) -> float:
    """Wheel angle [rad] after which the rollers of ``wheel`` (a
    :class:`~omnikin.physics.description.WheelBody`) stand as they stood: the pitch
    ``2 pi / (n R)`` between two hand-overs when its ``R`` staggered rows of ``n`` rollers all lie
    in the wheel's mid-plane (the rows are alike), ``2 pi / n`` (``R`` pitches) when the rows sit
    side by side (``physical.width``: the rows differ by their place along the axle, so a phase
    within one pitch would reach only the configurations in which a given row carries the wheel
    first, and the mirror image of a run would be missing); 0 for a wheel without rollers."""
    rollers = wheel.rollers
    if rollers is None:
        return 0.0
    rows_alike = len(set(rollers.offsets)) == 1
    return 2.0 * math.pi / (rollers.per_row * (rollers.rows if rows_alike else 1))


def roller_offsets(description: PhysicalRobot, rolling: list[str], phase) -> np.ndarray:
    """Start angles [rad] of the joints of the ``rolling`` wheels (names, file order) for roller
    ``phase``: a number or one number per rolling wheel, each a fraction in ``[0, 1)`` of the
    wheel's :func:`roller_period` (0: a roller of the first row straight below the axle). The
    angle is ``phase * period``; wheels without rollers get 0. Bad input: :class:`InputError`
    naming the wheel."""
    values = np.asarray(phase, dtype=float) if _is_numeric(phase) else None
    if values is None or values.ndim > 1 or (values.ndim == 1 and len(values) != len(rolling)):
        raise InputError(
            f"roller_phase must be a number or one number per rolling wheel ({shorten(rolling)}), "
            f"each a fraction of the roller period in [0, 1), got {shorten(phase)}"
        )
    values = np.broadcast_to(values, (len(rolling),))
    wheels = {w.name: w for w in description.wheels}
    for name, value in zip(rolling, values, strict=True):
        if not 0.0 <= value < 1.0:
            raise InputError(
                f"roller_phase of wheel {name!r} must be a fraction of the roller period in [0, 1), "
                f"got {shorten(float(value))}"
            )
    return np.array([v * roller_period(wheels[n]) for n, v in zip(rolling, values, strict=True)])


def _is_numeric(value) -> bool:
    """A real number or a flat sequence of real numbers (no bools, strings or None)."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):
        return False
    return array.dtype.kind in "iuf"


def _yaw(xmat: np.ndarray) -> float:
    """Heading [rad] of a body's x axis projected on the floor, from its 3x3 rotation (row-major)."""
    return math.atan2(xmat[3], xmat[0])


def _quat_yaw(q: np.ndarray) -> float:
    """Heading [rad] of the x axis projected on the floor of the rotation of the unit quaternion
    ``q`` (w, x, y, z): ``atan2(R_10, R_00)``."""
    w, x, y, z = (float(v) for v in q)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _world_geom_bodies(mj, model, world: World | None) -> np.ndarray | None:
    """Per geom of ``model``, the index of the body of ``world`` it belongs to
    (:attr:`omnikin.world.model.World.bodies`), -1 for the rest; None without a world or with no
    walls and obstacles (nothing to touch). The model names them by place
    (:func:`omnikin.physics.mjcf._world_bodies`): ``world:wall:I:K``, ``world:obstacle:J``."""
    if world is None or not world.bodies:
        return None
    owner = np.full(model.ngeom, -1, dtype=np.int64)
    walls = len(world.walls)
    for g in range(model.ngeom):
        parts = (mj.mj_id2name(model, mj.mjtObj.mjOBJ_GEOM, g) or "").split(":")
        if parts[:2] == ["world", "wall"]:
            owner[g] = int(parts[2])
        elif parts[:2] == ["world", "obstacle"]:
            owner[g] = walls + int(parts[2])
    return owner


class PhysicsSim:
    """``robot`` as a MuJoCo model, settled at ``start`` ``(x, y, theta)`` [m, m, rad], stepped
    at ``step`` [s] (module docstring). ``description``: a physical description of ``robot``
    (default :func:`~omnikin.physics.description.describe`). ``roller_phase``: where in its
    roller period each wheel starts, a fraction in ``[0, 1)`` of it (:func:`roller_period`), one
    for every wheel or one per rolling wheel (file order); wheels without rollers ignore it
    (:func:`roller_offsets`). The encoders start at zero whatever the phase. ``controller``: the
    robot whose encoder scale the dc motors' speed loops count by (default ``robot.design``, else
    ``robot``; module docstring, "motors")."""

    def __init__(
        self,
        robot: Robot,
        *,
        start=(0.0, 0.0, 0.0),
        step: float = DEFAULT_STEP,
        description: PhysicalRobot | None = None,
        roller_phase=0.0,
        controller: Robot | None = None,
        world: World | None = None,
        sensors: bool | float = False,
    ):
        mujoco = _mujoco()
        self._mj = mujoco
        self.robot = robot
        self.description = description if description is not None else describe(robot)
        if [w.name for w in self.description.wheels] != robot.wheel_names:
            raise InputError(
                f"robot {robot.name!r}: the physical description has wheels "
                f"{shorten([w.name for w in self.description.wheels])}, the robot {shorten(robot.wheel_names)}"
            )
        margin = self.description.support_margin
        if margin <= 0.0:
            where = f"{-margin:.3g} m outside" if margin < 0.0 else "on the edge of"
            raise InputError(
                f"robot {robot.name!r} cannot stand: its centre of mass lies {where} the polygon of its wheels' "
                "contact points" + ("" if margin < 0.0 else " (or on the line they stand in)")
            )
        pose = finite_vector(start, 3)
        if pose is None or np.max(np.abs(pose)) > START_MAX:
            raise InputError(
                f"start pose must be 3 finite numbers (x, y, theta) within +-{START_MAX:g} m and rad (beyond, "
                f"doubles no longer resolve the contacts), got {shorten(start)}"
            )
        start = pose
        self.world = world
        if world is not None:  # a start inside a wall would throw the robot out of it
            from ..world.collision import Collider
            from .description import footprint

            Collider(world, footprint(self.description)).require_clear(start)
        self.xml = mjcf(self.description, step, world)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        self.step_size = float(self.model.opt.timestep)
        m = self.model

        def joint(name: str) -> int:
            return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)

        def actuator(name: str) -> int:
            return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)

        wheels = {w.name: w for w in self.description.wheels}
        rolling = robot.rolling_names
        self._wheel_qpos = np.array([m.jnt_qposadr[joint(n)] for n in rolling])
        self._wheel_dof = np.array([m.jnt_dofadr[joint(n)] for n in rolling])
        driven = [i for i, n in enumerate(rolling) if wheels[n].driven]
        self._driven = np.array(driven, dtype=int)
        self._drive_ctrl = np.array([actuator(rolling[i]) for i in driven], dtype=int)
        motors = [wheels[rolling[i]].motor for i in driven]
        self._max_speed = np.array([mo.max_speed for mo in motors if mo is not None])
        self._speed_step = np.array([mo.max_accel * self.step_size for mo in motors if mo is not None])
        self._integral_gain = np.array([self.step_size / mo.integral_time for mo in motors if mo is not None])
        self._windup = np.array([mo.max_torque / mo.gain for mo in motors if mo is not None])
        self._driven_radius = np.array([robot.wheel(rolling[i]).radius for i in driven])
        self.loop_turn = _loop_turn(robot, controller, [rolling[i] for i in driven])
        """Per driven wheel, the joint speed its motor turns per unit of commanded speed: 1 for a
        stepper, ``rpt_true / rpt_controller`` for a dc motor (module docstring, "motors")."""
        self.driven_names = [rolling[i] for i in driven]
        """Names of the driven wheels (file order): the wheels of :attr:`lag_time` and friends."""
        self._track_alpha = min(1.0, UNWRAP_CHUNK * self.step_size / TRACK_TIME)
        self._track_ms = np.zeros(len(driven))
        self._track_sum = np.zeros(len(driven))
        self._lag_steps = np.zeros(len(driven), dtype=np.int64)
        self.lag_start = np.full(len(driven), math.nan)
        """Per driven wheel, the time [s] its tracking error first exceeded :data:`TRACK_ERROR` (NaN: never)."""
        self.lag_worst = np.zeros(len(driven))
        """Per driven wheel, the largest root mean square rim speed error [m/s] over :data:`TRACK_TIME`."""
        self._drive_dof = self._wheel_dof[self._driven]
        steer = robot.steer_names
        self._steer_qpos = np.array([m.jnt_qposadr[joint(f"{n}_steer")] for n in steer], dtype=int)
        self._steer_ctrl = np.array([actuator(f"{n}_steer") for n in steer], dtype=int)
        steerings = [wheels[n].steering for n in steer]
        self._steer_step = np.array([s.max_rate * self.step_size for s in steerings if s is not None])
        self._steer_limits = [s.limits for s in steerings if s is not None]
        self._steer_low = np.array([-np.inf if lim is None else lim[0] for lim in self._steer_limits])
        self._steer_high = np.array([np.inf if lim is None else lim[1] for lim in self._steer_limits])
        self._steer_gain = np.array([self.step_size / s.integral_time for s in steerings if s is not None])
        self._steer_windup = np.array([s.max_torque / s.stiffness for s in steerings if s is not None])
        self._steer_integral = np.zeros(len(steer))
        self._chassis = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "chassis")
        self._free = m.jnt_qposadr[joint("chassis:free")]
        self._free_dof = m.jnt_dofadr[joint("chassis:free")]
        encoded = robot.encoded_names
        self._encoded = np.array(robot.rolling_index(encoded), dtype=int)
        self._rad_per_tick = robot.rad_per_tick(encoded) if encoded else np.zeros(0)
        self._bits = [robot.wheel(n).encoder.counter_bits for n in encoded]  # type: ignore[union-attr]

        self._speed_target = np.zeros(len(driven))
        self.saturated = 0
        """Commands that asked a motor for more than its speed limit, or a steering joint for an
        angle beyond its limits (held at the limit, as the motor or the end stop would)."""
        self._speed_set = np.zeros(len(driven))
        self._integral = np.zeros(len(driven))
        self._ramping = False
        self._steer_target = np.zeros(len(steer))
        self._steer_set = np.zeros(len(steer))
        self.contacts: list[Contact] = []
        """Where the robot began to touch a body of the world (:meth:`_watch_contacts`)."""
        self._world_geoms = _world_geom_bodies(mujoco, m, world)
        obstacles = world.obstacles if world is not None else ()
        self._obstacle_bodies = [
            mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"world:obstacle:{j}") for j in range(len(obstacles))
        ]
        self._robot_geoms = m.body_rootid[m.geom_bodyid] == self._chassis
        self._touching: set[int] = set()
        self.roller_offsets = roller_offsets(self.description, rolling, roller_phase)
        """Wheel joint angles [rad] of the rolling wheels (file order) at the start of settling."""
        self._settle(start)
        self.sensors: PhysicsSensors | None = None
        """What the robot's IMUs and lidars read (:mod:`omnikin.physics.sensing`), when made
        with ``sensors`` (True: every sample kept; a number [s]: the latest that long) and the
        robot has some; else None."""
        if sensors is not False and any(isinstance(s, (Imu, Lidar)) for s in robot.sensors):
            keep = None if sensors is True else float(sensors)
            self.sensors = PhysicsSensors(
                mujoco, m, self.data, robot, self._free, self._free_dof, self.step_size, keep=keep
            )

    # --- start ---------------------------------------------------------------------------------
    def _settle(self, start: np.ndarray) -> None:
        """Let the robot take its weight, then put it back at ``start`` at rest (module docstring)."""
        mj, m, d = self._mj, self.model, self.data
        d.qpos[self._wheel_qpos] = self.roller_offsets
        mj.mj_forward(m, d)
        settled = False
        steps_min = max(1, round(SETTLE_MIN / self.step_size))
        h = self.step_size
        with _quiet(mj):
            for k in range(round(SETTLE_MAX / h)):
                mj.mj_step(m, d)
                if abs(d.time - (k + 1) * h) > h / 2 or (k == 0 and self._warned()):  # MuJoCo reset the state
                    self._diverged(k * h, settling=True)
                v = d.qvel[self._free_dof : self._free_dof + 6]
                still = abs(v[2]) < SETTLE_SPEED and abs(v[3]) < SETTLE_SPEED and abs(v[4]) < SETTLE_SPEED
                if k >= steps_min and still:
                    settled = True
                    break
        self._check(settling=True)
        if not settled:
            raise PhysicsError(
                f"robot {self.robot.name!r} did not come to rest on the floor within {SETTLE_MAX:g} s "
                f"(it tips over or bounces)"
            )
        q = d.qpos[self._free : self._free + 7]
        yaw = self._chassis_yaw()
        turn = float(start[2]) - yaw
        q[0], q[1] = start[0], start[1]  # the body origin to the start, turned about it by `turn`
        spin = np.array([math.cos(turn / 2.0), 0.0, 0.0, math.sin(turn / 2.0)])
        quat = np.empty(4)
        mj.mju_mulQuat(quat, spin, q[3:7].copy())
        q[3:7] = quat
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        d.time = 0.0
        mj.mj_forward(m, d)
        self._zero = d.qpos[self._wheel_qpos].copy()
        self._heading = float(start[2])
        self._last_yaw = self._chassis_yaw()
        self._steps = 0

    # --- commands ---------------------------------------------------------------------------------
    def command(self, wheel_speeds, steer=None) -> None:
        """Set the wheel speeds [rad/s] of the rolling wheels (file order) and, for steerable
        wheels, the steering angles [rad]; reached through the ramp (module docstring)."""
        n = len(self.robot.rolling)
        speeds = finite_vector(wheel_speeds, n)
        if speeds is None:
            raise InputError(
                f"robot {self.robot.name!r}: expected {n} finite wheel speeds [rad/s] (rolling wheels "
                f"{shorten(self.robot.rolling_names)}), got {shorten(wheel_speeds)}"
            )
        wanted = speeds[self._driven] * self.loop_turn
        self._speed_target = np.clip(wanted, -self._max_speed, self._max_speed)
        clipped = not np.array_equal(self._speed_target, wanted)
        self._ramping = self.ramping
        if steer is None:
            self.saturated += clipped
            return
        k = len(self._steer_ctrl)
        angles = finite_vector(steer, k)
        if angles is None:
            raise InputError(
                f"robot {self.robot.name!r}: expected {k} finite steering angles [rad] "
                f"(steerable wheels {shorten(self.robot.steer_names)}), got {shorten(steer)}"
            )
        for i, limits in enumerate(self._steer_limits):
            if limits is None:  # turns all the way round: the nearest turn of the angle
                angles[i] = self._steer_set[i] + wrap_angle(float(angles[i] - self._steer_set[i]))
            elif not limits[0] <= angles[i] <= limits[1]:
                angles[i] = min(max(angles[i], limits[0]), limits[1])
                clipped = True
        self.saturated += clipped
        self._steer_target = angles
        self._ramping = self.ramping

    @property
    def ramping(self) -> bool:
        """True while a set-point has not reached its command."""
        return not (
            np.array_equal(self._speed_set, self._speed_target) and np.array_equal(self._steer_set, self._steer_target)
        )

    # --- stepping ----------------------------------------------------------------------------------
    def step(self, n: int = 1) -> None:
        """Advance ``n`` time steps (a whole number >= 0, at most :data:`ADVANCE_MAX` of simulated
        time). Raises :class:`DivergedError` at the step where MuJoCo finds the state not finite."""
        most = round(ADVANCE_MAX / self.step_size)
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 0 <= n <= most:
            raise InputError(
                f"step: the number of steps must be a whole number from 0 to {most} ({ADVANCE_MAX:g} s), "
                f"got {shorten(n)}"
            )
        mj, m, d = self._mj, self.model, self.data
        h = self.step_size
        sensing = self.sensors
        with _quiet(mj):
            for _ in range(int(n)):
                self._control()
                mj.mj_step(m, d)
                self._steps += 1
                if abs(d.time - self._steps * h) > h / 2 or (self._steps == 1 and self._warned()):
                    self._diverged((self._steps - 1) * h, settling=False)  # MuJoCo reset the state
                if self._world_geoms is not None:
                    self._watch_contacts()
                if sensing is not None and self._steps == sensing.due:
                    sensing.take(self._steps)
                if self._steps % UNWRAP_CHUNK == 0:
                    self._track_heading()
                    self._track_window()
        self._track_heading()
        self._check()

    def _watch_contacts(self) -> None:
        """Note each body of the world the robot begins to touch (:attr:`contacts`: the time,
        the body's name, the contact point on the floor plane), once per touch."""
        d = self.data
        n = d.ncon
        touching: set[int] = set()
        if n:
            contact = d.contact
            g1, g2 = contact.geom1[:n], contact.geom2[:n]
            bodies = self._world_geoms
            assert bodies is not None
            hit = np.where(self._robot_geoms[g1], bodies[g2], np.where(self._robot_geoms[g2], bodies[g1], -1))
            for k in np.flatnonzero(hit >= 0):
                body = int(hit[k])
                if body not in touching and body not in self._touching:
                    x, y = (float(v) for v in contact.pos[k, :2])
                    self.contacts.append(Contact(float(d.time), self.world.bodies[body], (x, y)))  # type: ignore[union-attr]
                touching.add(body)
        self._touching = touching

    def _track_window(self) -> None:
        """Move the wheels' tracking window (:data:`TRACK_TIME`) on by the last
        :data:`UNWRAP_CHUNK` steps (their mean squared rim speed error, summed by :meth:`_control`)."""
        self._track_ms += (self._track_sum / UNWRAP_CHUNK - self._track_ms) * self._track_alpha
        self._track_sum[:] = 0.0
        beyond = self._track_ms > TRACK_ERROR * TRACK_ERROR
        if beyond.any():
            self._lag_steps += beyond * UNWRAP_CHUNK
            self.lag_start[beyond & np.isnan(self.lag_start)] = self.data.time
            np.maximum(self.lag_worst, np.sqrt(self._track_ms), out=self.lag_worst)

    def advance(self, t: float) -> None:
        """Step until the simulation time reaches ``t`` [s] (to the nearest step; at most
        :data:`ADVANCE_MAX` beyond the present time)."""
        if isinstance(t, bool) or not isinstance(t, numbers.Real) or not math.isfinite(t):
            raise InputError(f"advance: time must be a finite number of seconds, got {shorten(t)}")
        if t - self.time > ADVANCE_MAX:
            raise InputError(
                f"advance: at most {ADVANCE_MAX:g} s of simulated time per call (now t = {self.time:.6g} s), got "
                f"{shorten(t)}; advance in several calls"
            )
        n = round((float(t) - self.time) / self.step_size)
        if n > 0:
            self.step(n)

    def _control(self) -> None:
        """One step of the ramps and of the wheels' PI speed controllers (module docstring)."""
        d = self.data
        if self._ramping:
            change = self._speed_target - self._speed_set
            room = np.divide(self._speed_step, np.abs(change), out=np.full_like(change, np.inf), where=change != 0)
            self._speed_set += change * min(1.0, float(room.min(initial=np.inf)))
            if len(self._steer_ctrl):
                self._steer_set += np.clip(self._steer_target - self._steer_set, -self._steer_step, self._steer_step)
            self._ramping = self.ramping
        error = self._speed_set - d.qvel[self._drive_dof]
        rim = error * self._driven_radius
        self._track_sum += rim * rim
        self._integral = np.clip(self._integral + error * self._integral_gain, -self._windup, self._windup)
        d.ctrl[self._drive_ctrl] = self._speed_set + self._integral
        if len(self._steer_ctrl):
            error = self._steer_set - d.qpos[self._steer_qpos]
            self._steer_integral = np.clip(
                self._steer_integral + error * self._steer_gain, -self._steer_windup, self._steer_windup
            )
            d.ctrl[self._steer_ctrl] = self._steer_set + self._steer_integral

    def fall(self) -> str | None:
        """None while the robot stands, else one phrase saying that it tipped over: its chassis
        tilted beyond :data:`TIPPED` (the test every physics user makes: ``simulate --engine
        physics``, studies, the ROS node's and the viewer's back-end)."""
        tilt = self.tilt
        if tilt <= TIPPED:
            return None
        return (
            f"robot {self.robot.name!r} tipped over at t = {self.time:.4g} s (chassis tilted {math.degrees(tilt):.3g} "
            f"deg): its contacts left the support of its weight"
        )

    def _chassis_yaw(self) -> float:
        """The chassis' heading [rad] in ``(-pi, pi]`` now, from its free joint (MuJoCo's
        ``xmat`` after a step holds the pose at the step's start)."""
        return _quat_yaw(self.data.qpos[self._free + 3 : self._free + 7])

    def _track_heading(self) -> None:
        yaw = self._chassis_yaw()
        self._heading += wrap_angle(yaw - self._last_yaw)
        self._last_yaw = yaw

    def _warned(self) -> int:
        """How often MuJoCo found the state not finite or huge (and reset it: its clock restarts at 0,
        which is how :meth:`step` finds the step where it happened, except from time 0)."""
        d, warnings = self.data, self._mj.mjtWarning
        return sum(
            d.warning[w].number for w in (warnings.mjWARN_BADQACC, warnings.mjWARN_BADQPOS, warnings.mjWARN_BADQVEL)
        )

    def _check(self, settling: bool = False) -> None:
        """Refuse to go on after MuJoCo found the state not finite (it then resets the state and
        counts a warning; :meth:`step` catches the step where it did) or the state is not finite."""
        d = self.data
        if self._warned() or not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
            self._diverged(self._steps * self.step_size if not settling else float(d.time), settling=settling)

    def _diverged(self, t: float, settling: bool) -> None:
        """Raise :class:`DivergedError` at simulated time ``t`` [s] (of settling when ``settling``)."""
        when = f"while settling on the floor, {t:.4g} s after it was put down" if settling else f"at t = {t:.4g} s"
        cause = (
            "the robot cannot even stand: check its sizes and physical fields (masses, radii, torques)"
            if settling
            else "check the commands and the robot's physical fields (masses, radii, torques)"
        )
        raise DivergedError(
            f"robot {self.robot.name!r}: the physics simulation diverged {when} (MuJoCo found a non-finite or huge "
            f"acceleration at a {self.step_size:g} s time step); {cause}",
            time=t,
            settling=settling,
            step=self.step_size,
            min_step=STEP_RANGE[0],
        )

    # --- readings ------------------------------------------------------------------------------------
    @property
    def lag_time(self) -> np.ndarray:
        """Per driven wheel (:attr:`driven_names`), the time [s] its root mean square rim speed
        error over :data:`TRACK_TIME` exceeded :data:`TRACK_ERROR`: it did not follow its set-points."""
        return self._lag_steps * self.step_size

    @property
    def tracking_error(self) -> np.ndarray:
        """Per driven wheel, the present root mean square rim speed error [m/s] over :data:`TRACK_TIME`."""
        return np.sqrt(self._track_ms)

    @property
    def time(self) -> float:
        """Simulation time [s] since the end of settling."""
        return float(self.data.time)

    @property
    def pose(self) -> np.ndarray:
        """Ground-truth pose ``(x, y, theta)`` [m, m, rad] of the body frame; ``theta`` continuous."""
        q = self.data.qpos[self._free : self._free + 3]
        self._track_heading()
        return np.array([q[0], q[1], self._heading])

    def obstacle_poses(self) -> np.ndarray:
        """``(n_obstacles, 3)`` pose ``(x, y, yaw)`` [m, m, rad] of each obstacle of the world
        (world frame; movable ones where the robot pushed them), empty without a world."""
        out = np.empty((len(self._obstacle_bodies), 3))
        for j, body in enumerate(self._obstacle_bodies):
            out[j, :2] = self.data.xpos[body][:2]
            out[j, 2] = _yaw(self.data.xmat[body])
        return out

    @property
    def tilt(self) -> float:
        """Angle [rad] between the chassis' z axis and the vertical (0 standing level)."""
        _, x, y, _ = (float(v) for v in self.data.qpos[self._free + 3 : self._free + 7])
        return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y))))  # R_22 of the free joint's quaternion

    @property
    def height(self) -> float:
        """Height [m] of the body frame's origin above the floor (0 in the design; the contacts sink)."""
        return float(self.data.qpos[self._free + 2])

    @property
    def twist(self) -> np.ndarray:
        """Ground-truth body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] (module docstring)."""
        d = self.data
        v = d.qvel[self._free_dof : self._free_dof + 3]  # the body origin's velocity, world axes
        w = d.qvel[self._free_dof + 3 : self._free_dof + 6]  # the angular velocity, body axes
        qw, qx, qy, qz = (float(u) for u in d.qpos[self._free + 3 : self._free + 7])
        up = (2.0 * (qx * qz - qw * qy), 2.0 * (qy * qz + qw * qx), 1.0 - 2.0 * (qx * qx + qy * qy))  # R's last row
        turn = up[0] * w[0] + up[1] * w[1] + up[2] * w[2]  # the angular velocity's vertical part
        yaw = self._chassis_yaw()
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1], turn])

    @property
    def wheel_angles(self) -> np.ndarray:
        """Angles [rad] of the rolling wheels (file order) since the start."""
        return self.data.qpos[self._wheel_qpos] - self._zero

    @property
    def wheel_speeds(self) -> np.ndarray:
        """Speeds [rad/s] of the rolling wheels (file order)."""
        return self.data.qvel[self._wheel_dof].copy()

    @property
    def steer_angles(self) -> np.ndarray:
        """Steering angles [rad] of the steerable wheels (file order), relative to their mounting
        drive direction, wrapped to ``[-pi, pi)``; within the wheel's steering limits, as its
        angle sensor reads a joint held at its end stop (MuJoCo's soft joint limit lets the
        joint press a few nanoradians past it, which the file's limits would refuse)."""
        return np.clip(wrap_angle(self.data.qpos[self._steer_qpos]), self._steer_low, self._steer_high)

    def encoder_counts(self) -> np.ndarray:
        """Whole ticks ``round(angle / rad_per_tick)`` the encoded wheels (file order) turned since
        the start, never wrapped (int64)."""
        return np.rint(self.wheel_angles[self._encoded] / self._rad_per_tick).astype(np.int64)

    def encoder_ticks(self) -> np.ndarray:
        """Encoder readings of the encoded wheels (file order): :meth:`encoder_counts` wrapped
        modulo ``2**counter_bits`` where the encoder has a counter width (unsigned, as the
        hardware register holds them)."""
        return counter_output(self.encoder_counts(), self._bits)
