"""The world around a robot: floor, friction patches, walls, obstacles, floor marks, start pose.

Pure data, checked as it is built (``docs/world.md``). Frames and units: the world frame is
REP 105's ``map``/``odom`` fixed on the floor, x and y on it, z up; lengths in m, angles in rad
here (degrees only in world files, in fields ending in ``_deg``, and in the third number of
``start``), masses in kg.

A **wall** is a polyline of straight segments on the floor, each a box of the wall's
``thickness`` centred on the segment and of its ``height``, lengthened by half the thickness at
both ends so that the segments of a polyline close their corners (a square room is closed).
An **obstacle** is a box (``size`` the full extents x, y, z in its own frame, turned by
``yaw`` about z) or an upright cylinder, standing on the floor, ``fixed`` or movable with a
``mass``. A **patch** is a simple polygon of the floor with its own friction (a slippery zone).
A **mark** is a polyline painted on the floor (drawn, never touched).

Every problem raises :class:`~omnikin.errors.WorldFileError` naming the body (``wall #2``) and
the field, with the attributes the file reader uses to add the file and the line.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..common.arrays import range_problem
from ..common.messages import shorten
from ..errors import WorldFileError
from ..kinematics.physical import FRICTION_RANGE, MASS_RANGE
from ..kinematics.robot import robot_name_problem
from .plane import (
    overlapping_polygons,
    shape_gaps,
    simple_polygon_problem,
    wall_rects,
)

COORDINATE_LIMIT = 1000.0
"""Largest ``|x|`` or ``|y|`` [m] of any point of a world (a 2 km square)."""
THICKNESS_RANGE = (1e-3, 10.0)
"""Thickness of a wall [m]."""
HEIGHT_RANGE = (1e-3, 10.0)
"""Height of a wall or obstacle [m]."""
SIZE_RANGE = (1e-3, 100.0)
"""Each extent of a box, the radius of a cylinder [m]."""
FLOOR_SIZE_RANGE = (0.1, 2.0 * COORDINATE_LIMIT)
"""Each side of the floor [m]."""
MAX_WALL_SEGMENTS = 2000
"""Most wall segments of a world, all walls together (each is a body of the physics model and a
shape every lidar beam is tested against)."""
MAX_OBSTACLES = 1000
"""Most obstacles of a world."""
MAX_PATCHES = 100
"""Most friction patches of a world."""
MAX_PATCH_POINTS = 100
"""Most corners of one patch."""
MAX_MARKS = 100
"""Most floor marks of a world."""
MAX_MARK_POINTS = 1000
"""Most points of one floor mark."""
MIN_SEGMENT = 1e-3
"""Shortest wall segment, mark segment or patch edge [m]: two points closer are one point written
twice."""
MAX_NAME = 128
"""Longest name of a world or one of its bodies."""

DEFAULT_THICKNESS = 0.05
"""Thickness of a wall that does not give one [m]."""
DEFAULT_HEIGHT = 0.3
"""Height of a wall or obstacle that does not give one [m]."""
FLOOR_MARGIN = 1.0
"""Margin [m] around everything of a world whose floor does not give its size."""


def _fail(problem: str, field: str | None = None, group: str | None = None, body: int | None = None) -> WorldFileError:
    """The error of ``problem``, prefixed by the body and the field it concerns."""
    label = _label(group, body)
    parts = [p for p in (label, f"field {field!r}" if field else None) if p]
    return WorldFileError(": ".join([*parts, problem]), field=field, group=group, body=body)


_GROUP_NOUNS = {"walls": "wall", "obstacles": "obstacle", "patches": "patch", "marks": "mark"}


def _label(group: str | None, body: int | None) -> str | None:
    if group is None:
        return None
    noun = _GROUP_NOUNS.get(group, group)
    return f"{noun} #{body + 1}" if body is not None else noun


def _number(value: Any, limits: tuple[float, float], unit: str, field: str, group=None, body=None) -> float:
    """``value`` as a float in ``limits``, else the error naming the field."""
    problem = range_problem(value, *limits, unit)
    if problem:
        raise _fail(problem, field, group, body)
    return float(value)


def _name(value: Any, default: str, group=None, body=None) -> str:
    if value is None:
        return default
    problem = robot_name_problem(value)
    if problem:
        raise _fail(problem, "name", group, body)
    return str(value)


def _point(value: Any, field: str, group=None, body=None) -> tuple[float, float]:
    """``value`` as a point ``(x, y)`` [m] on the floor."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise _fail(f"must be a point [x, y] in m, got {shorten(value)}", field, group, body)
    limits = (-COORDINATE_LIMIT, COORDINATE_LIMIT)
    return (_number(value[0], limits, "m", field, group, body), _number(value[1], limits, "m", field, group, body))


def _points(value: Any, field: str, least: int, most: int, group=None, body=None) -> tuple[tuple[float, float], ...]:
    """``value`` as ``least`` to ``most`` points, consecutive ones at least :data:`MIN_SEGMENT` apart."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or not least <= len(value) <= most:
        count = f"{len(value)} points" if isinstance(value, (list, tuple)) else shorten(value)
        raise _fail(f"must be a list of {least} to {most} points [x, y] in m, got {count}", field, group, body)
    points = tuple(_point(p, field, group, body) for p in value)
    for i in range(1, len(points)):
        if math.dist(points[i - 1], points[i]) < MIN_SEGMENT:
            raise _fail(
                f"points {i - 1} and {i} (from 0) are closer than {MIN_SEGMENT * 1e3:g} mm: write a point once",
                field,
                group,
                body,
            )
    return points


def _yaw(value: Any, field: str, group=None, body=None) -> float:
    """A yaw given in rad, within one turn either way (files give degrees: the reader converts)."""
    return _number(value, (-2.0 * math.pi, 2.0 * math.pi), "rad", field, group, body)


def _flag(value: Any, field: str, group=None, body=None) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise _fail(f"must be true or false, got {shorten(value)}", field, group, body)
    return bool(value)


@dataclass(frozen=True)
class Wall:
    """A wall: ``points`` ``(n, 2)`` [m] of its polyline (n >= 2), ``thickness`` and ``height`` [m]."""

    points: tuple[tuple[float, float], ...]
    thickness: float = DEFAULT_THICKNESS
    height: float = DEFAULT_HEIGHT
    name: str = ""

    def check(self, index: int) -> Wall:
        """This wall with its fields checked (as wall ``index``, from 0) and its name defaulted."""
        group = "walls"
        return Wall(
            _points(self.points, "points", 2, MAX_WALL_SEGMENTS + 1, group, index),
            _number(self.thickness, THICKNESS_RANGE, "m", "thickness", group, index),
            _number(self.height, HEIGHT_RANGE, "m", "height", group, index),
            _name(self.name or None, f"wall {index + 1}", group, index),
        )

    @property
    def segments(self) -> np.ndarray:
        """``(n - 1, 2, 2)`` [m]: each segment's start and end point."""
        p = np.asarray(self.points, dtype=float)
        return np.stack([p[:-1], p[1:]], axis=1)


@dataclass(frozen=True)
class Box:
    """A box obstacle standing on the floor: ``center`` (x, y) [m], ``size`` full extents
    (x, y, z) [m] in its own frame, turned by ``yaw`` [rad]; ``fixed``, or movable of ``mass`` [kg]."""

    center: tuple[float, float]
    size: tuple[float, float, float]
    yaw: float = 0.0
    fixed: bool = True
    mass: float | None = None
    name: str = ""

    shape = "box"

    def check(self, index: int) -> Box:
        """This box with its fields checked (as obstacle ``index``, from 0) and its name defaulted."""
        group = "obstacles"
        size = self.size.tolist() if isinstance(self.size, np.ndarray) else self.size
        if not isinstance(size, (list, tuple)) or len(size) != 3:
            raise _fail(f"must be the extents [x, y, z] in m, got {shorten(size)}", "size", group, index)
        fixed, mass = _fixed_mass(self.fixed, self.mass, group, index)
        return Box(
            _point(self.center, "center", group, index),
            tuple(_number(v, SIZE_RANGE, "m", "size", group, index) for v in size),  # type: ignore[arg-type]
            _yaw(self.yaw, "yaw", group, index),
            fixed,
            mass,
            _name(self.name or None, f"box {index + 1}", group, index),
        )

    @property
    def height(self) -> float:
        """Height above the floor [m]."""
        return self.size[2]


@dataclass(frozen=True)
class Cylinder:
    """An upright cylinder obstacle on the floor: ``center`` (x, y), ``radius`` and ``height`` [m];
    ``fixed``, or movable of ``mass`` [kg]."""

    center: tuple[float, float]
    radius: float
    height: float = DEFAULT_HEIGHT
    fixed: bool = True
    mass: float | None = None
    name: str = ""

    shape = "cylinder"

    def check(self, index: int) -> Cylinder:
        """This cylinder with its fields checked (as obstacle ``index``, from 0), name defaulted."""
        group = "obstacles"
        fixed, mass = _fixed_mass(self.fixed, self.mass, group, index)
        return Cylinder(
            _point(self.center, "center", group, index),
            _number(self.radius, SIZE_RANGE, "m", "radius", group, index),
            _number(self.height, HEIGHT_RANGE, "m", "height", group, index),
            fixed,
            mass,
            _name(self.name or None, f"cylinder {index + 1}", group, index),
        )


def _fixed_mass(fixed: Any, mass: Any, group: str, index: int) -> tuple[bool, float | None]:
    """A fixed obstacle has no mass; a movable one needs one."""
    fixed = _flag(fixed, "fixed", group, index)
    if fixed and mass is not None:
        raise _fail("a fixed obstacle has no mass: leave 'mass' out, or say fixed: false", "mass", group, index)
    if not fixed and mass is None:
        raise _fail("a movable obstacle (fixed: false) needs its mass in kg", "mass", group, index)
    return fixed, None if fixed else _number(mass, MASS_RANGE, "kg", "mass", group, index)


Obstacle = Box | Cylinder
"""An obstacle of the world."""


@dataclass(frozen=True)
class Patch:
    """A zone of the floor with its own ``friction``: ``polygon`` ``(n, 2)`` [m], a simple polygon
    (n >= 3, edges that do not cross), either orientation."""

    polygon: tuple[tuple[float, float], ...]
    friction: float
    name: str = ""

    def check(self, index: int) -> Patch:
        """This patch with its fields checked (as patch ``index``, from 0), name defaulted."""
        group = "patches"
        polygon = _points(self.polygon, "polygon", 3, MAX_PATCH_POINTS, group, index)
        if math.dist(polygon[0], polygon[-1]) < MIN_SEGMENT:
            polygon = polygon[:-1]  # closed as written: the first point again at the end
            if len(polygon) < 3:
                raise _fail("needs 3 or more corners", "polygon", group, index)
        problem = simple_polygon_problem(np.asarray(polygon), MIN_SEGMENT)
        if problem:
            raise _fail(problem, "polygon", group, index)
        return Patch(
            polygon,
            _number(self.friction, FRICTION_RANGE, "", "friction", group, index),
            _name(self.name or None, f"patch {index + 1}", group, index),
        )


@dataclass(frozen=True)
class Mark:
    """A polyline painted on the floor, ``points`` ``(n, 2)`` [m] (drawn; never touched)."""

    points: tuple[tuple[float, float], ...]
    name: str = ""

    def check(self, index: int) -> Mark:
        """This mark with its fields checked (as mark ``index``, from 0), name defaulted."""
        group = "marks"
        return Mark(
            _points(self.points, "points", 2, MAX_MARK_POINTS, group, index),
            _name(self.name or None, f"mark {index + 1}", group, index),
        )


@dataclass(frozen=True)
class Floor:
    """The floor: ``size`` (x, y) [m] centred on the origin (None: everything of the world and
    :data:`FLOOR_MARGIN` around it), ``friction`` between any wheel and the floor outside the
    ``patches`` (None: each wheel's own, its ``physical.friction``)."""

    size: tuple[float, float] | None = None
    friction: float | None = None
    patches: tuple[Patch, ...] = ()

    def check(self) -> Floor:
        """This floor with its fields and patches checked (patches may not overlap)."""
        size = None
        if self.size is not None:
            raw = self.size.tolist() if isinstance(self.size, np.ndarray) else self.size
            if not isinstance(raw, (list, tuple)) or len(raw) != 2:
                raise _fail(f"must be [x, y] in m, got {shorten(raw)}", "size", "floor")
            size = (
                _number(raw[0], FLOOR_SIZE_RANGE, "m", "size", "floor"),
                _number(raw[1], FLOOR_SIZE_RANGE, "m", "size", "floor"),
            )
        patches = _typed(self.patches, "patches", MAX_PATCHES, Patch)
        checked = tuple(p.check(i) for i, p in enumerate(patches))
        for i, j in overlapping_polygons([np.asarray(p.polygon) for p in checked], MIN_SEGMENT / 100.0):
            raise _fail(f"overlaps patch #{i + 1} (which friction holds there?)", "polygon", "patches", j)
        friction = None if self.friction is None else _number(self.friction, FRICTION_RANGE, "", "friction", "floor")
        return Floor(size, friction, checked)


@dataclass(frozen=True)
class World:
    """A world: ``name``, the robot's ``start`` pose (x, y, theta) [m, m, rad] in the world
    frame, the ``floor``, ``walls``, ``obstacles`` and floor ``marks``. Build it with
    :func:`make_world` (or :meth:`checked`), which checks every field and how the bodies lie."""

    name: str
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    floor: Floor = field(default_factory=Floor)
    walls: tuple[Wall, ...] = ()
    obstacles: tuple[Obstacle, ...] = ()
    marks: tuple[Mark, ...] = ()
    description: str = ""

    def checked(self) -> World:
        """This world with every field checked and defaults filled in (names of bodies)."""
        name = _name(self.name, "world")
        if not isinstance(self.description, str):
            raise _fail(f"must be text, got {shorten(self.description)}", "description")
        start = self.start.tolist() if isinstance(self.start, np.ndarray) else self.start
        if not isinstance(start, (list, tuple)) or len(start) != 3:
            raise _fail(f"must be a pose [x, y, theta], got {shorten(start)}", "start")
        x, y = _point(start[:2], "start")
        theta = _yaw(start[2], "start")
        walls = tuple(w.check(i) for i, w in enumerate(_typed(self.walls, "walls", MAX_WALL_SEGMENTS, Wall)))
        segments = sum(len(w.points) - 1 for w in walls)
        if segments > MAX_WALL_SEGMENTS:
            raise _fail(f"{segments} wall segments in all, at most {MAX_WALL_SEGMENTS}", "walls")
        obstacles = _sequence(self.obstacles, "obstacles", MAX_OBSTACLES)
        for i, o in enumerate(obstacles):
            if not isinstance(o, (Box, Cylinder)):
                raise _fail(f"must be a Box or a Cylinder, got {type(o).__name__}", None, "obstacles", i)
        checked_obstacles = tuple(o.check(i) for i, o in enumerate(obstacles))
        marks = tuple(m.check(i) for i, m in enumerate(_typed(self.marks, "marks", MAX_MARKS, Mark)))
        if not isinstance(self.floor, Floor):
            raise _fail(f"must be a Floor, got {type(self.floor).__name__}", "floor")
        world = World(name, (x, y, theta), self.floor.check(), walls, checked_obstacles, marks, self.description)
        _check_names(world)
        _check_movable_clear(world)
        return world

    @property
    def bodies(self) -> tuple[str, ...]:
        """Names of the bodies a robot can touch: walls, then obstacles, in file order."""
        return tuple(w.name for w in self.walls) + tuple(o.name for o in self.obstacles)

    @property
    def floor_bounds(self) -> tuple[float, float, float, float]:
        """``(x_min, y_min, x_max, y_max)`` [m] of the floor (module docstring)."""
        if self.floor.size is not None:
            hx, hy = self.floor.size[0] / 2.0, self.floor.size[1] / 2.0
            return (-hx, -hy, hx, hy)
        points = [self.start[:2]]
        for w in self.walls:
            points.extend(w.points)
        for o in self.obstacles:
            reach = o.radius if isinstance(o, Cylinder) else math.hypot(o.size[0], o.size[1]) / 2.0
            points.extend([(o.center[0] - reach, o.center[1] - reach), (o.center[0] + reach, o.center[1] + reach)])
        for p in self.floor.patches:
            points.extend(p.polygon)
        for m in self.marks:
            points.extend(m.points)
        arr = np.asarray(points, dtype=float)
        low, high = arr.min(axis=0) - FLOOR_MARGIN, arr.max(axis=0) + FLOOR_MARGIN
        return (float(low[0]), float(low[1]), float(high[0]), float(high[1]))


def make_world(
    name: str,
    start: Sequence[float] = (0.0, 0.0, 0.0),
    floor: Floor | None = None,
    walls: Sequence[Wall] = (),
    obstacles: Sequence[Obstacle] = (),
    marks: Sequence[Mark] = (),
    description: str = "",
) -> World:
    """A world built in Python, checked as a world file is.

    Parameters
    ----------
    name : str
        Its name (1 to 128 printable characters).
    start : sequence of 3 float
        The robot's start pose (x, y, theta) [m, m, rad] in the world frame.
    floor : Floor, optional
        The floor (None: its size from everything else, each wheel's own friction, no patches).
    walls : sequence of Wall
        Walls as polylines.
    obstacles : sequence of Box or Cylinder
        Obstacles standing on the floor.
    marks : sequence of Mark
        Lines painted on the floor.
    description : str
        Free text.

    Returns
    -------
    World
        The world with every field checked and the bodies' names filled in.

    Raises
    ------
    WorldFileError
        In one line naming the body and the field (module docstring).
    """
    return World(
        name,
        start,  # type: ignore[arg-type]  # checked by World.checked
        floor if floor is not None else Floor(),
        walls,  # type: ignore[arg-type]
        obstacles,  # type: ignore[arg-type]
        marks,  # type: ignore[arg-type]
        description,
    ).checked()


def _sequence(value: Any, group: str, most: int) -> tuple:
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise _fail(f"must be a list, got {shorten(value)}", group)
    if len(value) > most:
        raise _fail(f"{len(value)} entries, at most {most}", group)
    return tuple(value)


def _typed(value: Any, group: str, most: int, kind: type) -> tuple:
    """``value`` as a list of at most ``most`` items of ``kind`` (the bodies of ``group``)."""
    items = _sequence(value, group, most)
    for i, item in enumerate(items):
        if not isinstance(item, kind):
            raise _fail(f"must be a {kind.__name__}, got {type(item).__name__}", None, group, i)
    return items


def _check_names(world: World) -> None:
    """Every body of the world has a name of its own (contacts and the scene name them)."""
    seen: dict[str, str] = {}
    groups = (
        ("walls", world.walls),
        ("obstacles", world.obstacles),
        ("patches", world.floor.patches),
        ("marks", world.marks),
    )
    for group, bodies in groups:
        for i, body in enumerate(bodies):
            if body.name in seen:
                raise _fail(f"{body.name!r} is also the name of {seen[body.name]}", "name", group, i)
            seen[body.name] = _label(group, i) or group


def _check_movable_clear(world: World) -> None:
    """A movable obstacle may touch nothing at the start (the physics would throw it): each one's
    shapes against every other body's at once (vectorised: a world of 1000 movable obstacles
    beside 2000 wall segments is checked in about a second)."""
    movable = [i for i, o in enumerate(world.obstacles) if not o.fixed]
    if not movable:
        return
    outlines = [outline(body) for body in (*world.walls, *world.obstacles)]
    rects = np.concatenate([r for r, _ in outlines])
    circles = np.concatenate([c for _, c in outlines])
    rect_owner = np.concatenate([np.full(len(r), k) for k, (r, _) in enumerate(outlines)])
    circle_owner = np.concatenate([np.full(len(c), k) for k, (_, c) in enumerate(outlines)])
    first = len(world.walls)
    for i in movable:
        me = first + i
        mine_r, mine_c = outlines[me]
        other_r, other_c = rect_owner != me, circle_owner != me
        rr, cr, rc, cc = shape_gaps(mine_r, mine_c, rects[other_r], circles[other_c])
        gaps = np.concatenate([m.min(axis=0, initial=np.inf) for m in (rr, cr, rc, cc)])
        owners = np.concatenate(
            [rect_owner[other_r], rect_owner[other_r], circle_owner[other_c], circle_owner[other_c]]
        )
        touching = np.flatnonzero(gaps < 0.0)
        if len(touching):
            other = int(owners[touching[0]])
            raise _fail(f"a movable obstacle overlaps {world.bodies[other]!r} at the start", "center", "obstacles", i)


def outline(body: Wall | Obstacle) -> tuple[np.ndarray, np.ndarray]:
    """The rectangles ``(m, 5)`` and circles ``(k, 3)`` [m, world frame] of a wall (its segments
    lengthened by half its thickness at both ends: the corners of a polyline closed) or an
    obstacle, seen from above (:mod:`omnikin.world.plane` for the layout)."""
    no_circles = np.empty((0, 3))
    if isinstance(body, Wall):
        return wall_rects(np.asarray(body.points, dtype=float), body.thickness), no_circles
    if isinstance(body, Box):
        sx, sy, _ = body.size
        return np.array([[*body.center, sx / 2.0, sy / 2.0, body.yaw]]), no_circles
    return np.empty((0, 5)), np.array([[*body.center, body.radius]])
