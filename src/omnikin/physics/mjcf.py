"""MuJoCo's XML model (MJCF) of a physical description (:mod:`omnikin.physics.description`).

:func:`mjcf` writes the text with :mod:`xml.etree.ElementTree` (every value an attribute, so
names and numbers are escaped by the writer, never pasted into markup); it does not need
``mujoco``. The model:

- ``<option>``: the ``implicitfast`` integrator (velocity-dependent forces, here the speed
  servos, integrated implicitly: stable at any servo gain), time step 2 ms by default,
  elliptic friction cones (isotropic friction: a pyramid would favour its edge directions);
- a floor plane and one free body ``chassis`` whose frame is the robot's body frame with its
  origin on the floor, so the chassis pose is the robot's pose;
- per wheel a body ``NAME:wheel`` (frame: x along the drive direction, y along the axle) with
  a hinge joint ``NAME`` about its axle; standard wheels and castors roll on a tyre that is an
  ellipsoid of revolution about the axle (semi-axes ``r``, ``width / 2``, ``r``: exactly round
  in the wheel plane, rounded across it), which touches the floor in one point in the wheel's
  mid-plane as the kinematics assumes (a cylinder touches it at both rim edges, which slide
  against each other whenever the wheel turns about a vertical axis, and then transmits no
  drive force without slipping by about ``omega width / 2``: a differential drive turning on
  the spot lost 11 % of its rate that way); Swedish wheels on ellipsoid rollers
  ``NAME:roller:ROW:K``, each a body with a free hinge joint of the same name about its spin
  axis; steered wheels and castors hang from a fork body
  ``NAME:fork`` with a vertical hinge joint ``NAME_steer`` through the steering axis;
- actuators: a velocity servo ``NAME`` on each driven wheel (``kv`` the servo gain,
  ``forcerange`` the motor torque, ``ctrlrange`` the speed limit) and a position servo
  ``NAME_steer`` on each steering joint of a steerable wheel (castors swivel freely);
- contacts only between the wheels (tyres, rollers) and the floor (``contype``/``conaffinity``
  bits: the robot's parts never collide with each other, so rollers may overlap their hub; the
  chassis is drawn only: MuJoCo 4.0.0 reports a false contact tens of millimetres deep between
  a plane and a cylinder standing exactly upright on it when rounding leaves 1e-17 in its
  rotation matrix, which launched the robot into the air), three friction
  dimensions (``condim 3``: sliding in the plane, no torsional or rolling friction), the
  wheel's friction coefficient (MuJoCo takes the larger of two geoms' coefficients: the floor's
  is 0) and a contact softness of :data:`CONTACT_SOLREF` and :data:`CONTACT_SOLIMP`.

Names: wheel names are letters, digits and underscores (``omnikin.kinematics.wheels.NAME_PATTERN``); the
names MuJoCo needs to be unique get a suffix with ``:``, which no wheel name holds, so a wheel
called ``chassis`` or ``w1_roller`` cannot collide with anything generated. Joint and actuator
names of the wheels and steering joints are those of ROS ``joint_states`` (``NAME``,
``NAME_steer``).
"""

from __future__ import annotations

import math
import numbers
import xml.etree.ElementTree as ET

import numpy as np

from ..common.messages import shorten
from ..errors import SMALLEST_STEP, InputError
from ..kinematics.robot import Robot
from ..world.model import Box, World
from ..world.plane import triangulate, wall_rects
from .description import MAX_STEP, PhysicalRobot, WheelBody, describe, shape_volume_inertia
from .validity import check_resolvable

DEFAULT_STEP = 0.002
"""Time step [s]: 500 Hz resolves the contact dynamics of rollers a few millimetres thick."""
CONTACT_SOLREF = (2.0 * MAX_STEP, 1.0)
"""Contact time constant [s] and damping ratio: critically damped, and no shorter than twice
the default time step, below which MuJoCo's soft contacts lose their meaning."""
STEP_RANGE = (SMALLEST_STEP, MAX_STEP)
"""Time steps [s] :func:`mjcf` accepts: at most half the contacts' time constant
(:data:`CONTACT_SOLREF`). MuJoCo raises a time constant below twice the step to twice the step
(its ``refsafe`` flag), so a longer step would silently simulate softer contacts: at 4 ms the
wheels of tomasi-omni3 sank 112 um instead of 16 um, the same as a time constant of 8 ms, and
the UMBmark floor's heading bias grew from 0.15 to 0.57 deg (docs/physics.md, "Convergence")."""
CONTACT_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
"""Contact impedance (MuJoCo's default width, 95 % of a contact enforced when shallow, 99 % from
1 mm deep). The wheels sink 0.01-0.1 % of their radius under the robot's weight, which shortens
the rolling radius by about half as much (0.04 % on tomasi-omni3). Stiffer contacts (99 % at
any depth) sink five times less but make the load of a four-wheel base jump between its wheels
as the rollers hand over: omni4 on a curve left its kinematic twist by 1.1 % instead of 0.13 %."""

ROBOT_BITS = (2, 1 | 8)
"""``contype``, ``conaffinity`` of the wheels' geoms: they collide with the floor (and its
patches) and with a world's bodies, never with each other or the chassis."""
FLOOR_BITS = (1, 2)
"""``contype``, ``conaffinity`` of the floor and its friction patches."""
CHASSIS_BITS = (4, 0)
"""``contype``, ``conaffinity`` of the chassis in a world: it touches the world's bodies only
(never the floor: module docstring)."""
WORLD_BITS = (8, 1 | 2 | 4 | 8)
"""``contype``, ``conaffinity`` of a world's walls and obstacles: they touch the robot, the floor
(movable obstacles stand on it) and each other."""
WORLD_GROUP = 2
"""Geom group of a world's walls and obstacles: what a lidar's rays see."""
PATCH_RAISE = 5e-4
"""Height [m] of a friction patch's top above the floor: a wheel on it touches the patch only
(MuJoCo would otherwise combine the patch's contact with the floor's under it)."""
PATCH_DEPTH = 0.01
"""Depth [m] of a patch's prism below the floor."""
MARK_HEIGHT = 2e-4
"""Height [m] of a floor mark's strip (drawn only)."""
MARK_WIDTH = 0.02
"""Width [m] of a floor mark's strip."""
OBSTACLE_FRICTION = 0.5
"""Sliding friction of a movable obstacle on the floor and against walls (wood on concrete)."""
VISUAL_GROUP = 1
"""Geom group of the parts that are drawn but never touch anything (hubs of Swedish wheels, forks)."""


def _num(x: float) -> str:
    return format(float(x), ".15g")


def _vec(values) -> str:
    return " ".join(_num(v) for v in values)


def _sub(parent: ET.Element, tag: str, **attrs) -> ET.Element:
    return ET.SubElement(parent, tag, {k: v for k, v in attrs.items() if v is not None})


def _contact(geom: ET.Element, friction: float, bits: tuple[int, int] = ROBOT_BITS) -> None:
    """Make ``geom`` touch what ``bits`` (``contype``, ``conaffinity``) let it, with sliding
    ``friction`` only (``condim`` 3) and the contacts' softness (:data:`CONTACT_SOLREF`,
    :data:`CONTACT_SOLIMP`); the wheels' bits unless told."""
    geom.set("contype", str(bits[0]))
    geom.set("conaffinity", str(bits[1]))
    geom.set("condim", "3")
    geom.set("friction", _vec((friction, 0.0, 0.0)))
    geom.set("solref", _vec(CONTACT_SOLREF))
    geom.set("solimp", _vec(CONTACT_SOLIMP))


def _visual(geom: ET.Element) -> None:
    geom.set("contype", "0")
    geom.set("conaffinity", "0")
    geom.set("group", str(VISUAL_GROUP))


def _inertial(body: ET.Element, mass: float, diag, pos=(0.0, 0.0, 0.0)) -> None:
    _sub(body, "inertial", pos=_vec(pos), mass=_num(mass), diaginertia=_vec(diag))


def _wheel(parent: ET.Element, wheel: WheelBody, pos, yaw: float | None) -> None:
    """The wheel body of ``wheel`` at ``pos`` in ``parent`` (turned by ``yaw`` about z)."""
    body = _sub(
        parent, "body", name=f"{wheel.name}:wheel", pos=_vec(pos), euler=None if yaw is None else _vec((0, 0, yaw))
    )
    axle, across = wheel.hub_inertia
    _inertial(body, wheel.hub_mass, (across, axle, across))
    armature = wheel.motor.armature if wheel.motor is not None and wheel.motor.armature > 0.0 else None
    _sub(
        body,
        "joint",
        name=wheel.name,
        type="hinge",
        axis="0 1 0",
        armature=None if armature is None else _num(armature),
    )
    rollers = wheel.rollers
    if rollers is None:
        tyre = _sub(body, "geom", name=f"{wheel.name}:tyre", type="ellipsoid")
        tyre.set("size", _vec((wheel.radius, wheel.width / 2.0, wheel.radius)))
        tyre.set("mass", "0")
        _contact(tyre, wheel.friction)
        return
    hub = _sub(body, "geom", name=f"{wheel.name}:hub", type="cylinder", zaxis="0 1 0")
    hub.set("size", _vec((max(rollers.centre_radius - rollers.radius, 0.2 * wheel.radius), wheel.width / 2.0)))
    hub.set("mass", "0")
    _visual(hub)
    spin, side = rollers.inertia
    for roller in rollers.rollers:
        name = f"{wheel.name}:roller:{roller.row}:{roller.index}"
        rb = _sub(body, "body", name=name, pos=_vec(roller.position), zaxis=_vec(roller.axis))
        _inertial(rb, rollers.mass, (side, side, spin))
        _sub(rb, "joint", name=name, type="hinge", axis="0 0 1")
        geom = _sub(rb, "geom", name=name, type="ellipsoid")
        geom.set("size", _vec((rollers.radius, rollers.radius, rollers.half_length)))
        geom.set("mass", "0")
        _contact(geom, wheel.friction)


def _steered(parent: ET.Element, wheel: WheelBody) -> None:
    """Fork with its vertical steering joint, then the wheel trailing the axis."""
    steering = wheel.steering
    assert steering is not None
    pivot = (steering.pivot[0], steering.pivot[1], wheel.radius)
    fork = _sub(parent, "body", name=f"{wheel.name}:fork", pos=_vec(pivot), euler=_vec((0, 0, wheel.drive)))
    _inertial(fork, steering.fork_mass, steering.fork_inertia)
    joint = _sub(fork, "joint", name=f"{wheel.name}_steer", type="hinge", axis="0 0 1")
    if steering.armature > 0.0:
        joint.set("armature", _num(steering.armature))
    if steering.limits is not None:
        joint.set("range", _vec(steering.limits))
    size = max(wheel.radius / 4.0, 1e-3)
    stem = _sub(fork, "geom", name=f"{wheel.name}:fork", type="box", size=_vec((size, size / 2.0, size / 2.0)))
    stem.set("pos", _vec((-steering.trail / 2.0, 0.0, wheel.radius)))
    stem.set("mass", "0")
    _visual(stem)
    _wheel(fork, wheel, (-steering.trail, 0.0, 0.0), None)


def _world_bodies(asset: ET.Element, parent: ET.Element, floor: ET.Element, world: World) -> None:
    """``world``'s floor friction, patches, marks, walls and obstacles in the model.

    - The floor takes the world's friction, when it gives one, by priority (MuJoCo then uses
      the floor's coefficient, not the larger of the two geoms').
    - Each patch is cut into triangles (:func:`omnikin.world.plane.triangulate`), each a prism
      mesh from :data:`PATCH_DEPTH` below the floor to :data:`PATCH_RAISE` above it, with the
      patch's friction by priority: a wheel on it rests on the patch alone.
    - Each mark is a strip :data:`MARK_WIDTH` wide per segment, drawn only.
    - Each wall segment and fixed obstacle is a static body of its own (MuJoCo skips pairs of
      static geoms; one body each keeps its broad phase as cheap as on the empty floor), each
      movable obstacle a free body of its mass, uniform; all in :data:`WORLD_GROUP` (what a
      lidar sees) with :data:`WORLD_BITS`. Bodies and geoms are named by place, not by the
      world's names (which may hold any character): ``world:wall:I:K`` (wall I's segment K),
      ``world:obstacle:J``, ``world:patch:I:K``, ``world:mark:I:K``, all from 0.
    """
    if world.floor.friction is not None:
        floor.set("priority", "1")
        floor.set("friction", _vec((world.floor.friction, 0.0, 0.0)))
    for i, patch in enumerate(world.floor.patches):
        polygon = np.asarray(patch.polygon, dtype=float)
        for k, tri in enumerate(triangulate(polygon)):
            corners = polygon[tri]
            vertices = [(x, y, z) for z in (-PATCH_DEPTH, PATCH_RAISE) for x, y in corners]
            mesh = f"patch:{i}:{k}"
            _sub(asset, "mesh", name=mesh, vertex=_vec(np.ravel(vertices)))
            geom = _sub(parent, "geom", name=f"world:patch:{i}:{k}", type="mesh", mesh=mesh)
            _contact(geom, patch.friction, (FLOOR_BITS[0], FLOOR_BITS[1] | WORLD_BITS[0]))
            geom.set("priority", "1")
            geom.set("rgba", "0.35 0.55 0.85 0.6")
    for i, mark in enumerate(world.marks):
        for k, (a, b) in enumerate(zip(mark.points[:-1], mark.points[1:], strict=True)):
            length = math.dist(a, b)
            strip = _sub(parent, "geom", name=f"world:mark:{i}:{k}", type="box")
            strip.set("size", _vec((length / 2.0 + MARK_WIDTH / 2.0, MARK_WIDTH / 2.0, MARK_HEIGHT / 2.0)))
            strip.set("pos", _vec(((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, MARK_HEIGHT / 2.0)))
            strip.set("euler", _vec((0.0, 0.0, math.atan2(b[1] - a[1], b[0] - a[0]))))
            strip.set("rgba", "0.85 0.65 0.1 1")
            _visual(strip)
    for i, wall in enumerate(world.walls):
        for k, rect in enumerate(wall_rects(np.asarray(wall.points, dtype=float), wall.thickness)):
            _static_box(parent, f"world:wall:{i}:{k}", rect, wall.height, "0.75 0.72 0.68 1")
    for j, obstacle in enumerate(world.obstacles):
        name = f"world:obstacle:{j}"
        if isinstance(obstacle, Box):
            sx, sy, sz = obstacle.size
            rect = np.array([*obstacle.center, sx / 2.0, sy / 2.0, obstacle.yaw])
            if obstacle.fixed:
                _static_box(parent, name, rect, sz, "0.55 0.4 0.3 1")
                continue
            body = _sub(parent, "body", name=name, pos=_vec((*obstacle.center, sz / 2.0)))
            body.set("euler", _vec((0.0, 0.0, obstacle.yaw)))
            half = (sx / 2.0, sy / 2.0, sz / 2.0)
            geom = _sub(body, "geom", name=name, type="box", size=_vec(half))
            _, inertia = shape_volume_inertia("box", half, float(obstacle.mass or 0.0))
        else:
            half_height = obstacle.height / 2.0
            body = _sub(parent, "body", name=name, pos=_vec((*obstacle.center, half_height)))
            geom = _sub(body, "geom", name=name, type="cylinder", size=_vec((obstacle.radius, half_height)))
            if obstacle.fixed:
                _world_geom(geom, "0.5 0.5 0.55 1")
                continue
            _, inertia = shape_volume_inertia("cylinder", (obstacle.radius, half_height), float(obstacle.mass or 0.0))
        _sub(body, "freejoint", name=f"{name}:free")
        _inertial(body, float(obstacle.mass or 0.0), inertia)
        geom.set("mass", "0")
        _world_geom(geom, "0.8 0.45 0.2 1")


def _static_box(parent: ET.Element, name: str, rect: np.ndarray, height: float, rgba: str) -> None:
    """A static body ``name`` holding one box: ``rect`` (x, y, half length, half width, yaw)
    seen from above, ``height`` [m] tall, standing on the floor."""
    x, y, hx, hy, yaw = (float(v) for v in rect)
    body = _sub(parent, "body", name=name, pos=_vec((x, y, height / 2.0)), euler=_vec((0.0, 0.0, yaw)))
    _world_geom(_sub(body, "geom", name=name, type="box", size=_vec((hx, hy, height / 2.0))), rgba)


def _world_geom(geom: ET.Element, rgba: str) -> None:
    _contact(geom, OBSTACLE_FRICTION, WORLD_BITS)
    geom.set("group", str(WORLD_GROUP))
    geom.set("rgba", rgba)


def time_step(step: float | None = None, name: str = "time step") -> float:
    """``step`` [s] (:data:`DEFAULT_STEP` when None) if it lies in :data:`STEP_RANGE`, else
    :class:`~omnikin.errors.InputError` naming it as ``name`` (``"--step"``)."""
    if step is None:
        return DEFAULT_STEP
    if isinstance(step, bool) or not isinstance(step, numbers.Real) or not STEP_RANGE[0] <= step <= STEP_RANGE[1]:
        raise InputError(
            f"{name} must be a time step in [{STEP_RANGE[0]:g}, {STEP_RANGE[1]:g}] s (at most half the contact "
            f"time constant), got {shorten(step)}"
        )
    return float(step)


def mjcf(robot: PhysicalRobot | Robot, step: float = DEFAULT_STEP, world: World | None = None) -> str:
    """The MJCF text of ``robot`` (a description, or a robot to :func:`describe`; module
    docstring) with time step ``step`` [s] (:data:`STEP_RANGE`, :func:`time_step`), in ``world``
    (None: an empty floor; :func:`_world_bodies`). A robot the engine cannot resolve is refused
    in one line (:func:`omnikin.physics.validity.check_resolvable`)."""
    if isinstance(robot, Robot):
        robot = describe(robot)
    step = time_step(step)
    check_resolvable(robot)
    root = ET.Element("mujoco", model=robot.name)
    _sub(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="false")
    option = _sub(root, "option", timestep=_num(step), integrator="implicitfast", cone="elliptic")
    option.set("gravity", _vec((0.0, 0.0, -robot.gravity)))
    asset = _sub(root, "asset")
    _sub(asset, "texture", name="floor", type="2d", builtin="checker", width="512", height="512")
    asset[-1].set("rgb1", "0.82 0.82 0.8")
    asset[-1].set("rgb2", "0.72 0.72 0.7")
    _sub(asset, "material", name="floor", texture="floor", texrepeat="4 4", texuniform="true")

    world_body = _sub(root, "worldbody")
    _sub(world_body, "light", name="sun", directional="true", pos="0 0 5", dir="0 0 -1")
    floor = _sub(world_body, "geom", name="floor", type="plane", size="0 0 0.1", material="floor")
    floor.set("contype", str(FLOOR_BITS[0]))
    floor.set("conaffinity", str(FLOOR_BITS[1]))
    floor.set("friction", "0 0 0")
    floor.set("solref", _vec(CONTACT_SOLREF))
    floor.set("solimp", _vec(CONTACT_SOLIMP))

    if world is not None:
        _world_bodies(asset, world_body, floor, world)

    lift = max(0.0, max(w.reach - w.radius for w in robot.wheels))
    chassis = _sub(world_body, "body", name="chassis", pos=_vec((0.0, 0.0, lift)))
    _sub(chassis, "freejoint", name="chassis:free")
    c = robot.chassis
    _inertial(chassis, c.mass, c.inertia, c.com)
    plate = _sub(chassis, "geom", name="chassis", type=c.shape, pos=_vec(c.centre), size=_vec(c.size))
    plate.set("mass", "0")
    plate.set("rgba", "0.3 0.45 0.65 1")
    _visual(plate)  # MuJoCo 4.0's plane-cylinder test finds a deep false contact under a level cylinder
    if world is not None:  # it touches the world's bodies, still never the floor
        plate.set("contype", str(CHASSIS_BITS[0]))
        plate.set("conaffinity", str(CHASSIS_BITS[1]))
        plate.set("condim", "3")
        plate.set("friction", _vec((OBSTACLE_FRICTION, 0.0, 0.0)))
    for wheel in robot.wheels:
        if wheel.steering is not None:
            _steered(chassis, wheel)
        else:
            _wheel(chassis, wheel, wheel.hub, wheel.drive)

    actuators = _sub(root, "actuator")
    for wheel in robot.wheels:
        motor = wheel.motor
        if motor is not None:
            servo = _sub(actuators, "velocity", name=wheel.name, joint=wheel.name, kv=_num(motor.gain))
            servo.set("forcerange", _vec((-motor.max_torque, motor.max_torque)))
            servo.set("ctrlrange", _vec((-motor.max_speed, motor.max_speed)))
    for wheel in robot.steered:
        steering = wheel.steering
        assert steering is not None
        name = f"{wheel.name}_steer"
        servo = _sub(actuators, "position", name=name, joint=name, kp=_num(steering.stiffness))
        servo.set("kv", _num(steering.damping))
        servo.set("forcerange", _vec((-steering.max_torque, steering.max_torque)))
        if steering.limits is not None:
            servo.set("ctrlrange", _vec(steering.limits))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"
