"""The robot drawn in a viser scene from its physical description, and the scene around it.

:class:`RobotDrawing` builds, from :func:`omnikin.physics.description.describe` (the same
description the MuJoCo model is written from), a tree of scene nodes:

- ``/robot`` at the robot's pose ``(x, y, theta)`` (world frame, z up; ``docs/conventions.md``):
  the chassis (cylinder or box of the description);
- per wheel ``i`` (description order) ``/robot/wheel{i}`` at its steering pivot, turned about z
  by the steering angle (steered wheels and castors; fixed wheels sit at their hub, unturned),
  with the steering leg drawn from the chassis down to the hub;
- ``.../hub`` at the hub (the pivot's trail applied), turned about z to the wheel frame of the
  description (x along the drive direction, y along the axle, z up);
- ``.../hub/spin`` turned about the axle (y) by the wheel angle [rad]: tyre or hub disc, a
  marker that shows the turning, and the rollers of a Swedish wheel as one batched mesh of
  ellipsoids (semi-axes ``a`` along the spin axis, ``b`` across), each turned about its own
  spin axis by its roller angle;
- ``/robot/heading``: the heading arrow (:func:`arrow_mesh`), from the reference point along the
  body's +x, flat above everything else of the robot (:func:`robot_top`), so that every camera
  (from above, from behind, the mouse's) sees which way the robot faces.

:class:`RobotView` adds the odometry's pose beside it: ``/odometry`` with an arrow of its own
(narrower, magenta, a little higher: where the two poses agree, the truth's green shows round it).

Nodes are named by index, never by the file's wheel names (which may hold ``/``). The scene
around the robot (:func:`draw_ground`, :func:`draw_umbmark_square`, :class:`Trail`) is in the
world frame. Everything here only builds and moves nodes; what moves them is the caller's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import viser
import viser.transforms as vtf

from ..physics.description import PhysicalRobot, WheelBody
from ..world.model import Box, World
from ..world.plane import triangulate, wall_rects
from .live import Snapshot
from .panel import robot_extent

CHASSIS_COLOUR = (20, 160, 170)
TYRE_COLOUR = (45, 45, 45)
HUB_COLOUR = (170, 170, 170)
ROLLER_COLOUR = (235, 140, 40)
MARKER_COLOUR = (250, 210, 0)
LEG_COLOUR = (110, 110, 120)


def _wxyz_z(angle: float) -> np.ndarray:
    return vtf.SO3.from_z_radians(angle).wxyz


def _wxyz_y(angle: float) -> np.ndarray:
    return vtf.SO3.from_y_radians(angle).wxyz


AXLE_ALONG_Y = vtf.SO3.from_x_radians(math.pi / 2).wxyz
"""Turns viser's cylinders (height along z) to lie along a wheel's axle (y)."""


def ellipsoid_mesh(semi_axes: Sequence[float], segments: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an ellipsoid with ``semi_axes`` (x, y, z) [m], a UV sphere of
    ``segments`` around and ``segments / 2`` from pole to pole, scaled."""
    rings = max(segments // 2, 2)
    theta = np.linspace(0.0, math.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    body = np.stack([np.cos(t), np.sin(t) * np.cos(p), np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    vertices = np.vstack([[1.0, 0.0, 0.0], body, [-1.0, 0.0, 0.0]]) * np.asarray(semi_axes, dtype=float)
    last = len(vertices) - 1
    faces = []
    for j in range(segments):
        k = (j + 1) % segments
        faces.append((0, 1 + k, 1 + j))  # the cap at +x
        base = 1 + (rings - 2) * segments
        faces.append((last, base + j, base + k))  # the cap at -x
        for i in range(rings - 2):
            a, b = 1 + i * segments + j, 1 + i * segments + k
            faces.extend([(a, b, b + segments), (a, b + segments, a + segments)])
    return vertices.astype(np.float32), np.asarray(faces, dtype=np.int32)


def drawn_box(description: PhysicalRobot) -> np.ndarray:
    """Half sizes [m] of a box chassis as drawn: the description's box reaches the wheels' hubs,
    which would hide them from above; each side is drawn inside the wheels beside it (those
    farther out than half the box), unless that would leave less than 30 % of it."""
    chassis = description.chassis
    half = np.asarray(chassis.size, dtype=float).copy()
    centre = np.asarray(chassis.centre[:2], dtype=float)
    for axis in (0, 1):
        beside = [w for w in description.wheels if abs(w.hub[axis] - centre[axis]) >= 0.5 * half[axis]]
        if beside:
            inner = min(abs(w.hub[axis] - centre[axis]) - 0.6 * max(w.width, 0.2 * w.radius) for w in beside)
            if inner >= 0.3 * half[axis]:
                half[axis] = min(half[axis], inner)
    return half


def roller_base_rotations(wheel: WheelBody) -> np.ndarray:
    """Rotation matrices (n, 3, 3) taking a roller's own x to its spin axis in the wheel frame
    at wheel angle 0: ``R_y(psi) R_z(gamma)``, ``psi`` the roller's angle about the axle (from its
    centre ``R_y(psi) (0, y, -c)``) and ``gamma`` the roller angle (description, "Rollers")."""
    rollers = wheel.rollers
    assert rollers is not None
    centres = np.array([r.position for r in rollers.rollers])
    psi = np.arctan2(-centres[:, 0], -centres[:, 2])
    ry = vtf.SO3.from_y_radians(psi).as_matrix()
    rz = vtf.SO3.from_z_radians(rollers.angle).as_matrix()
    return ry @ rz


def robot_top(description: PhysicalRobot) -> float:
    """Height [m] of the highest point of the robot as drawn: the chassis' top, the wheels'
    tops (hub height plus radius)."""
    chassis = description.chassis
    return max([chassis.centre[2] + chassis.size[-1]] + [w.hub[2] + w.radius for w in description.wheels])


def arrow_mesh(length: float, width: float, thickness: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a flat arrow along +x from the origin: a shaft ``width`` [m]
    wide and a head ``2.5 width`` wide and ``0.3 length`` long, ending at ``x = length``, a
    slab ``thickness`` [m] thick from ``z = 0`` up. Two convex prisms (shaft, head)."""
    head = 0.3 * length
    shaft = [(0.0, -width / 2), (length - head, -width / 2), (length - head, width / 2), (0.0, width / 2)]
    tip = [(length - head, -1.25 * width), (length, 0.0), (length - head, 1.25 * width)]
    vertices: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []
    for outline in (shaft, tip):  # counter-clockwise seen from above
        n, base = len(outline), len(vertices)
        vertices += [(x, y, 0.0) for x, y in outline] + [(x, y, thickness) for x, y in outline]
        faces += [(base, base + k + 1, base + k) for k in range(1, n - 1)]  # bottom, facing down
        faces += [(base + n, base + n + k, base + n + k + 1) for k in range(1, n - 1)]  # top, facing up
        for k in range(n):
            j = (k + 1) % n
            faces += [(base + k, base + j, base + n + j), (base + k, base + n + j, base + n + k)]
    return np.asarray(vertices, dtype=np.float32), np.asarray(faces, dtype=np.int32)


HEADING_LENGTH = 1.3
"""Length of the heading arrow in robot reaches (:func:`robot_extent`): its head shows beyond
the wheels."""


def add_heading_arrow(
    scene: viser.SceneApi, name: str, description: PhysicalRobot, colour, *, narrow=False, opacity=None
):
    """The heading arrow of :func:`arrow_mesh` at ``name`` (a child of the pose's frame), sized
    to the robot and lying just above :func:`robot_top`; ``narrow``: the odometry's, half as
    wide and a slab higher."""
    reach = robot_extent(description)
    thickness = 0.04 * reach
    width = 0.16 * reach * (0.5 if narrow else 1.0)
    vertices, faces = arrow_mesh(HEADING_LENGTH * reach, width, thickness)
    z = robot_top(description) + (2.5 if narrow else 1.0) * thickness
    return scene.add_mesh_simple(
        name, vertices, faces, color=colour, position=(0.0, 0.0, z), side="double", opacity=opacity, cast_shadow=False
    )


TRUTH_COLOUR = (30, 160, 60)
"""The true pose: its trail and the robot's heading arrow."""
ODOMETRY_COLOUR = (200, 60, 200)
"""The odometry: its trail and its heading arrow."""


class RobotDrawing:
    """The robot's nodes in ``scene`` (module docstring); :meth:`update` moves them.
    ``heading_colour``: the heading arrow's colour."""

    def __init__(
        self,
        scene: viser.SceneApi,
        description: PhysicalRobot,
        root: str = "/robot",
        opacity=None,
        heading_colour=None,
    ):
        self.description = description
        self.root = scene.add_frame(root, show_axes=False)
        self.heading = add_heading_arrow(
            scene, f"{root}/heading", description, heading_colour or TRUTH_COLOUR, opacity=opacity
        )
        chassis = description.chassis
        if chassis.shape == "cylinder":
            radius, half_height = chassis.size
            # drawn inside the wheels (the description's radius reaches the mounting points,
            # which would hide the wheels from above)
            inner = min(math.hypot(w.hub[0], w.hub[1]) - 0.6 * max(w.width, 0.2 * w.radius) for w in description.wheels)
            radius = radius if inner <= 0.3 * radius else min(radius, inner)
            scene.add_cylinder(
                f"{root}/chassis",
                radius=radius,
                height=2 * half_height,
                color=CHASSIS_COLOUR,
                position=chassis.centre,
                opacity=opacity,
            )
        else:
            scene.add_box(
                f"{root}/chassis",
                color=CHASSIS_COLOUR,
                dimensions=2 * drawn_box(description),
                position=chassis.centre,
                opacity=opacity,
            )
        underside = chassis.centre[2] - chassis.size[-1]
        self.pivots: list[viser.FrameHandle] = []
        self.spins: list[viser.FrameHandle] = []
        self.rollers: list[tuple[viser.BatchedMeshHandle, np.ndarray] | None] = []
        for i, wheel in enumerate(description.wheels):
            name = f"{root}/wheel{i}"
            steering = wheel.steering
            hub = np.asarray(wheel.hub, dtype=float)
            pivot = np.array([*steering.pivot, hub[2]]) if steering is not None else hub
            self.pivots.append(scene.add_frame(name, show_axes=False, position=pivot))
            if steering is not None:
                top = max(underside, hub[2])
                scene.add_box(
                    f"{name}/leg",
                    color=LEG_COLOUR,
                    dimensions=(0.15 * wheel.radius, 0.15 * wheel.radius, top - hub[2] + wheel.radius * 0.3),
                    position=(0.0, 0.0, (top - hub[2] + wheel.radius * 0.3) / 2),
                    opacity=opacity,
                )
            hub_node = scene.add_frame(f"{name}/hub", show_axes=False, position=hub - pivot, wxyz=_wxyz_z(wheel.drive))
            del hub_node  # placed once; it moves with its parents
            spin = scene.add_frame(f"{name}/hub/spin", show_axes=False)
            self.spins.append(spin)
            self.rollers.append(self._draw_wheel(scene, f"{name}/hub/spin", wheel, opacity))

    def _draw_wheel(self, scene, name: str, wheel: WheelBody, opacity):
        width = max(wheel.width, 0.2 * wheel.radius)
        rollers = wheel.rollers
        if rollers is None:
            scene.add_cylinder(
                f"{name}/tyre", radius=wheel.radius, height=width, color=TYRE_COLOUR, wxyz=AXLE_ALONG_Y, opacity=opacity
            )
            marker_radius = wheel.radius
        else:
            hub_radius = max(rollers.centre_radius - rollers.radius, 0.3 * rollers.centre_radius)
            scene.add_cylinder(
                f"{name}/disc",
                radius=hub_radius,
                height=0.6 * width,
                color=HUB_COLOUR,
                wxyz=AXLE_ALONG_Y,
                opacity=opacity,
            )
            marker_radius = hub_radius
        scene.add_box(
            f"{name}/marker",
            color=MARKER_COLOUR,
            dimensions=(0.15 * marker_radius, width * 1.02, 0.9 * marker_radius),
            position=(0.0, 0.0, 0.5 * marker_radius),
            opacity=opacity,
        )
        if rollers is None:
            return None
        vertices, faces = ellipsoid_mesh((rollers.half_length, rollers.radius, rollers.radius))
        base = roller_base_rotations(wheel)
        centres = np.array([r.position for r in rollers.rollers], dtype=float)
        handle = scene.add_batched_meshes_simple(
            f"{name}/rollers",
            vertices,
            faces,
            batched_wxyzs=vtf.SO3.from_matrix(base).wxyz,
            batched_positions=centres,
            batched_colors=ROLLER_COLOUR,
            lod="off",
            opacity=opacity,
        )
        return handle, base

    def update(self, pose, wheel_angles, steer_angles=None, roller_angles=None) -> None:
        """Move the robot: ``pose`` ``(x, y, theta)`` [m, m, rad] in the world frame;
        ``wheel_angles`` [rad] per wheel (description order; castors included); ``steer_angles``
        [rad] per wheel relative to its mounting drive direction (NaN or None: not steered);
        ``roller_angles``: per wheel an array of its rollers' angles [rad] about their spin
        axes (None: leave them)."""
        x, y, theta = (float(v) for v in pose)
        self.root.position = (x, y, 0.0)
        self.root.wxyz = _wxyz_z(theta)
        for i, spin in enumerate(self.spins):
            spin.wxyz = _wxyz_y(float(wheel_angles[i]))
            if steer_angles is not None and math.isfinite(steer_angles[i]):
                self.pivots[i].wxyz = _wxyz_z(float(steer_angles[i]))
            drawn = self.rollers[i]
            if drawn is not None and roller_angles is not None and roller_angles[i] is not None:
                handle, base = drawn
                turn = vtf.SO3.from_x_radians(np.asarray(roller_angles[i], dtype=float)).as_matrix()
                handle.batched_wxyzs = vtf.SO3.from_matrix(base @ turn).wxyz


def draw_world(scene: viser.SceneApi, extent: float, umbmark_side: float) -> None:
    """Lights, a ground grid ``2 extent`` [m] wide (10 cm cells) and the UMBmark squares of side
    ``umbmark_side`` [m] from the origin (0: none)."""
    plain_lights(scene)
    draw_ground(scene, extent, 0.1)
    if umbmark_side > 0:
        draw_umbmark_square(scene, umbmark_side)


WALL_COLOUR = (190, 184, 174)
FIXED_COLOUR = (140, 102, 76)
MOVABLE_COLOUR = (204, 115, 51)
PATCH_COLOUR = (90, 140, 217)
MARK_COLOUR = (217, 166, 25)


def _yaw_wxyz(yaw: float) -> tuple[float, float, float, float]:
    return (math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0))


class WorldDrawing:
    """A world's walls, obstacles, friction patches and floor marks (``docs/world.md``) under
    the scene node ``/world``, placed at ``origin`` (x, y, theta): the world frame's pose in the
    scene's frame, which is the odometry's (where the robot started: the inverse of the world's
    start pose). Movable obstacles are moved by :meth:`move` (the physics engine pushes them)."""

    def __init__(self, scene: viser.SceneApi, world: World, origin):
        x, y, theta = (float(v) for v in origin)
        scene.add_frame("/world", show_axes=False, position=(x, y, 0.0), wxyz=_yaw_wxyz(theta))
        for i, wall in enumerate(world.walls):
            for k, (cx, cy, hx, hy, yaw) in enumerate(wall_rects(np.asarray(wall.points, dtype=float), wall.thickness)):
                scene.add_box(
                    f"/world/wall{i}/{k}",
                    color=WALL_COLOUR,
                    dimensions=(2 * hx, 2 * hy, wall.height),
                    position=(cx, cy, wall.height / 2.0),
                    wxyz=_yaw_wxyz(yaw),
                )
        self.obstacles: list[viser.BoxHandle | viser.CylinderHandle] = []
        for j, obstacle in enumerate(world.obstacles):
            colour = FIXED_COLOUR if obstacle.fixed else MOVABLE_COLOUR
            height = obstacle.height
            where = (*obstacle.center, height / 2.0)
            handle: viser.BoxHandle | viser.CylinderHandle
            if isinstance(obstacle, Box):
                handle = scene.add_box(
                    f"/world/obstacle{j}",
                    color=colour,
                    dimensions=obstacle.size,
                    position=where,
                    wxyz=_yaw_wxyz(obstacle.yaw),
                )
            else:
                handle = scene.add_cylinder(
                    f"/world/obstacle{j}", radius=obstacle.radius, height=height, color=colour, position=where
                )
            self.obstacles.append(handle)
        for i, patch in enumerate(world.floor.patches):
            corners = np.asarray(patch.polygon, dtype=float)
            vertices = np.column_stack([corners, np.full(len(corners), 0.001)])
            scene.add_mesh_simple(
                f"/world/patch{i}",
                vertices.astype(np.float32),
                triangulate(corners).astype(np.uint32),
                color=PATCH_COLOUR,
                opacity=0.6,
                side="double",
            )
        for i, mark in enumerate(world.marks):
            points = np.column_stack([np.asarray(mark.points, dtype=float), np.full(len(mark.points), 0.002)])
            segments = np.stack([points[:-1], points[1:]], axis=1)
            scene.add_line_segments(f"/world/mark{i}", segments, colors=MARK_COLOUR, thickness=0.02)
        self.heights = [o.height for o in world.obstacles]

    def move(self, poses) -> None:
        """Put each obstacle at its pose ``(x, y, yaw)`` [m, m, rad], world frame (``poses``
        ``(n_obstacles, 3)``)."""
        for handle, height, (x, y, yaw) in zip(self.obstacles, self.heights, poses, strict=True):
            handle.position = (float(x), float(y), height / 2.0)
            handle.wxyz = _yaw_wxyz(float(yaw))


class RobotView:
    """The robot (:class:`RobotDrawing`, its heading arrow green), its odometry's pose
    (``/odometry``: a narrower magenta arrow, module docstring) and the trails of its true pose
    (green) and odometry (magenta); ``trail`` passes options to both :class:`Trail` s."""

    def __init__(self, scene: viser.SceneApi, description: PhysicalRobot, **trail):
        self.drawing = RobotDrawing(scene, description)
        self.odometry_frame = scene.add_frame("/odometry", show_axes=False)
        self.odometry_arrow = add_heading_arrow(scene, "/odometry/heading", description, ODOMETRY_COLOUR, narrow=True)
        self.trails = {
            "truth": Trail(scene, "/trails/truth", TRUTH_COLOUR, **trail),
            "odometry": Trail(scene, "/trails/odometry", ODOMETRY_COLOUR, **trail),
        }

    def clear_trails(self) -> None:
        for trail in self.trails.values():
            trail.clear()

    def show(self, s: Snapshot) -> None:
        """The robot at ``s``'s true pose with its joints, the odometry's frame at its pose."""
        self.drawing.update(s.truth, s.wheel_angles, s.steer, s.roller_angles)
        x, y, theta = s.odometry
        self.odometry_frame.position = (x, y, 0.0)
        self.odometry_frame.wxyz = (math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2))


def plain_lights(scene: viser.SceneApi) -> None:
    """An ambient light and a sun instead of viser's environment map and default lights:
    image-based lighting costs a browser without a GPU seconds per page load, and the default
    lights' shadows made every frame of software WebGL 4 to 8 times slower (2.4 s instead of
    0.3 s a frame on this loaded 2-core machine); plain lights show the robot's colours as they
    are."""
    scene.configure_environment_map(hdri=None)
    scene.configure_default_lights(enabled=False, cast_shadow=False)
    scene.add_light_ambient("/lights/ambient", intensity=0.6)
    scene.add_light_directional("/lights/sun", intensity=1.2, position=(2.0, -3.0, 5.0))


MAX_GROUND = 1000.0
"""Largest half width [m] of the ground grid: a run that goes farther (or a hostile file's
coordinates) gets a grid this wide, not one without bound."""
SCALE_LABELS = 10
"""Most labels along the ground's scale."""


def draw_ground(scene: viser.SceneApi, extent: float, cell: float) -> None:
    """A ground grid in the floor plane, ``2 extent`` [m] wide (at most ``2 MAX_GROUND``), lines
    every ``cell`` [m] (coarser by tens so that a side has at most 1000 cells) and a darker line
    every metre (likewise), with at most :data:`SCALE_LABELS` labels of the scale along +x at
    1, 2 or 5 times a power of ten metres."""
    extent = min(float(extent), MAX_GROUND) if math.isfinite(extent) and extent > 0 else MAX_GROUND
    while 2 * extent / cell > 1000:
        cell *= 10
    section = max(1.0, cell * 10) if cell >= 1.0 else 1.0
    scene.add_grid(
        "/ground",
        width=2 * extent,
        height=2 * extent,
        plane="xy",
        cell_size=cell,
        section_size=section,
        infinite_grid=False,
    )
    step = max(1.0, scale_step(extent, SCALE_LABELS))
    for k in range(1, min(SCALE_LABELS, int(extent / step)) + 1):
        scene.add_label(f"/ground/scale{k}", f"{k * step:g} m", position=(k * step, -0.05, 0.0), font_screen_scale=0.7)


def scale_step(extent: float, labels: int) -> float:
    """The smallest of 1, 2, 5 times a power of ten [m] that puts at most ``labels`` marks in ``extent``."""
    power = 10.0 ** math.floor(math.log10(max(extent / labels, 1e-9)))
    return next(m * power for m in (1.0, 2.0, 5.0, 10.0) if extent / (m * power) <= labels)


def draw_umbmark_square(scene: viser.SceneApi, side: float, start=(0.0, 0.0, 0.0)) -> None:
    """The two UMBmark squares of side ``side`` [m] from ``start`` ``(x, y, theta)``: first leg
    along the heading, clockwise (turning right) in red, counter-clockwise in blue."""
    x0, y0, th = (float(v) for v in start)
    c, s = math.cos(th), math.sin(th)
    for name, sign, colour in (("cw", -1.0, (220, 60, 60)), ("ccw", 1.0, (60, 90, 220))):
        corners = np.array([(0, 0), (side, 0), (side, sign * side), (0, sign * side), (0, 0)], dtype=float)
        world = np.column_stack(
            [x0 + c * corners[:, 0] - s * corners[:, 1], y0 + s * corners[:, 0] + c * corners[:, 1]]
        )
        points = np.column_stack([world, np.full(len(world), 0.002)])
        segments = np.stack([points[:-1], points[1:]], axis=1)
        scene.add_line_segments(f"/umbmark/{name}", segments, colors=colour, thickness=0.01)


class Trail:
    """A polyline of poses in the floor plane, kept to the last ``capacity`` points and redrawn
    by :meth:`flush` (one message for the whole line)."""

    def __init__(self, scene: viser.SceneApi, name: str, colour, capacity: int = 20000, spacing: float = 0.005):
        self.scene = scene
        self.name = name
        self.colour = colour
        self.capacity = capacity
        self.spacing = spacing
        self.points: list[tuple[float, float]] = []
        self._added = 0  # points ever added: a trimmed line has as many points but new ones
        self._drawn = 0
        self._handle: viser.LineSegmentsHandle | None = None

    def add(self, x: float, y: float) -> None:
        """Append ``(x, y)`` [m] when it is ``spacing`` from the last point."""
        if self.points and math.hypot(x - self.points[-1][0], y - self.points[-1][1]) < self.spacing:
            return
        self.points.append((x, y))
        self._added += 1
        if len(self.points) > self.capacity:
            del self.points[: len(self.points) - self.capacity]

    def clear(self) -> None:
        self.points.clear()
        self.flush()

    def flush(self) -> None:
        """Redraw the line when points were added since the last flush."""
        if len(self.points) < 2:
            if self._handle is not None:
                self._handle.remove()
                self._handle = None
            self._drawn = self._added
            return
        if self._added == self._drawn and self._handle is not None:
            return
        p = np.array(self.points)
        points = np.column_stack([p, np.full(len(p), 0.003)])
        segments = np.stack([points[:-1], points[1:]], axis=1)
        if self._handle is None:
            self._handle = self.scene.add_line_segments(self.name, segments, colors=self.colour, thickness=0.006)
        else:
            self._handle.points = segments
        self._drawn = self._added
