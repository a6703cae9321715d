"""The URDF of a physical description (:mod:`omnikin.physics.description`), for ROS tools
(``robot_state_publisher``, RViz, MoveIt, Gazebo's importer) and any URDF parser.

:func:`urdf` writes the text with :mod:`xml.etree.ElementTree` (every name and number an
attribute, escaped by the writer, never pasted into markup); it needs neither ROS nor
``mujoco``. The tree, in the frames of :mod:`omnikin.physics.description` (SI, radians):

- link ``base_link``: the body frame of ``docs/conventions.md`` (x forward, y left, z up) with
  its origin on the floor under the kinematic reference point; it carries the chassis (its
  mass, centre of mass and inertia, its cylinder or box drawn and as collision shape);
- per wheel a link ``NAME_wheel`` (frame: x along the drive direction, y along the axle, z up,
  origin at the hub) on a ``continuous`` joint named as the wheel, axis ``0 1 0`` (the axle;
  positive = positive wheel speed, which drives the hub along the drive direction), with the
  motor's torque and speed limits when the wheel is driven;
- steered wheels and castors: a link ``NAME_fork`` on a joint ``NAME_steer`` about the vertical
  steering axis through the mounting point at hub height, ``revolute`` with the file's
  steering limits (relative to the mounting drive direction) or ``continuous`` when the wheel
  turns all the way round (castors swivel freely); the wheel's joint hangs from the fork,
  trailing the axis by the steering offset;
- Swedish wheels: per roller a link ``NAME_roller_ROW_K`` on a ``continuous`` joint of the same
  name about the roller's spin axis, its origin at the roller's centre;
- per IMU and lidar (:mod:`omnikin.kinematics.sensors`) a link named as the sensor (its frame:
  the mount, the frame of its messages) on a ``fixed`` joint ``NAME_joint`` from ``base_link``.

Joint names of the wheels and steering joints are those the ROS node publishes in
``joint_states`` (``NAME``, ``NAME_steer``; :mod:`omnikin.ros.node`) and MuJoCo's model uses
(:mod:`omnikin.physics.mjcf`).

Shapes: URDF has boxes, cylinders, spheres and meshes, no ellipsoids. Tyres (ellipsoids of
revolution about the axle in the physics model) are drawn and collide as cylinders of the
wheel's radius and width about the axle; rollers (ellipsoids of semi-axes ``b``, ``b``, ``a``
along their spin axis) are drawn as cylinders of radius ``b`` and length ``2 a`` along the spin
axis and collide as spheres of radius ``b`` about their centre, which touch the floor where the
ellipsoid does when the roller is at the bottom (its cross-section there is the same circle).
Masses and inertias are the description's (each roller's about its own centre, the hub's
without the rollers).

Link and joint names built from wheel names could meet (a wheel ``w_roller_0_1`` beside a
Swedish wheel ``w``): :func:`urdf` refuses such a robot with one line naming the name.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from ..common.messages import shorten
from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.sensors import Imu, Lidar, Sensor
from .description import PhysicalRobot, WheelBody, describe

BASE_LINK = "base_link"
"""The body frame's link (REP-105)."""


def _num(x: float) -> str:
    return format(float(x), ".15g")


def _vec(values) -> str:
    return " ".join(_num(v) for v in values)


def _z_to(axis) -> tuple[float, float, float]:
    """``(roll, pitch, yaw)`` [rad] of a rotation that turns +z onto the unit vector ``axis``
    (URDF's fixed-axis roll-pitch-yaw, ``R = Rz(yaw) Ry(pitch) Rx(roll)``; roll 0)."""
    x, y, z = axis
    return 0.0, math.acos(max(-1.0, min(1.0, z))), math.atan2(y, x)


class _Tree:
    """The ``<robot>`` element with a check that every link and joint name is new."""

    def __init__(self, name: str):
        self.root = ET.Element("robot", name=name)
        self.names: dict[str, set[str]] = {"link": set(), "joint": set()}

    def add(self, kind: str, name: str, **attrs) -> ET.Element:
        if name in self.names[kind]:
            raise InputError(
                f"robot {self.root.get('name')!r}: the URDF would hold two {kind}s named {shorten(name)} "
                f"(a wheel name meets a name built from another); rename the wheel"
            )
        self.names[kind].add(name)
        return ET.SubElement(self.root, kind, name=name, **attrs)

    def link(self, name: str, mass: float, com, inertia, rpy=(0.0, 0.0, 0.0)) -> ET.Element:
        """A link with its inertial: ``mass`` [kg] at ``com`` [m], principal moments ``inertia``
        [kg m^2] along the axes turned by ``rpy``."""
        link = self.add("link", name)
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "origin", xyz=_vec(com), rpy=_vec(rpy))
        ET.SubElement(inertial, "mass", value=_num(mass))
        ixx, iyy, izz = inertia
        ET.SubElement(inertial, "inertia", ixx=_num(ixx), ixy="0", ixz="0", iyy=_num(iyy), iyz="0", izz=_num(izz))
        return link

    def joint(self, name: str, kind: str, parent: str, child: str, xyz, rpy, axis) -> ET.Element:
        joint = self.add("joint", name, type=kind)
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=child)
        ET.SubElement(joint, "origin", xyz=_vec(xyz), rpy=_vec(rpy))
        ET.SubElement(joint, "axis", xyz=_vec(axis))
        return joint


def _shape(link: ET.Element, tag: str, geometry: str, xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0), **size) -> None:
    """A ``visual`` or ``collision`` (``tag``) of ``link``: ``geometry`` with ``size`` attributes."""
    element = ET.SubElement(link, tag)
    ET.SubElement(element, "origin", xyz=_vec(xyz), rpy=_vec(rpy))
    shape = ET.SubElement(element, "geometry")
    ET.SubElement(shape, geometry, {k: _num(v) if not isinstance(v, str) else v for k, v in size.items()})


def _limit(joint: ET.Element, effort: float, velocity: float, lower=None, upper=None) -> None:
    attrs = {"effort": _num(effort), "velocity": _num(velocity)}
    if lower is not None:
        attrs.update(lower=_num(lower), upper=_num(upper))
    ET.SubElement(joint, "limit", attrs)


def _wheel(tree: _Tree, wheel: WheelBody, parent: str, xyz, yaw: float) -> None:
    """The wheel link and joint of ``wheel`` at ``xyz`` in ``parent``, turned by ``yaw`` about z."""
    link_name = f"{wheel.name}_wheel"
    axle, across = wheel.hub_inertia
    link = tree.link(link_name, wheel.hub_mass, (0.0, 0.0, 0.0), (across, axle, across))
    joint = tree.joint(wheel.name, "continuous", parent, link_name, xyz, (0.0, 0.0, yaw), (0.0, 1.0, 0.0))
    if wheel.motor is not None:
        _limit(joint, wheel.motor.max_torque, wheel.motor.max_speed)
    across_axle = (math.pi / 2.0, 0.0, 0.0)  # a cylinder's z along the axle (y)
    rollers = wheel.rollers
    if rollers is None:
        for tag in ("visual", "collision"):
            _shape(link, tag, "cylinder", rpy=across_axle, radius=wheel.radius, length=wheel.width)
        return
    hub_radius = max(rollers.centre_radius - rollers.radius, 0.2 * wheel.radius)
    _shape(link, "visual", "cylinder", rpy=across_axle, radius=hub_radius, length=wheel.width)
    spin, side = rollers.inertia
    for roller in rollers.rollers:
        name = f"{wheel.name}_roller_{roller.row}_{roller.index}"
        along = _z_to(roller.axis)
        roller_link = tree.link(name, rollers.mass, (0.0, 0.0, 0.0), (side, side, spin), along)
        _shape(roller_link, "visual", "cylinder", rpy=along, radius=rollers.radius, length=2.0 * rollers.half_length)
        _shape(roller_link, "collision", "sphere", radius=rollers.radius)
        tree.joint(name, "continuous", link_name, name, roller.position, (0.0, 0.0, 0.0), roller.axis)


def _steered(tree: _Tree, wheel: WheelBody) -> None:
    """The fork on its steering joint ``NAME_steer``, then the wheel trailing the axis."""
    steering = wheel.steering
    assert steering is not None
    fork = f"{wheel.name}_fork"
    tree.link(fork, steering.fork_mass, (0.0, 0.0, 0.0), steering.fork_inertia)
    pivot = (steering.pivot[0], steering.pivot[1], wheel.radius)
    kind = "continuous" if steering.limits is None else "revolute"
    joint = tree.joint(f"{wheel.name}_steer", kind, BASE_LINK, fork, pivot, (0.0, 0.0, wheel.drive), (0.0, 0.0, 1.0))
    if steering.limits is not None:
        _limit(joint, steering.max_torque, steering.max_rate, *steering.limits)
    elif steering.actuated:
        _limit(joint, steering.max_torque, steering.max_rate)
    _wheel(tree, wheel, fork, (-steering.trail, 0.0, 0.0), 0.0)


def urdf(robot: PhysicalRobot | Robot, sensors: Sequence[Sensor] | None = None) -> str:
    """The URDF text of ``robot`` (a description, or a robot to :func:`describe`; module
    docstring) with a link for each IMU and lidar of ``sensors`` (default: a robot's own, none
    for a description)."""
    if sensors is None:
        sensors = robot.sensors if isinstance(robot, Robot) else ()
    if isinstance(robot, Robot):
        robot = describe(robot)
    tree = _Tree(robot.name)
    c = robot.chassis
    size: dict[str, float | str]
    base = tree.link(BASE_LINK, c.mass, c.com, c.inertia)
    if c.shape == "cylinder":
        radius, half = c.size
        size = {"radius": radius, "length": 2.0 * half}
    else:
        size = {"size": _vec(2.0 * s for s in c.size)}
    for tag in ("visual", "collision"):
        _shape(base, tag, c.shape, xyz=c.centre, **size)
    for wheel in robot.wheels:
        if wheel.steering is not None:
            _steered(tree, wheel)
        else:
            _wheel(tree, wheel, BASE_LINK, wheel.hub, wheel.drive)
    for sensor in sensors:
        if isinstance(sensor, (Imu, Lidar)):  # a bumper has no frame of its own
            tree.add("link", sensor.name)
            m = sensor.mount
            joint = tree.add("joint", f"{sensor.name}_joint", type="fixed")
            ET.SubElement(joint, "parent", link=BASE_LINK)
            ET.SubElement(joint, "child", link=sensor.name)
            ET.SubElement(joint, "origin", xyz=_vec((m.x, m.y, m.z)), rpy=_vec((0.0, 0.0, m.yaw)))
    ET.indent(tree.root)
    return '<?xml version="1.0"?>\n' + ET.tostring(tree.root, encoding="unicode") + "\n"
