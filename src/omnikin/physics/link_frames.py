"""Where every link of a URDF is, given its joints' positions: the transforms ``/tf`` carries.

rviz2's RobotModel draws each link at the TF frame of the link's name; without
``robot_state_publisher`` the node publishes those frames itself (:mod:`omnikin.ros.node`).
This module is the URDF's kinematics in NumPy (no ROS): read the joints of a URDF text
(:func:`urdf_joints`), then :class:`LinkFrames` turns joint positions into the pose of every
child link in its parent link, all joints at once.

URDF (ROS wiki "urdf/XML/joint"): a joint's ``<origin xyz rpy>`` places the joint frame in the
parent link's frame, rotated by fixed-axis roll-pitch-yaw, ``R0 = Rz(yaw) Ry(pitch) Rx(roll)``;
the child link's frame is the joint frame moved by the joint position ``q`` along the unit
``<axis>`` ``k`` (given in the joint frame):

* ``revolute`` / ``continuous``: rotated by ``q`` [rad] about ``k``, the origin kept:
  ``p = xyz``, ``R = R0 Rot(k, q)``;
* ``prismatic``: translated by ``q`` [m] along ``k``: ``p = xyz + R0 k q``, ``R = R0``;
* ``fixed``: ``p = xyz``, ``R = R0`` whatever ``q`` (published once, on ``/tf_static``).

Rotations are unit quaternions ``(x, y, z, w)`` as ``geometry_msgs/Quaternion`` holds them;
``Rot(k, q)`` is ``(k sin(q/2), cos(q/2))`` and ``R0`` the product ``qz(yaw) qy(pitch)
qx(roll)`` (Hamilton product, :func:`quaternion_multiply`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..common.messages import shorten
from ..errors import InputError

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
"""Joint types :class:`LinkFrames` moves (floating and planar joints have no single position)."""


@dataclass(frozen=True)
class UrdfJoint:
    """One ``<joint>``: ``name``, ``type``, ``parent`` and ``child`` link names, ``xyz`` [m] and
    ``rpy`` [rad] of its origin in the parent link, unit ``axis`` in the joint frame."""

    name: str
    type: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]

    @property
    def movable(self) -> bool:
        return self.type != "fixed"


def _triple(element: ET.Element | None, attr: str, default: tuple, where: str) -> tuple[float, float, float]:
    if element is None or element.get(attr) is None:
        return default
    text = element.get(attr, "")
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        values = ()
    if len(values) != 3 or not all(np.isfinite(values)):
        raise InputError(f"{where}: {attr} must be three finite numbers, got {shorten(text)}")
    x, y, z = values
    return x, y, z


def urdf_joints(text: str) -> list[UrdfJoint]:
    """The joints of URDF ``text``, in document order (a missing origin is the identity, a
    missing axis ``1 0 0``, as URDF says); the axis is normalised."""
    root = ET.fromstring(text)
    joints = []
    for element in root.iter("joint"):
        name = element.get("name", "")
        where = f"URDF joint {shorten(name)}"
        kind = element.get("type", "")
        if kind not in JOINT_TYPES:
            raise InputError(f"{where}: type {shorten(kind)} is not one of {', '.join(JOINT_TYPES)}")
        parent, child = element.find("parent"), element.find("child")
        if parent is None or child is None or not parent.get("link") or not child.get("link"):
            raise InputError(f"{where}: needs a parent and a child link")
        origin = element.find("origin")
        ax, ay, az = _triple(element.find("axis"), "xyz", (1.0, 0.0, 0.0), where)
        norm = math.hypot(ax, ay, az)  # no overflow on the way
        if not (norm > 0.0 and np.isfinite(norm)):
            raise InputError(f"{where}: the axis must have a finite, non-zero length")
        joints.append(
            UrdfJoint(
                name,
                kind,
                parent.get("link", ""),
                child.get("link", ""),
                _triple(origin, "xyz", (0.0, 0.0, 0.0), where),
                _triple(origin, "rpy", (0.0, 0.0, 0.0), where),
                (ax / norm, ay / norm, az / norm),
            )
        )
    return joints


def quaternion_multiply(a, b) -> np.ndarray:
    """Hamilton product ``a b`` of quaternions ``(..., 4)`` stored ``(x, y, z, w)``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def axis_angle_quaternion(axis, angle) -> np.ndarray:
    """Quaternions ``(..., 4)`` of rotations by ``angle`` ``(...)`` [rad] about unit ``axis`` ``(..., 3)``."""
    half = 0.5 * np.asarray(angle, dtype=float)
    return np.concatenate([np.asarray(axis, dtype=float) * np.sin(half)[..., None], np.cos(half)[..., None]], axis=-1)


def rpy_quaternion(rpy) -> np.ndarray:
    """Quaternions ``(..., 4)`` of URDF's fixed-axis roll-pitch-yaw ``(..., 3)`` [rad]:
    ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    rpy = np.asarray(rpy, dtype=float)
    eye = np.eye(3)
    q = axis_angle_quaternion(eye[2], rpy[..., 2])
    q = quaternion_multiply(q, axis_angle_quaternion(eye[1], rpy[..., 1]))
    return quaternion_multiply(q, axis_angle_quaternion(eye[0], rpy[..., 0]))


class LinkFrames:
    """Child-in-parent transforms of every joint of a URDF (module docstring), vectorised.

    ``movable`` and ``fixed`` are the joints by kind, in document order; :meth:`moved` takes the
    positions of the movable ones in that order."""

    def __init__(self, joints: Sequence[UrdfJoint]):
        self.movable = [j for j in joints if j.movable]
        self.fixed = [j for j in joints if not j.movable]
        self.movable_names = [j.name for j in self.movable]
        m = self.movable
        self._xyz = np.array([j.xyz for j in m], dtype=float).reshape(-1, 3)
        self._origin = rpy_quaternion(np.array([j.rpy for j in m], dtype=float).reshape(-1, 3))
        self._axis = np.array([j.axis for j in m], dtype=float).reshape(-1, 3)
        self._prismatic = np.array([j.type == "prismatic" for j in m], dtype=bool)
        # R0 k: a prismatic joint's direction of travel in the parent link
        self._travel = quaternion_rotate(self._origin, self._axis)

    def index_in(self, names: Sequence[str]) -> np.ndarray:
        """Where each movable joint is in ``names`` (a ``joint_states`` message's): ``moved``
        then takes ``positions[index]``; a movable joint missing from ``names`` is an error."""
        where = {name: i for i, name in enumerate(names)}
        missing = [n for n in self.movable_names if n not in where]
        if missing:
            raise InputError(f"joint positions lack the URDF joint(s) {shorten(missing)}")
        return np.array([where[n] for n in self.movable_names], dtype=int)

    def moved(self, positions) -> tuple[np.ndarray, np.ndarray]:
        """``(translations (n, 3) [m], rotations (n, 4))`` of the movable joints' child links in
        their parent links at joint ``positions`` ``(n,)`` [rad or m]."""
        q = np.asarray(positions, dtype=float)
        if q.shape != (len(self.movable),):
            raise InputError(f"{len(self.movable)} movable joints, {q.size} positions")
        turn = np.where(self._prismatic, 0.0, q)
        rotations = quaternion_multiply(self._origin, axis_angle_quaternion(self._axis, turn))
        translations = self._xyz + self._travel * np.where(self._prismatic, q, 0.0)[:, None]
        return translations, rotations

    def still(self) -> tuple[np.ndarray, np.ndarray]:
        """``(translations (m, 3), rotations (m, 4))`` of the fixed joints' child links."""
        xyz = np.array([j.xyz for j in self.fixed], dtype=float).reshape(-1, 3)
        return xyz, rpy_quaternion(np.array([j.rpy for j in self.fixed], dtype=float).reshape(-1, 3))


def quaternion_rotate(q, v) -> np.ndarray:
    """Vectors ``(..., 3)`` ``v`` rotated by unit quaternions ``(..., 4)`` ``q``: ``q v q*``."""
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)
