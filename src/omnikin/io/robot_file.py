"""Robot files, schema version 1 (``docs/conventions.md``): YAML, JSON accepted.

Every problem is reported as :class:`~omnikin.errors.RobotFileError` naming the
file, the wheel and the field, e.g.
``robot.yaml: wheel 'w2' (#2): field 'radius': must be > 0, got -0.04``.
Degrees appear only in fields ending in ``_deg``; the loaded
:class:`~omnikin.model.Robot` holds radians.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any, Mapping

from ..errors import OmnikinError, RobotFileError, shorten
from ..model import Robot
from ..presets import PRESET_NAMES, preset_path
from ..wheels import SWEDISH_TYPES, WHEEL_TYPES, Encoder, Steer, Wheel

SCHEMA_VERSION = 1
TOP_KEYS = {"omnikin": True, "name": True, "description": False, "references": False, "wheels": True}
WHEEL_KEYS = {"name", "type", "distance", "angle_deg", "x", "y", "drive_deg", "roller_deg",
              "radius", "encoder", "max_speed", "steer"}
ENCODER_KEYS = {"ticks_per_rev", "gear_ratio", "invert", "counter_bits"}
STEER_KEYS = {"offset", "min_deg", "max_deg"}


class _Where:
    """Formats error locations: file, wheel, field."""

    def __init__(self, source: str):
        self.source = source

    def error(self, msg: str, wheel: str | None = None, field: str | None = None) -> RobotFileError:
        parts = [self.source]
        if wheel is not None:
            parts.append(wheel)
        if field is not None:
            parts.append(f"field {field!r}")
        return RobotFileError(": ".join(parts) + ": " + msg)


def _number(where: _Where, value: Any, wheel: str | None, field: str, *, positive=False,
            nonnegative=False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise where.error(f"must be a number, got {value!r}", wheel, field)
    try:
        x = float(value)
    except OverflowError:
        raise where.error(f"number too large, got {value!r}", wheel, field) from None
    if not math.isfinite(x):
        raise where.error(f"must be finite, got {value!r}", wheel, field)
    if positive and x <= 0:
        raise where.error(f"must be > 0, got {value!r}", wheel, field)
    if nonnegative and x < 0:
        raise where.error(f"must be >= 0, got {value!r}", wheel, field)
    return x


def _check_keys(where: _Where, data: Mapping, allowed, wheel: str | None, field: str | None):
    unknown = sorted(set(map(str, data)) - set(allowed))
    if unknown:
        raise where.error(f"unknown key(s) {unknown}; allowed: {sorted(allowed)}", wheel,
                          field if field else None)


def _encoder(where: _Where, data: Any, wheel: str) -> Encoder:
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping with keys {sorted(ENCODER_KEYS)}, got {data!r}", wheel, "encoder")
    _check_keys(where, data, ENCODER_KEYS, wheel, "encoder")
    if "ticks_per_rev" not in data:
        raise where.error("missing required key 'ticks_per_rev'", wheel, "encoder")
    tpr = _number(where, data["ticks_per_rev"], wheel, "encoder.ticks_per_rev", positive=True)
    gear = _number(where, data.get("gear_ratio", 1.0), wheel, "encoder.gear_ratio", positive=True)
    invert = data.get("invert", False)
    if not isinstance(invert, bool):
        raise where.error(f"must be true or false, got {invert!r}", wheel, "encoder.invert")
    bits = data.get("counter_bits")
    if bits is not None and (isinstance(bits, bool) or not isinstance(bits, int) or not 2 <= bits <= 64):
        raise where.error(f"the width of the encoder's counter, a whole number from 2 to 64, got {shorten(bits)}",
                          wheel, "encoder.counter_bits")
    return Encoder(tpr, gear, invert, bits)


def _steer(where: _Where, data: Any, wheel: str) -> Steer:
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping with keys {sorted(STEER_KEYS)}, got {data!r}", wheel, "steer")
    _check_keys(where, data, STEER_KEYS, wheel, "steer")
    offset = _number(where, data.get("offset", 0.0), wheel, "steer.offset", nonnegative=True)
    lo = _number(where, data.get("min_deg", -180.0), wheel, "steer.min_deg")
    hi = _number(where, data.get("max_deg", 180.0), wheel, "steer.max_deg")
    if not -180.0 <= lo < hi <= 180.0:
        raise where.error(f"need -180 <= min_deg < max_deg <= 180, got {lo} and {hi}", wheel, "steer")
    return Steer(offset, math.radians(lo), math.radians(hi))


def _wheel(where: _Where, data: Any, index: int) -> Wheel:
    label = f"wheel #{index}"
    if not isinstance(data, Mapping):
        raise where.error(f"must be a mapping, got {data!r}", label)
    if isinstance(data.get("name"), str) and data["name"]:
        label = f"wheel {data['name']!r} (#{index})"
    _check_keys(where, data, WHEEL_KEYS, label, None)
    for key in ("name", "type", "radius"):
        if key not in data:
            raise where.error("missing required key", label, key)
    name, kind = data["name"], data["type"]
    if not isinstance(name, str) or not name.strip():
        raise where.error(f"must be a non-empty string, got {name!r}", label, "name")
    if kind not in WHEEL_TYPES:
        raise where.error(f"unknown wheel type {kind!r}; one of {list(WHEEL_TYPES)}", label, "type")

    polar = [k for k in ("distance", "angle_deg") if k in data]
    cart = [k for k in ("x", "y") if k in data]
    if polar and cart:
        raise where.error("give either distance/angle_deg or x/y, not both", label)
    if cart:
        if len(cart) != 2:
            raise where.error("Cartesian placement needs both 'x' and 'y'", label)
        x = _number(where, data["x"], label, "x")
        y = _number(where, data["y"], label, "y")
    elif polar:
        if len(polar) != 2:
            raise where.error("polar placement needs both 'distance' and 'angle_deg'", label)
        dist = _number(where, data["distance"], label, "distance", nonnegative=True)
        beta = math.radians(_number(where, data["angle_deg"], label, "angle_deg"))
        x, y = dist * math.cos(beta), dist * math.sin(beta)
        x, y = (0.0 if abs(x) < 1e-15 * max(dist, 1) else x), (0.0 if abs(y) < 1e-15 * max(dist, 1) else y)
    else:
        raise where.error("missing placement: give distance and angle_deg, or x and y", label)

    if "drive_deg" in data:
        drive = math.radians(_number(where, data["drive_deg"], label, "drive_deg"))
    elif x == 0.0 and y == 0.0:
        raise where.error("a wheel at the origin has no default drive direction: give drive_deg", label,
                          "drive_deg")
    else:
        drive = math.atan2(y, x) + math.pi / 2

    radius = _number(where, data["radius"], label, "radius", positive=True)
    roller = 0.0
    if kind in SWEDISH_TYPES:
        if kind == "omni":
            if "roller_deg" in data and _number(where, data["roller_deg"], label, "roller_deg") != 0.0:
                raise where.error(f"an omni wheel has roller_deg 0, got {data['roller_deg']!r} "
                                  f"(use type 'swedish' for other roller angles)", label, "roller_deg")
        else:
            if "roller_deg" not in data:
                raise where.error(f"required for a {kind} wheel", label, "roller_deg")
            gamma = _number(where, data["roller_deg"], label, "roller_deg")
            if kind == "mecanum" and abs(gamma) != 45.0:
                raise where.error(f"a mecanum wheel has roller_deg +45 or -45, got {gamma!r} "
                                  f"(use type 'swedish' for other angles)", label, "roller_deg")
            if not -90.0 < gamma < 90.0:
                raise where.error(f"must lie strictly between -90 and 90 (at +-90 the wheel cannot drive), "
                                  f"got {gamma!r}", label, "roller_deg")
            roller = math.radians(gamma)
    elif "roller_deg" in data:
        raise where.error(f"only Swedish wheels (omni, mecanum, swedish) have rollers, not {kind!r}", label,
                          "roller_deg")

    steer = None
    if "steer" in data:
        if kind not in ("steerable", "castor"):
            raise where.error(f"only steerable wheels and castors have 'steer', not {kind!r}", label, "steer")
        steer = _steer(where, data["steer"], label)
    if kind == "castor" and (steer is None or steer.offset <= 0.0):
        raise where.error("a castor needs steer.offset > 0 (the trail behind its swivel axis)", label, "steer")
    if kind == "castor" and "encoder" in data:
        raise where.error("castors are passive and unmeasured in schema 1: remove 'encoder'", label, "encoder")
    encoder = _encoder(where, data["encoder"], label) if "encoder" in data else None
    max_speed = None
    if "max_speed" in data:
        max_speed = _number(where, data["max_speed"], label, "max_speed", positive=True)
    return Wheel(name, kind, x, y, drive, radius, roller, encoder, max_speed, steer)


def robot_from_dict(data: Any, source: str = "<robot>") -> Robot:
    """Validate a schema-1 mapping and build the :class:`Robot` it describes."""
    where = _Where(source)
    if not isinstance(data, Mapping):
        raise where.error(f"a robot file must be a mapping at top level, got {type(data).__name__}")
    _check_keys(where, data, TOP_KEYS, None, None)
    for key, required in TOP_KEYS.items():
        if required and key not in data:
            raise where.error("missing required key", None, key)
    if data["omnikin"] != SCHEMA_VERSION or isinstance(data["omnikin"], bool):
        raise where.error(f"unsupported schema version {data['omnikin']!r}; this omnikin reads version "
                          f"{SCHEMA_VERSION}", None, "omnikin")
    name = data["name"]
    if not isinstance(name, str) or not name.strip():
        raise where.error(f"must be a non-empty string, got {name!r}", None, "name")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise where.error(f"must be a string, got {description!r}", None, "description")
    refs = data.get("references", [])
    if not isinstance(refs, list) or not all(isinstance(r, str) for r in refs):
        raise where.error(f"must be a list of strings, got {refs!r}", None, "references")
    wheels = data["wheels"]
    if not isinstance(wheels, list) or not wheels:
        raise where.error(f"must be a non-empty list of wheels, got {wheels!r}", None, "wheels")
    parsed = [_wheel(where, w, i + 1) for i, w in enumerate(wheels)]
    seen = set()
    for i, w in enumerate(parsed):
        if w.name in seen:
            raise where.error(f"duplicate wheel name {w.name!r}", f"wheel #{i + 1}", "name")
        seen.add(w.name)
    try:
        return Robot(name, tuple(parsed), description, tuple(refs))
    except OmnikinError as exc:
        raise RobotFileError(f"{source}: {exc}") from None


_EXPONENT = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+$")
"""Floats YAML 1.1 reads as strings (``5e-2``: no dot) but YAML 1.2 and JSON as numbers."""


def strict_yaml_loader():
    """A PyYAML SafeLoader that refuses duplicate keys and reads ``5e-2`` as a float."""
    import yaml

    class StrictLoader(yaml.SafeLoader):
        pass

    def mapping(loader, node, deep=False):
        keys = set()
        for key_node, _ in node.value:
            key = loader.construct_object(key_node, deep=deep)
            if key in keys:
                mark = key_node.start_mark
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (line {mark.line + 1})", mark)
            keys.add(key)
        return loader.construct_mapping(node, deep=deep)

    def scalar(loader, node):
        value = loader.construct_scalar(node)
        if node.style is None and _EXPONENT.match(value):
            return float(value)
        return value

    StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, mapping)
    StrictLoader.add_constructor("tag:yaml.org,2002:str", scalar)
    return StrictLoader


def _unique_json_keys(source: str):
    def hook(pairs):
        keys = [k for k, _ in pairs]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            raise RobotFileError(f"{source}: duplicate key(s) {dup}")
        return dict(pairs)
    return hook


def parse_robot_text(text: str, source: str) -> Robot:
    """Parse YAML or JSON text (JSON is YAML 1.2 too; tried first when it looks like JSON)."""
    if text.lstrip().startswith("{"):
        try:
            data = json.loads(text, object_pairs_hook=_unique_json_keys(source))
        except json.JSONDecodeError as exc:
            raise RobotFileError(f"{source}: invalid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}") from None
    else:
        import yaml

        try:
            data = yaml.load(text, Loader=strict_yaml_loader())
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            at = f" at line {mark.line + 1} column {mark.column + 1}" if mark is not None else ""
            problem = getattr(exc, "problem", None) or str(exc)
            raise RobotFileError(f"{source}: invalid YAML{at}: {problem}") from None
    return robot_from_dict(data, source)


def load_robot(spec: str | Path) -> Robot:
    """Load a robot from a preset name (``omnikin show`` lists them) or a file path."""
    spec_str = str(spec)
    path = Path(spec_str)
    if spec_str in PRESET_NAMES and not path.exists():
        path = preset_path(spec_str)
    elif not path.exists():
        raise RobotFileError(f"{spec_str}: no such robot file or preset; presets: {', '.join(PRESET_NAMES)}")
    if path.is_dir():
        raise RobotFileError(f"{spec_str}: is a directory, not a robot file")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotFileError(f"{spec_str}: cannot read: {exc}") from None
    return parse_robot_text(text, path.name if spec_str in PRESET_NAMES else spec_str)


def _clean(x: float) -> float:
    return float(round(float(x), 12))


def robot_to_dict(robot: Robot) -> dict:
    """Schema-1 mapping of ``robot`` (Cartesian placement, explicit drive_deg)."""
    wheels = []
    for w in robot.wheels:
        d: dict[str, Any] = {"name": w.name, "type": w.type, "x": _clean(w.x), "y": _clean(w.y),
                             "drive_deg": _clean(math.degrees(w.drive))}
        if w.type in ("mecanum", "swedish"):
            d["roller_deg"] = _clean(math.degrees(w.roller))
        d["radius"] = float(w.radius)
        if w.encoder is not None:
            d["encoder"] = {"ticks_per_rev": float(w.encoder.ticks_per_rev), "gear_ratio": float(w.encoder.gear_ratio),
                            "invert": bool(w.encoder.invert)}
            if w.encoder.counter_bits is not None:
                d["encoder"]["counter_bits"] = int(w.encoder.counter_bits)
        if w.max_speed is not None:
            d["max_speed"] = float(w.max_speed)
        if w.steer is not None:
            d["steer"] = {"offset": float(w.steer.offset), "min_deg": _clean(math.degrees(w.steer.lower)),
                          "max_deg": _clean(math.degrees(w.steer.upper))}
        wheels.append(d)
    return {"omnikin": SCHEMA_VERSION, "name": robot.name, "description": robot.description,
            "references": list(robot.references), "wheels": wheels}


def save_robot(robot: Robot, path: str | Path) -> None:
    """Write ``robot`` as YAML (``.yaml``/``.yml``) or JSON (``.json``)."""
    path = Path(path)
    data = robot_to_dict(robot)
    if path.suffix.lower() == ".json":
        path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    else:
        import yaml

        path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
