"""The protocol description: ``protocol.yaml`` read, checked and held as frozen dataclasses.

Implements the rules ``docs/protocol.md`` states for a description (sections *Constants*,
*Frame*, *Frame types*, *Timing and link loss*, *Error codes*, *Status flags*):
version 1-255, two distinct sync bytes, little-endian only, a payload of at most
``max_payload`` bytes whose first field is the wheel index (u8, 255 reserved), field types
u8/i8/u16/i16/u32/i32 and one trailing ``text``, scales > 0 (physical value = raw x scale,
in the field's ``unit``), a non-reflected 16-bit CRC that matches its check value, a one-byte
sequence (modulo 256), and times in seconds that are whole milliseconds (the firmware counts ms).

``protocol.yaml`` is package data of :mod:`omnikin.runtime` (next to this package), the
single source of truth of the Python side, the C header and the documentation tables.
Every problem raises :class:`ProtocolError` (an :class:`~omnikin.errors.InputError`) whose
one-line message names the file and the key.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

from ...common.messages import shorten
from ...errors import ProtocolError
from .crc import Crc

DIRECTIONS = ("host_to_controller", "controller_to_host", "both")
INT_TYPES = {  # name: (struct code, size, C type, min, max)
    "u8": ("B", 1, "uint8_t", 0, 2**8 - 1),
    "i8": ("b", 1, "int8_t", -(2**7), 2**7 - 1),
    "u16": ("H", 2, "uint16_t", 0, 2**16 - 1),
    "i16": ("h", 2, "int16_t", -(2**15), 2**15 - 1),
    "u32": ("I", 4, "uint32_t", 0, 2**32 - 1),
    "i32": ("i", 4, "int32_t", -(2**31), 2**31 - 1),
}
HEADER_BYTES = 4  # version, type, seq, length (after the sync bytes)
CRC_BYTES = 2


# --- description -------------------------------------------------------------------------


@dataclass(frozen=True)
class Field:
    """One payload field; physical value = raw * scale (scale None: the raw value)."""

    name: str
    type: str
    description: str = ""
    unit: str = ""
    scale: float | None = None
    wraps: bool = False
    table: str | None = None
    max_length: int = 0

    @property
    def size(self) -> int:
        """Bytes on the wire (text: its maximum)."""
        return self.max_length if self.type == "text" else INT_TYPES[self.type][1]


@dataclass(frozen=True)
class FrameType:
    name: str
    id: int
    direction: str
    description: str
    fields: tuple

    @property
    def fixed(self) -> tuple:
        return tuple(f for f in self.fields if f.type != "text")

    @property
    def text(self) -> Field | None:
        return next((f for f in self.fields if f.type == "text"), None)

    @property
    def min_size(self) -> int:
        return sum(f.size for f in self.fixed)

    @property
    def max_size(self) -> int:
        return self.min_size + (self.text.max_length if self.text else 0)

    @property
    def struct_format(self) -> str:
        return "<" + "".join(INT_TYPES[f.type][0] for f in self.fixed)

    def accepts(self, length: int) -> bool:
        return self.min_size <= length <= self.max_size

    def field(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise ProtocolError(
            f"frame type {self.name} has no field {shorten(name)} (fields: {[f.name for f in self.fields]})"
        )


@dataclass(frozen=True)
class Code:
    """An error code (``value`` = code) or a status flag (``value`` = bit)."""

    value: int
    name: str
    description: str


@dataclass(frozen=True)
class Timing:
    heartbeat_period: float
    report_period: float
    link_timeout: float
    connect_timeout: float


@dataclass(frozen=True)
class Protocol:
    """``protocol.yaml``, checked (:func:`load_protocol`)."""

    name: str
    version: int
    byte_order: str
    sync: bytes
    max_payload: int
    wheel_index_max: int
    serial: dict
    crc: Crc
    seq_modulo: int
    resync_after: int
    counter_bits: int
    timing: Timing
    frames: dict
    error_codes: tuple
    status_flags: tuple
    source: str = field(default="", compare=False)
    by_id: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        self.by_id.update({ft.id: ft for ft in self.frames.values()})

    @property
    def header_size(self) -> int:
        """Bytes before the payload: sync, version, type, seq, length."""
        return len(self.sync) + HEADER_BYTES

    @property
    def max_frame(self) -> int:
        return self.header_size + self.max_payload + CRC_BYTES

    def frame(self, name: str) -> FrameType:
        frame = self.frames.get(name) if isinstance(name, str) else None
        if frame is None:
            raise ProtocolError(f"unknown frame type {shorten(name)} (types: {sorted(self.frames)})")
        return frame

    def error_name(self, code: int) -> str:
        return next((c.name for c in self.error_codes if c.value == code), f"UNKNOWN_{code}")

    def error_code(self, name: str) -> int:
        for c in self.error_codes:
            if c.name == name:
                return c.value
        raise ProtocolError(f"unknown error code {shorten(name)} (codes: {[c.name for c in self.error_codes]})")

    def status_bit(self, name: str) -> int:
        for c in self.status_flags:
            if c.name == name:
                return 1 << c.value
        raise ProtocolError(f"unknown status flag {shorten(name)} (flags: {[c.name for c in self.status_flags]})")


def _take(d: dict, where: str, required: tuple, optional: tuple = ()) -> dict:
    if not isinstance(d, dict):
        raise ProtocolError(f"{where}: expected a mapping, got {shorten(d)}")
    unknown = set(d) - set(required) - set(optional)
    missing = [k for k in required if k not in d]
    if unknown:
        raise ProtocolError(f"{where}: unknown key(s) {shorten(sorted(map(str, unknown)))}")
    if missing:
        raise ProtocolError(f"{where}: missing key(s) {missing}")
    return d


def _int(v, where: str, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise ProtocolError(f"{where}: expected an integer from {lo} to {hi}, got {shorten(v)}")
    return v


def _seconds(v, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ProtocolError(f"{where}: expected a time > 0 [s], got {shorten(v)}")
    if abs(v * 1000 - round(v * 1000)) > 1e-9:
        raise ProtocolError(f"{where}: {v} s is not a whole number of milliseconds (the firmware counts ms)")
    return float(v)


def _codes(items, where: str, key: str, hi: int) -> tuple:
    if not isinstance(items, list) or not items:
        raise ProtocolError(f"{where}: expected a non-empty list")
    out: list[Code] = []
    seen: set[int] = set()
    for i, c in enumerate(items):
        w = f"{where}[{i}]"
        _take(c, w, (key, "name", "description"))
        value = _int(c[key], f"{w}.{key}", 0 if key == "bit" else 1, hi)
        if not isinstance(c["name"], str) or not re.fullmatch(r"[A-Z][A-Z0-9_]*", c["name"]):
            raise ProtocolError(f"{w}.name: expected UPPER_CASE, got {shorten(c['name'])}")
        if value in seen or c["name"] in {o.name for o in out}:
            raise ProtocolError(f"{w}: duplicate {key} {value} or name {shorten(c['name'])}")
        seen.add(value)
        out.append(Code(value, c["name"], str(c["description"])))
    return tuple(out)


def parse_protocol(doc: dict, source: str = "<dict>") -> Protocol:
    """Check a protocol description (the content of ``protocol.yaml``) and build a :class:`Protocol`."""
    top = (
        "name",
        "version",
        "byte_order",
        "sync",
        "max_payload",
        "wheel_index_max",
        "serial",
        "crc",
        "sequence",
        "encoder",
        "timing",
        "frames",
        "error_codes",
        "status_flags",
    )
    _take(doc, source, top)
    version = _int(doc["version"], f"{source}: version", 1, 255)
    if doc["byte_order"] != "little":
        raise ProtocolError(f"{source}: byte_order: only 'little' is implemented, got {shorten(doc['byte_order'])}")
    sync = doc["sync"]
    if not isinstance(sync, list) or len(sync) != 2 or len(set(sync)) != 2:
        raise ProtocolError(f"{source}: sync: expected two different bytes, got {shorten(sync)}")
    sync = bytes(_int(b, f"{source}: sync", 0, 255) for b in sync)
    max_payload = _int(doc["max_payload"], f"{source}: max_payload", 1, 255 - HEADER_BYTES - CRC_BYTES - 2)
    wheel_max = _int(doc["wheel_index_max"], f"{source}: wheel_index_max", 0, 254)
    ser = _take(doc["serial"], f"{source}: serial", ("baud", "bytesize", "parity", "stopbits"))
    _int(ser["baud"], f"{source}: serial.baud", 50, 10_000_000)
    _int(ser["bytesize"], f"{source}: serial.bytesize", 5, 8)
    _int(ser["stopbits"], f"{source}: serial.stopbits", 1, 2)
    if ser["parity"] not in ("none", "even", "odd"):
        raise ProtocolError(f"{source}: serial.parity: expected none, even or odd, got {shorten(ser['parity'])}")
    c = _take(
        doc["crc"], f"{source}: crc", ("name", "width", "poly", "init", "refin", "refout", "xorout", "check", "covers")
    )
    if c["width"] != 16 or c["refin"] or c["refout"]:
        raise ProtocolError(f"{source}: crc: only non-reflected 16-bit CRCs are implemented")
    crc = Crc(
        str(c["name"]),
        16,
        _int(c["poly"], "crc.poly", 1, 0xFFFF),
        _int(c["init"], "crc.init", 0, 0xFFFF),
        False,
        False,
        _int(c["xorout"], "crc.xorout", 0, 0xFFFF),
        _int(c["check"], "crc.check", 0, 0xFFFF),
        str(c["covers"]),
    )
    if crc(b"123456789") != crc.check:
        raise ProtocolError(
            f"{source}: crc: the parameters give check 0x{crc(b'123456789'):04X}, the file says 0x{crc.check:04X}"
        )
    seq = _take(doc["sequence"], f"{source}: sequence", ("modulo", "resync_after"))
    if seq["modulo"] != 256:
        raise ProtocolError(f"{source}: sequence.modulo: the sequence is one byte (256), got {shorten(seq['modulo'])}")
    resync = _int(seq["resync_after"], f"{source}: sequence.resync_after", 1, 127)
    enc = _take(doc["encoder"], f"{source}: encoder", ("counter_bits",))
    bits = _int(enc["counter_bits"], f"{source}: encoder.counter_bits", 2, 32)
    tm = _take(
        doc["timing"], f"{source}: timing", ("heartbeat_period", "report_period", "link_timeout", "connect_timeout")
    )
    timing = Timing(
        *(
            _seconds(tm[k], f"{source}: timing.{k}")
            for k in ("heartbeat_period", "report_period", "link_timeout", "connect_timeout")
        )
    )
    if not (timing.heartbeat_period < timing.link_timeout and timing.report_period < timing.link_timeout):
        raise ProtocolError(f"{source}: timing: heartbeat_period and report_period must be shorter than link_timeout")
    error_codes = _codes(doc["error_codes"], f"{source}: error_codes", "code", 255)
    status_flags = _codes(doc["status_flags"], f"{source}: status_flags", "bit", 7)
    tables = {"error_codes", "status_flags"}
    frames, ids = {}, set()
    if not isinstance(doc["frames"], dict) or not doc["frames"]:
        raise ProtocolError(f"{source}: frames: expected a mapping of frame types")
    for name, ft in doc["frames"].items():
        w = f"{source}: frames.{name}"
        if not re.fullmatch(r"[A-Z][A-Z0-9_]*", str(name)):
            raise ProtocolError(f"{w}: frame names are UPPER_CASE")
        _take(ft, w, ("id", "direction", "description", "fields"))
        fid = _int(ft["id"], f"{w}.id", 1, 255)
        if fid in ids:
            raise ProtocolError(f"{w}.id: 0x{fid:02X} is used twice")
        ids.add(fid)
        if ft["direction"] not in DIRECTIONS:
            raise ProtocolError(f"{w}.direction: expected one of {DIRECTIONS}, got {shorten(ft['direction'])}")
        if not isinstance(ft["fields"], list):
            raise ProtocolError(f"{w}.fields: expected a list of fields, got {shorten(ft['fields'])}")
        flist: list[Field] = []
        for i, fd in enumerate(ft["fields"]):
            fw = f"{w}.fields[{i}]"
            _take(fd, fw, ("name", "type"), ("description", "unit", "scale", "wraps", "table", "max_length"))
            if not isinstance(fd["type"], str) or (fd["type"] not in INT_TYPES and fd["type"] != "text"):
                raise ProtocolError(
                    f"{fw}.type: expected one of {sorted(INT_TYPES) + ['text']}, got {shorten(fd['type'])}"
                )
            if (
                not isinstance(fd["name"], str)
                or not re.fullmatch(r"[a-z][a-z0-9_]*", fd["name"])
                or fd["name"] in {f.name for f in flist}
            ):
                raise ProtocolError(f"{fw}.name: expected a new lower_case name, got {shorten(fd['name'])}")
            scale = fd.get("scale")
            if scale is not None and (
                isinstance(scale, bool)
                or not isinstance(scale, (int, float))
                or not math.isfinite(scale)
                or scale <= 0
                or fd["type"] == "text"
            ):
                raise ProtocolError(f"{fw}.scale: expected a number > 0 on an integer field, got {shorten(scale)}")
            if fd.get("table") is not None and (not isinstance(fd["table"], str) or fd["table"] not in tables):
                raise ProtocolError(f"{fw}.table: expected one of {sorted(tables)}, got {shorten(fd['table'])}")
            max_length = 0
            if fd["type"] == "text":
                max_length = _int(fd.get("max_length"), f"{fw}.max_length", 1, max_payload)
                if i != len(ft["fields"]) - 1:
                    raise ProtocolError(f"{fw}: a text field must be the last field")
            flist.append(
                Field(
                    fd["name"],
                    fd["type"],
                    str(fd.get("description", "")),
                    str(fd.get("unit", "")),
                    None if scale is None else float(scale),
                    bool(fd.get("wraps", False)),
                    fd.get("table"),
                    max_length,
                )
            )
        if not flist or flist[0].name != "wheel" or flist[0].type != "u8":
            raise ProtocolError(f"{w}: the first field must be 'wheel' (u8): receivers track sequences per wheel")
        frame = FrameType(name, fid, ft["direction"], str(ft["description"]), tuple(flist))
        if frame.max_size > max_payload:
            raise ProtocolError(f"{w}: payload of up to {frame.max_size} bytes exceeds max_payload {max_payload}")
        frames[name] = frame
    for needed in ("SPEED_CMD", "ENCODER_REPORT", "ERROR_REPORT", "HEARTBEAT"):
        if needed not in frames:
            raise ProtocolError(f"{source}: frames: the runtime needs frame type {needed}")
    if "RESET" not in {c.name for c in error_codes}:
        raise ProtocolError(f"{source}: error_codes: the sequence rules need a RESET code")
    return Protocol(
        str(doc["name"]),
        version,
        "little",
        sync,
        max_payload,
        wheel_max,
        dict(ser),
        crc,
        256,
        resync,
        bits,
        timing,
        frames,
        error_codes,
        status_flags,
        source,
    )


MAX_PROTOCOL_BYTES = 256 * 1024
"""Largest protocol description read [bytes]: the shipped one is about 6 KiB."""


def load_protocol(path=None) -> Protocol:
    """The protocol of ``path`` (default: the package's ``protocol.yaml``, read once).

    A user's file is read as plain YAML data only: at most :data:`MAX_PROTOCOL_BYTES`, no
    anchors or aliases (an alias bomb of a few hundred bytes expands to gigabytes), no explicit
    tags (``!!int 'abc'``); anything else is a one-line :class:`ProtocolError` naming the file."""
    if path is None:
        return _default_protocol()
    import yaml

    try:
        path = Path(path)
    except TypeError:
        raise ProtocolError(f"protocol description: expected a path, got {shorten(path)}") from None
    try:
        if path.exists() and not path.is_file():  # a folder, FIFO or device: never read
            raise ProtocolError(f"{path}: cannot read the protocol description: not a regular file")
        with path.open("rb") as f:
            raw = f.read(MAX_PROTOCOL_BYTES + 1)
        if len(raw) > MAX_PROTOCOL_BYTES:
            raise ProtocolError(f"{path}: larger than {MAX_PROTOCOL_BYTES // 1024} KiB: not a protocol description")
        text = raw.decode("utf-8")
        _plain_yaml(yaml, text, path)
        doc = yaml.safe_load(text)
    except ProtocolError:
        raise
    except OSError as exc:
        raise ProtocolError(f"{path}: cannot read the protocol description: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ProtocolError(f"{path}: the protocol description is not UTF-8 text (byte {exc.start})") from None
    except yaml.YAMLError as exc:
        raise ProtocolError(f"{path}: not valid YAML: {_yaml_problem(exc)}") from None
    except (ValueError, IndexError, TypeError, OverflowError) as exc:  # PyYAML's number constructors
        raise ProtocolError(f"{path}: not valid YAML data: {shorten(str(exc))}") from None
    return parse_protocol(doc, str(path))


def _plain_yaml(yaml, text: str, path: Path) -> None:
    """Raise :class:`ProtocolError` at the first anchor, alias or explicit tag of ``text``."""
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        mark = event.start_mark
        where = f"{path}: line {mark.line + 1} column {mark.column + 1}"
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
            raise ProtocolError(f"{where}: anchors and aliases are not allowed in a protocol description")
        tag = getattr(event, "tag", None)
        implicit = getattr(event, "implicit", True)
        explicit = tag is not None and not (implicit if isinstance(implicit, bool) else any(implicit))
        if explicit:
            raise ProtocolError(
                f"{where}: explicit tag {shorten(tag)} not allowed: write numbers plain, text in quotes"
            )


def _yaml_problem(exc) -> str:
    """A YAML error in one line: the problem and where (PyYAML's own message spans lines)."""
    mark = getattr(exc, "problem_mark", None)
    text = getattr(exc, "problem", None) or str(exc)
    if mark is not None:
        text += f" at line {mark.line + 1}, column {mark.column + 1}"
    return " ".join(text.split())


_DATA_PACKAGE = __package__.rpartition(".")[0]  # omnikin.runtime: protocol.yaml sits next to this package


@lru_cache(maxsize=1)
def _default_protocol() -> Protocol:
    import yaml

    text = resources.files(_DATA_PACKAGE).joinpath("protocol.yaml").read_text(encoding="utf-8")
    return parse_protocol(yaml.safe_load(text), "omnikin/runtime/protocol.yaml")
