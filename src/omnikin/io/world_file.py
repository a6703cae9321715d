"""World files, schema version 1 (``docs/world.md``): YAML (JSON is YAML too).

Read as robot files are (:mod:`omnikin.io.robot_file`): a regular file of at most 256 KiB, the
strict YAML loader (no aliases, tags, duplicate keys or YAML 1.1 number forms, bounded
nesting), unknown keys refused with the closest known one. Every problem raises
:class:`~omnikin.errors.WorldFileError` in one line naming the file, the line, the body and the
field, e.g. ``room.yaml: line 7: wall #2: field 'thickness': must lie in [0.001, 10] m, got 0``.
Lengths are in m; angles in deg (``yaw_deg``, and the third number of ``start``), converted to
the radians of :class:`~omnikin.world.model.World`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..common.arrays import range_problem
from ..common.messages import did_you_mean, shorten
from ..errors import WorldFileError
from ..world.model import Box, Cylinder, Floor, Mark, Patch, Wall, World
from .robot_file import parse_yaml_lines
from .textfile import read_text

SCHEMA_VERSION = 1
TOP_KEYS = {"omnikin_world": True, "name": True, "description": False, "start": False, "floor": False}
TOP_KEYS.update({"walls": False, "obstacles": False, "marks": False})
FLOOR_KEYS = ("size", "friction", "patches")
WALL_KEYS = ("points", "thickness", "height", "name")
BOX_KEYS = ("shape", "center", "size", "yaw_deg", "fixed", "mass", "name")
CYLINDER_KEYS = ("shape", "center", "radius", "height", "fixed", "mass", "name")
PATCH_KEYS = ("polygon", "friction", "name")
MARK_KEYS = ("points", "name")
SHAPES = ("box", "cylinder")
MAX_YAW_DEG = 360.0
"""Largest ``|yaw_deg|`` of an obstacle or of the start pose [deg]."""


class _Where:
    """Turns a problem at a path of the document into the one-line error with file and line."""

    def __init__(self, source: str, lines: dict[tuple[Any, ...], int]):
        self.source = source
        self.lines = lines

    def line(self, path: tuple[Any, ...]) -> int | None:
        while path not in self.lines and path:
            path = path[:-1]
        return self.lines.get(path)

    def error(self, problem: str, path: tuple[Any, ...], label: str | None = None) -> WorldFileError:
        line = self.line(path)
        parts = [self.source] + ([f"line {line}"] if line else []) + ([label] if label else [])
        return WorldFileError(": ".join([*parts, problem]))

    def located(self, exc: WorldFileError) -> WorldFileError:
        """``exc`` raised by the model, with the file and the line of the body and field it names."""
        path: tuple[Any, ...] = ()
        if exc.group == "patches":
            path = ("floor", "patches")
        elif exc.group == "floor":
            path = ("floor",)
        elif exc.group is not None:
            path = (exc.group,)
        if exc.body is not None:
            path = (*path, exc.body)
        if exc.field is not None:
            path = (*path, {"yaw": "yaw_deg"}.get(exc.field, exc.field))
        return WorldFileError(self.error(str(exc), path).args[0], field=exc.field, group=exc.group, body=exc.body)


def _mapping(where: _Where, data: Any, keys, path: tuple[Any, ...], label: str) -> Mapping:
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping with keys {list(keys)}, got {shorten(data)}", path, label)
    unknown = sorted(set(map(str, data)) - set(keys))
    if unknown:
        hint = did_you_mean(unknown[0], keys) if len(unknown[0]) <= 100 else ""
        raise where.error(f"unknown key(s) {shorten(unknown)}; allowed: {list(keys)}{hint}", path, label)
    return data


def _list(where: _Where, data: Any, path: tuple[Any, ...], what: str) -> list:
    if not isinstance(data, list):
        raise where.error(f"must be a list of {what}, got {shorten(data)}", path, f"field {path[-1]!r}")
    return data


def _degrees(where: _Where, value: Any, path: tuple[Any, ...], label: str) -> float:
    problem = range_problem(value, -MAX_YAW_DEG, MAX_YAW_DEG, "deg")
    if problem:
        raise where.error(problem, path, label)
    return math.radians(float(value))


def _obstacle(where: _Where, data: Any, i: int) -> Box | Cylinder:
    path = ("obstacles", i)
    label = f"obstacle #{i + 1}"
    if not isinstance(data, Mapping) or "shape" not in data:
        raise where.error(f"must be a mapping with 'shape' one of {list(SHAPES)}, got {shorten(data)}", path, label)
    shape = data["shape"]
    if shape not in SHAPES:
        hint = did_you_mean(str(shape), SHAPES) if isinstance(shape, str) and len(shape) <= 100 else ""
        raise where.error(f"unknown shape {shorten(shape)}; one of {list(SHAPES)}{hint}", (*path, "shape"), label)
    common = {"fixed": data.get("fixed", True), "mass": data.get("mass"), "name": data.get("name", "")}
    if shape == "box":
        _mapping(where, data, BOX_KEYS, path, label)
        for key in ("center", "size"):
            if key not in data:
                raise where.error("missing required key", path, f"{label}: field {key!r}")
        yaw = _degrees(where, data.get("yaw_deg", 0.0), (*path, "yaw_deg"), f"{label}: field 'yaw_deg'")
        return Box(data["center"], data["size"], yaw, **common)
    _mapping(where, data, CYLINDER_KEYS, path, label)
    for key in ("center", "radius"):
        if key not in data:
            raise where.error("missing required key", path, f"{label}: field {key!r}")
    return Cylinder(data["center"], data["radius"], data.get("height", 0.3), **common)


def world_from_dict(data: Any, source: str = "<world>", lines: dict[tuple[Any, ...], int] | None = None) -> World:
    """Validate a schema-1 mapping and build the :class:`~omnikin.world.model.World` it
    describes; ``lines`` (path -> line, :func:`omnikin.io.robot_file.parse_yaml_lines`) puts
    the line in messages."""
    where = _Where(source, lines or {})
    if not isinstance(data, Mapping):
        raise where.error(f"a world file must be a mapping at top level, got {type(data).__name__}", ())
    _mapping(where, data, TOP_KEYS, (), "")
    for key, required in TOP_KEYS.items():
        if required and key not in data:
            raise where.error("missing required key", (), f"field {key!r}")
    version = data["omnikin_world"]
    if version != SCHEMA_VERSION or isinstance(version, bool):
        raise where.error(
            f"unsupported world schema version {shorten(version)}; this omnikin reads version {SCHEMA_VERSION}",
            ("omnikin_world",),
            "field 'omnikin_world'",
        )
    start = data.get("start", [0.0, 0.0, 0.0])
    if not isinstance(start, list) or len(start) != 3:
        raise where.error(f"must be [x, y, yaw_deg] (m, m, deg), got {shorten(start)}", ("start",), "field 'start'")
    start = [start[0], start[1], _degrees(where, start[2], ("start",), "field 'start' (yaw, third number)")]

    floor_data = _mapping(where, data.get("floor", {}), FLOOR_KEYS, ("floor",), "field 'floor'")
    patches = []
    for i, p in enumerate(_list(where, floor_data.get("patches", []), ("floor", "patches"), "patches")):
        p = _mapping(where, p, PATCH_KEYS, ("floor", "patches", i), f"patch #{i + 1}")
        for key in ("polygon", "friction"):
            if key not in p:
                raise where.error("missing required key", ("floor", "patches", i), f"patch #{i + 1}: field {key!r}")
        patches.append(Patch(p["polygon"], p["friction"], p.get("name", "")))
    floor = Floor(floor_data.get("size"), floor_data.get("friction"), tuple(patches))

    walls = []
    for i, w in enumerate(_list(where, data.get("walls", []), ("walls",), "walls")):
        w = _mapping(where, w, WALL_KEYS, ("walls", i), f"wall #{i + 1}")
        if "points" not in w:
            raise where.error("missing required key", ("walls", i), f"wall #{i + 1}: field 'points'")
        walls.append(Wall(w["points"], w.get("thickness", 0.05), w.get("height", 0.3), w.get("name", "")))
    obstacles = [
        _obstacle(where, o, i)
        for i, o in enumerate(_list(where, data.get("obstacles", []), ("obstacles",), "obstacles"))
    ]
    marks = []
    for i, m in enumerate(_list(where, data.get("marks", []), ("marks",), "marks")):
        m = _mapping(where, m, MARK_KEYS, ("marks", i), f"mark #{i + 1}")
        if "points" not in m:
            raise where.error("missing required key", ("marks", i), f"mark #{i + 1}: field 'points'")
        marks.append(Mark(m["points"], m.get("name", "")))
    try:
        return World(
            data["name"],
            tuple(start),
            floor,
            tuple(walls),
            tuple(obstacles),
            tuple(marks),
            data.get("description", ""),
        ).checked()
    except WorldFileError as exc:
        raise where.located(exc) from None


def parse_world_text(text: str, source: str) -> World:
    """The world of a world file's ``text`` (``source`` names it in messages)."""
    data, lines = parse_yaml_lines(text, source, WorldFileError)
    return world_from_dict(data, source, lines)


def load_world(path: str | Path) -> World:
    """The world of the world file at ``path`` (module docstring for what is refused)."""
    return parse_world_text(read_text(path, WorldFileError, what="a world file"), str(path))


def world_to_dict(world: World) -> dict[str, Any]:
    """The schema-1 mapping of ``world`` (degrees where the file has them): ``load_world`` of
    its YAML gives ``world`` back."""
    out: dict[str, Any] = {
        "omnikin_world": SCHEMA_VERSION,
        "name": world.name,
        "description": world.description,
        "start": [world.start[0], world.start[1], math.degrees(world.start[2])],
    }
    floor: dict[str, Any] = {}
    if world.floor.friction is not None:
        floor["friction"] = world.floor.friction
    if world.floor.size is not None:
        floor["size"] = list(world.floor.size)
    if world.floor.patches:
        floor["patches"] = [
            {"name": p.name, "polygon": [list(q) for q in p.polygon], "friction": p.friction}
            for p in world.floor.patches
        ]
    out["floor"] = floor
    out["walls"] = [
        {"name": w.name, "points": [list(q) for q in w.points], "thickness": w.thickness, "height": w.height}
        for w in world.walls
    ]
    obstacles = []
    for o in world.obstacles:
        item: dict[str, Any] = {"name": o.name, "shape": o.shape, "center": list(o.center)}
        if isinstance(o, Box):
            item.update(size=list(o.size), yaw_deg=math.degrees(o.yaw))
        else:
            item.update(radius=o.radius, height=o.height)
        item["fixed"] = o.fixed
        if not o.fixed:
            item["mass"] = o.mass
        obstacles.append(item)
    out["obstacles"] = obstacles
    out["marks"] = [{"name": m.name, "points": [list(q) for q in m.points]} for m in world.marks]
    return out
