"""The wheel-controller protocol: framing, encoding and a robust streaming decoder.

``protocol.yaml`` (next to this module) is the single source of truth; this module reads it,
and generates from it the C header of the firmware and the tables of ``docs/protocol.md``::

    python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h
    python -m omnikin.runtime.protocol --update-doc docs/protocol.md

Frame (every multi-byte integer little-endian, the CRC included)::

    | sync (0xAA 0x55) | version | type | seq | length | payload (length bytes) | CRC-16 |

The CRC is CRC-16/CCITT-FALSE over version .. payload. Every payload starts with the wheel
index (u8). ``seq`` counts the frames of one stream modulo 256, a stream being one direction
of one wheel. The envelope (sync, the four header bytes, the CRC) is the same in every
version, so a receiver can skip whole frames of a version it does not speak.

:class:`StreamDecoder` never raises on bad bytes. It resynchronises on the sync bytes and
counts what it rejects (:class:`DecoderStats`):

* ``corrupt``: the CRC fails (or the length byte is impossible) and no frame starts inside;
* ``short``: a frame was cut off: a valid frame starts before the end it announced (each
  frame start before that valid frame counts: two cut frames in a row count two), or, on
  :meth:`StreamDecoder.flush`, the bytes stopped mid-frame;
* ``bad_version``, ``unknown_type``, ``bad_length`` (the length does not fit the type),
  ``wrong_direction`` (a type the other side sends, e.g. an echo), ``bad_wheel`` (index 255);
* sequence, per wheel: ``duplicates`` (same number again; dropped), ``out_of_order`` (a number
  from the past; dropped, unless ``resync_after`` of them in a row show that the sender
  restarted: then adopted and counted in ``resyncs``), ``lost`` (numbers skipped; the frame
  is accepted). An ERROR_REPORT with code RESET restarts its stream whatever its number;
* ``skipped_bytes``: bytes that were not part of an accepted frame.
"""

from __future__ import annotations

import argparse
import math
import re
import struct
import sys
from dataclasses import dataclass, field
from dataclasses import fields as dc_fields
from functools import lru_cache
from importlib import resources
from pathlib import Path

from ..errors import InputError

DIRECTIONS = ("host_to_controller", "controller_to_host", "both")
INT_TYPES = {  # name: (struct code, size, C type, min, max)
    "u8": ("B", 1, "uint8_t", 0, 2 ** 8 - 1),
    "i8": ("b", 1, "int8_t", -2 ** 7, 2 ** 7 - 1),
    "u16": ("H", 2, "uint16_t", 0, 2 ** 16 - 1),
    "i16": ("h", 2, "int16_t", -2 ** 15, 2 ** 15 - 1),
    "u32": ("I", 4, "uint32_t", 0, 2 ** 32 - 1),
    "i32": ("i", 4, "int32_t", -2 ** 31, 2 ** 31 - 1),
}
HEADER_BYTES = 4  # version, type, seq, length (after the sync bytes)
CRC_BYTES = 2


class ProtocolError(InputError):
    """A protocol description that breaks the rules, or a frame that cannot be encoded."""


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
        raise ProtocolError(f"frame type {self.name} has no field {name!r} (fields: {[f.name for f in self.fields]})")


@dataclass(frozen=True)
class Code:
    """An error code (``value`` = code) or a status flag (``value`` = bit)."""

    value: int
    name: str
    description: str


@dataclass(frozen=True)
class Crc:
    name: str
    width: int
    poly: int
    init: int
    refin: bool
    refout: bool
    xorout: int
    check: int
    covers: str

    def __post_init__(self):
        table = []
        for byte in range(256):
            c = byte << 8
            for _ in range(8):
                c = ((c << 1) ^ self.poly) if c & 0x8000 else (c << 1)
            table.append(c & 0xFFFF)
        object.__setattr__(self, "_table", tuple(table))

    def __call__(self, data) -> int:
        crc, table = self.init, self._table
        for b in data:
            crc = ((crc << 8) & 0xFFFF) ^ table[(crc >> 8) ^ b]
        return crc ^ self.xorout


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
        try:
            return self.frames[name]
        except KeyError:
            raise ProtocolError(f"unknown frame type {name!r} (types: {sorted(self.frames)})") from None

    def error_name(self, code: int) -> str:
        return next((c.name for c in self.error_codes if c.value == code), f"UNKNOWN_{code}")

    def error_code(self, name: str) -> int:
        for c in self.error_codes:
            if c.name == name:
                return c.value
        raise ProtocolError(f"unknown error code {name!r} (codes: {[c.name for c in self.error_codes]})")

    def status_bit(self, name: str) -> int:
        for c in self.status_flags:
            if c.name == name:
                return 1 << c.value
        raise ProtocolError(f"unknown status flag {name!r}")


def _take(d: dict, where: str, required: tuple, optional: tuple = ()) -> dict:
    if not isinstance(d, dict):
        raise ProtocolError(f"{where}: expected a mapping, got {d!r}")
    unknown = set(d) - set(required) - set(optional)
    missing = [k for k in required if k not in d]
    if unknown:
        raise ProtocolError(f"{where}: unknown key(s) {sorted(unknown)}")
    if missing:
        raise ProtocolError(f"{where}: missing key(s) {missing}")
    return d


def _int(v, where: str, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise ProtocolError(f"{where}: expected an integer from {lo} to {hi}, got {v!r}")
    return v


def _seconds(v, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ProtocolError(f"{where}: expected a time > 0 [s], got {v!r}")
    if abs(v * 1000 - round(v * 1000)) > 1e-9:
        raise ProtocolError(f"{where}: {v} s is not a whole number of milliseconds (the firmware counts ms)")
    return float(v)


def _codes(items, where: str, key: str, hi: int) -> tuple:
    if not isinstance(items, list) or not items:
        raise ProtocolError(f"{where}: expected a non-empty list")
    out, seen = [], set()
    for i, c in enumerate(items):
        w = f"{where}[{i}]"
        _take(c, w, (key, "name", "description"))
        value = _int(c[key], f"{w}.{key}", 0 if key == "bit" else 1, hi)
        if value in seen or c["name"] in {o.name for o in out}:
            raise ProtocolError(f"{w}: duplicate {key} {value} or name {c['name']!r}")
        if not re.fullmatch(r"[A-Z][A-Z0-9_]*", str(c["name"])):
            raise ProtocolError(f"{w}.name: expected UPPER_CASE, got {c['name']!r}")
        seen.add(value)
        out.append(Code(value, c["name"], str(c["description"])))
    return tuple(out)


def parse_protocol(doc: dict, source: str = "<dict>") -> Protocol:
    """Check a protocol description (the content of ``protocol.yaml``) and build a :class:`Protocol`."""
    top = ("name", "version", "byte_order", "sync", "max_payload", "wheel_index_max", "serial", "crc",
           "sequence", "encoder", "timing", "frames", "error_codes", "status_flags")
    _take(doc, source, top)
    version = _int(doc["version"], f"{source}: version", 1, 255)
    if doc["byte_order"] != "little":
        raise ProtocolError(f"{source}: byte_order: only 'little' is implemented, got {doc['byte_order']!r}")
    sync = doc["sync"]
    if not isinstance(sync, list) or len(sync) != 2 or len(set(sync)) != 2:
        raise ProtocolError(f"{source}: sync: expected two different bytes, got {sync!r}")
    sync = bytes(_int(b, f"{source}: sync", 0, 255) for b in sync)
    max_payload = _int(doc["max_payload"], f"{source}: max_payload", 1, 255 - HEADER_BYTES - CRC_BYTES - 2)
    wheel_max = _int(doc["wheel_index_max"], f"{source}: wheel_index_max", 0, 254)
    ser = _take(doc["serial"], f"{source}: serial", ("baud", "bytesize", "parity", "stopbits"))
    _int(ser["baud"], f"{source}: serial.baud", 50, 10_000_000)
    _int(ser["bytesize"], f"{source}: serial.bytesize", 5, 8)
    _int(ser["stopbits"], f"{source}: serial.stopbits", 1, 2)
    if ser["parity"] not in ("none", "even", "odd"):
        raise ProtocolError(f"{source}: serial.parity: expected none, even or odd, got {ser['parity']!r}")
    c = _take(doc["crc"], f"{source}: crc", ("name", "width", "poly", "init", "refin", "refout", "xorout", "check",
                                              "covers"))
    if c["width"] != 16 or c["refin"] or c["refout"]:
        raise ProtocolError(f"{source}: crc: only non-reflected 16-bit CRCs are implemented")
    crc = Crc(str(c["name"]), 16, _int(c["poly"], "crc.poly", 1, 0xFFFF), _int(c["init"], "crc.init", 0, 0xFFFF),
              False, False, _int(c["xorout"], "crc.xorout", 0, 0xFFFF), _int(c["check"], "crc.check", 0, 0xFFFF),
              str(c["covers"]))
    if crc(b"123456789") != crc.check:
        raise ProtocolError(f"{source}: crc: the parameters give check 0x{crc(b'123456789'):04X}, "
                            f"the file says 0x{crc.check:04X}")
    seq = _take(doc["sequence"], f"{source}: sequence", ("modulo", "resync_after"))
    if seq["modulo"] != 256:
        raise ProtocolError(f"{source}: sequence.modulo: the sequence is one byte (256), got {seq['modulo']!r}")
    resync = _int(seq["resync_after"], f"{source}: sequence.resync_after", 1, 127)
    enc = _take(doc["encoder"], f"{source}: encoder", ("counter_bits",))
    bits = _int(enc["counter_bits"], f"{source}: encoder.counter_bits", 2, 32)
    tm = _take(doc["timing"], f"{source}: timing", ("heartbeat_period", "report_period", "link_timeout",
                                                     "connect_timeout"))
    timing = Timing(*(_seconds(tm[k], f"{source}: timing.{k}") for k in
                      ("heartbeat_period", "report_period", "link_timeout", "connect_timeout")))
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
            raise ProtocolError(f"{w}.direction: expected one of {DIRECTIONS}, got {ft['direction']!r}")
        flist = []
        for i, fd in enumerate(ft["fields"] or []):
            fw = f"{w}.fields[{i}]"
            _take(fd, fw, ("name", "type"), ("description", "unit", "scale", "wraps", "table", "max_length"))
            if fd["type"] not in INT_TYPES and fd["type"] != "text":
                raise ProtocolError(f"{fw}.type: expected one of {sorted(INT_TYPES) + ['text']}, got {fd['type']!r}")
            if not re.fullmatch(r"[a-z][a-z0-9_]*", str(fd["name"])) or fd["name"] in {f.name for f in flist}:
                raise ProtocolError(f"{fw}.name: expected a new lower_case name, got {fd['name']!r}")
            scale = fd.get("scale")
            if scale is not None and (isinstance(scale, bool) or not isinstance(scale, (int, float))
                                      or not math.isfinite(scale) or scale <= 0 or fd["type"] == "text"):
                raise ProtocolError(f"{fw}.scale: expected a number > 0 on an integer field, got {scale!r}")
            if fd.get("table") is not None and fd["table"] not in tables:
                raise ProtocolError(f"{fw}.table: expected one of {sorted(tables)}, got {fd['table']!r}")
            max_length = 0
            if fd["type"] == "text":
                max_length = _int(fd.get("max_length"), f"{fw}.max_length", 1, max_payload)
                if i != len(ft["fields"]) - 1:
                    raise ProtocolError(f"{fw}: a text field must be the last field")
            flist.append(Field(fd["name"], fd["type"], str(fd.get("description", "")), str(fd.get("unit", "")),
                               None if scale is None else float(scale), bool(fd.get("wraps", False)),
                               fd.get("table"), max_length))
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
    return Protocol(str(doc["name"]), version, "little", sync, max_payload, wheel_max, dict(ser), crc, 256, resync,
                    bits, timing, frames, error_codes, status_flags, source)


def load_protocol(path=None) -> Protocol:
    """The protocol of ``path`` (default: the package's ``protocol.yaml``, read once)."""
    if path is None:
        return _default_protocol()
    import yaml

    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ProtocolError(f"{path}: cannot read the protocol description: {exc}") from None
    return parse_protocol(doc, str(path))


@lru_cache(maxsize=1)
def _default_protocol() -> Protocol:
    import yaml

    text = resources.files(__package__).joinpath("protocol.yaml").read_text(encoding="utf-8")
    return parse_protocol(yaml.safe_load(text), "omnikin/runtime/protocol.yaml")


def crc16_ccitt_false(data) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor) of ``data``."""
    return _CCITT_FALSE(data)


_CCITT_FALSE = Crc("CRC-16/CCITT-FALSE", 16, 0x1021, 0xFFFF, False, False, 0, 0x29B1, "")


# --- encoding ---------------------------------------------------------------------------------


def round_half_away(x: float) -> int:
    """Nearest integer, halves away from zero (as C's ``lround``)."""
    return math.floor(abs(x) + 0.5) * (1 if x >= 0 else -1)


def to_raw(f: Field, value) -> int:
    """Physical value -> wire integer of field ``f`` (checked against its type's range)."""
    if isinstance(value, bool):
        value = int(value)
    if f.scale is not None:
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ProtocolError(f"field {f.name}: expected a finite number, got {value!r}")
        raw = round_half_away(value / f.scale)
    else:
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if not isinstance(value, int):
            raise ProtocolError(f"field {f.name}: expected an integer, got {value!r}")
        raw = value
    _, _, _, lo, hi = INT_TYPES[f.type]
    if f.wraps and f.scale is None:
        span = hi - lo + 1
        raw = (raw - lo) % span + lo
    if not lo <= raw <= hi:
        unit = f" {f.unit}" if f.unit else ""
        raise ProtocolError(f"field {f.name}: {value!r}{unit} is outside the range of {f.type}"
                            + (f" at scale {f.scale:g}" if f.scale else ""))
    return raw


def pack_payload(ft: FrameType, values: dict, raw: bool = False) -> bytes:
    """Payload bytes of frame type ``ft``; ``values`` physical (``raw``: wire integers)."""
    names = {f.name for f in ft.fields}
    unknown = set(values) - names
    if unknown:
        raise ProtocolError(f"{ft.name}: unknown field(s) {sorted(unknown)} (fields: {[f.name for f in ft.fields]})")
    ints = []
    for f in ft.fixed:
        if f.name not in values:
            raise ProtocolError(f"{ft.name}: field {f.name!r} is missing")
        v = values[f.name]
        ints.append(to_raw(f, v) if not raw else to_raw(Field(f.name, f.type, wraps=f.wraps), v))
    out = struct.pack(ft.struct_format, *ints)
    if ft.text is not None:
        text = values.get(ft.text.name, "")
        data = text.encode("ascii", "replace") if isinstance(text, str) else bytes(text)
        if len(data) > ft.text.max_length:
            raise ProtocolError(f"{ft.name}: text of {len(data)} bytes exceeds {ft.text.max_length}")
        out += data
    return out


def unpack_payload(ft: FrameType, payload: bytes) -> tuple[dict, dict]:
    """``(raw, physical)`` field values of a payload whose length ``ft`` accepts."""
    ints = struct.unpack_from(ft.struct_format, payload)
    raw, phys = {}, {}
    for f, v in zip(ft.fixed, ints):
        raw[f.name] = v
        phys[f.name] = v * f.scale if f.scale is not None else v
    if ft.text is not None:
        text = bytes(payload[ft.min_size:])
        raw[ft.text.name] = text
        phys[ft.text.name] = text.decode("ascii", "replace")
    return raw, phys


def frame_bytes(protocol: Protocol, type_id: int, seq: int, payload: bytes, version: int | None = None) -> bytes:
    """A complete frame around ``payload`` (``version`` overrides the protocol's, for tests)."""
    if not 0 <= seq <= 255:
        raise ProtocolError(f"sequence number must be 0..255, got {seq}")
    if len(payload) > protocol.max_payload:
        raise ProtocolError(f"payload of {len(payload)} bytes exceeds max_payload {protocol.max_payload}")
    body = bytes((protocol.version if version is None else version, type_id, seq, len(payload))) + bytes(payload)
    return protocol.sync + body + protocol.crc(body).to_bytes(2, "little")


def encode(name: str, seq: int, protocol: Protocol | None = None, raw: bool = False, **values) -> bytes:
    """One frame of type ``name`` with sequence number ``seq`` (``values``: physical, or wire with ``raw``)."""
    p = protocol or load_protocol()
    ft = p.frame(name)
    wheel = values.get("wheel")
    if isinstance(wheel, int) and not isinstance(wheel, bool) and wheel > p.wheel_index_max:
        raise ProtocolError(f"wheel index {wheel} is beyond {p.wheel_index_max} (255 is reserved)")
    return frame_bytes(p, ft.id, seq, pack_payload(ft, values, raw))


class FrameEncoder:
    """Encodes frames numbering each wheel's stream 0, 1, ... 255, 0, ... (one sender, one direction)."""

    def __init__(self, protocol: Protocol | None = None):
        self.protocol = protocol or load_protocol()
        self._seq: dict[int, int] = {}

    def peek(self, wheel: int) -> int:
        """The number the next frame of ``wheel`` will carry."""
        return self._seq.get(wheel, 0)

    def next_seq(self, wheel: int) -> int:
        s = self._seq.get(wheel, 0)
        self._seq[wheel] = (s + 1) % 256
        return s

    def encode(self, name: str, raw: bool = False, **values) -> bytes:
        if "wheel" not in values:
            raise ProtocolError(f"{name}: field 'wheel' is missing")
        frame = encode(name, self._seq.get(values["wheel"], 0), self.protocol, raw, **values)
        self.next_seq(values["wheel"])
        return frame

    def reset(self, wheel: int | None = None) -> None:
        if wheel is None:
            self._seq.clear()
        else:
            self._seq.pop(wheel, None)


# --- decoding ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Message:
    """A decoded frame: ``fields`` physical (scaled) values, ``raw`` the wire integers."""

    name: str
    type_id: int
    seq: int
    wheel: int
    fields: dict
    raw: dict
    frame: bytes = b""

    def __getitem__(self, key):
        return self.fields[key]


@dataclass
class DecoderStats:
    """What a :class:`StreamDecoder` accepted and rejected (module docstring)."""

    frames_ok: int = 0
    corrupt: int = 0
    short: int = 0
    bad_version: int = 0
    unknown_type: int = 0
    bad_length: int = 0
    wrong_direction: int = 0
    bad_wheel: int = 0
    duplicates: int = 0
    out_of_order: int = 0
    lost: int = 0
    resyncs: int = 0
    skipped_bytes: int = 0
    bytes_in: int = 0
    internal_errors: int = 0

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in dc_fields(self)}

    def add(self, other: DecoderStats) -> None:
        for f in dc_fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))


SEQ_FIRST, SEQ_OK, SEQ_GAP, SEQ_DUPLICATE, SEQ_OUT_OF_ORDER, SEQ_RESYNC = range(6)  # as OMNIKIN_SEQ_* in C


class SequenceTracker:
    """The sequence rules of one stream (the C header has the same ``omnikin_seq_check``)."""

    def __init__(self, resync_after: int):
        self.resync_after = resync_after
        self.last: int | None = None
        self.rejects = 0

    def check(self, seq: int) -> tuple[int, int]:
        """``(verdict, frames lost)``; SEQ_DUPLICATE and SEQ_OUT_OF_ORDER mean: drop the frame."""
        if self.last is None:
            self.last, self.rejects = seq, 0
            return SEQ_FIRST, 0
        d = (seq - self.last) % 256
        if d == 0:
            return SEQ_DUPLICATE, 0
        if d < 128:
            self.last, self.rejects = seq, 0
            return (SEQ_OK, 0) if d == 1 else (SEQ_GAP, d - 1)
        self.rejects += 1
        if self.rejects >= self.resync_after:
            self.last, self.rejects = seq, 0
            return SEQ_RESYNC, 0
        return SEQ_OUT_OF_ORDER, 0

    def restart(self, seq: int) -> None:
        self.last, self.rejects = seq, 0


class StreamDecoder:
    """Bytes in, :class:`Message` s out, whatever the bytes (module docstring).

    ``direction``: the direction of the frames this side receives (``controller_to_host``
    on the host, ``host_to_controller`` on a controller); frames of types only the other
    direction carries are counted as ``wrong_direction`` and dropped. None accepts all.
    """

    def __init__(self, protocol: Protocol | None = None, direction: str | None = "controller_to_host",
                 check_sequence: bool = True):
        if direction is not None and direction not in DIRECTIONS[:2]:
            raise ProtocolError(f"direction must be one of {DIRECTIONS[:2]} or None, got {direction!r}")
        self.protocol = protocol or load_protocol()
        self.direction = direction
        self.check_sequence = check_sequence
        self.stats = DecoderStats()
        self.streams: dict[int, SequenceTracker] = {}
        self._buf = bytearray()
        self._reset_code = self.protocol.error_code("RESET")

    @property
    def pending(self) -> int:
        """Bytes held back waiting for the rest of a frame."""
        return len(self._buf)

    def feed(self, data) -> list[Message]:
        """Decode what ``data`` completes; never raises on bad bytes (they are counted)."""
        self._buf += data
        self.stats.bytes_in += len(data)
        try:
            return self._parse()
        except Exception:  # a bug must not take the link down; counted and visible in stats
            self.stats.internal_errors += 1
            self._skip(len(self._buf))
            return []

    def flush(self) -> None:
        """The stream stopped: bytes of an unfinished frame are counted as a short frame."""
        if self._buf:
            if self._buf.startswith(self.protocol.sync):
                self.stats.short += 1
            self._skip(len(self._buf))

    def restart_stream(self, wheel: int | None = None) -> None:
        """Forget the sequence state of one wheel (None: all)."""
        if wheel is None:
            self.streams.clear()
        else:
            self.streams.pop(wheel, None)

    # -- internals --
    def _skip(self, n: int) -> None:
        del self._buf[:n]
        self.stats.skipped_bytes += n

    def _candidate(self, j: int):
        """At offset ``j`` (a sync): True valid frame, False not one, None not enough bytes yet."""
        p, buf = self.protocol, self._buf
        h = p.header_size
        if len(buf) < j + h:
            return None
        length = buf[j + h - 1]
        if length > p.max_payload:
            return False
        n = h + length + CRC_BYTES
        if len(buf) < j + n:
            return None
        return p.crc(buf[j + len(p.sync): j + h + length]) == int.from_bytes(buf[j + n - 2: j + n], "little")

    def _inner_frame(self, end: int):
        """After a rejected candidate at 0 that claimed ``end`` bytes: ``(offset, cut)`` of a valid
        frame starting inside it, ``cut`` counting the frame starts before it that did not
        complete (the candidate included); ``(0, 0)`` if there is none; None to wait for bytes."""
        sync = self.protocol.sync
        j = self._buf.find(sync, 1, end + len(sync) - 1)
        cut = 1
        while j > 0:
            verdict = self._candidate(j)
            if verdict is None:
                return None
            if verdict:
                return j, cut
            cut += 1
            j = self._buf.find(sync, j + 1, end + len(sync) - 1)
        return 0, 0

    def _parse(self) -> list[Message]:
        p, buf, st = self.protocol, self._buf, self.stats
        sync, h = p.sync, p.header_size
        out = []
        while buf:
            i = buf.find(sync)
            if i < 0:
                keep = 1 if buf[-1] == sync[0] else 0
                self._skip(len(buf) - keep)
                break
            if i:
                self._skip(i)
            if len(buf) < h:
                break
            length = buf[h - 1]
            if length > p.max_payload:
                end = h
            else:
                end = h + length + CRC_BYTES
                if len(buf) < end:
                    break
                body = buf[len(sync): h + length]
                if p.crc(body) == int.from_bytes(buf[end - 2: end], "little"):
                    version, type_id, seq = body[0], body[1], body[2]
                    payload, frame = bytes(buf[h: h + length]), bytes(buf[:end])
                    del buf[:end]
                    msg = self._accept(version, type_id, seq, payload, frame)
                    if msg is None:
                        st.skipped_bytes += end
                    else:
                        out.append(msg)
                    continue
            inner = self._inner_frame(end)
            if inner is None:
                break
            if inner[0]:
                st.short += inner[1]
                self._skip(inner[0])
            else:
                st.corrupt += 1
                self._skip(1)
        return out

    def _accept(self, version: int, type_id: int, seq: int, payload: bytes, frame: bytes) -> Message | None:
        p, st = self.protocol, self.stats
        if version != p.version:
            st.bad_version += 1
            return None
        ft = p.by_id.get(type_id)
        if ft is None:
            st.unknown_type += 1
            return None
        if self.direction is not None and ft.direction not in (self.direction, "both"):
            st.wrong_direction += 1
            return None
        if not ft.accepts(len(payload)):
            st.bad_length += 1
            return None
        raw, phys = unpack_payload(ft, payload)
        wheel = raw["wheel"]
        if wheel > p.wheel_index_max:
            st.bad_wheel += 1
            return None
        if self.check_sequence:
            tracker = self.streams.setdefault(wheel, SequenceTracker(p.resync_after))
            if ft.name == "ERROR_REPORT" and raw.get("code") == self._reset_code:
                tracker.restart(seq)
            else:
                verdict, lost = tracker.check(seq)
                if verdict == SEQ_DUPLICATE:
                    st.duplicates += 1
                    return None
                if verdict == SEQ_OUT_OF_ORDER:
                    st.out_of_order += 1
                    return None
                if verdict == SEQ_RESYNC:
                    st.out_of_order += 1
                    st.resyncs += 1
                st.lost += lost
        st.frames_ok += 1
        return Message(ft.name, type_id, seq, wheel, phys, raw, frame)


# --- generators: C header and documentation tables ----------------------------------------------

HEADER_COMMAND = "python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h"
DOC_COMMAND = "python -m omnikin.runtime.protocol --update-doc docs/protocol.md"


def _c_float(x: float) -> str:
    s = repr(float(x))
    if "e" not in s and "." not in s:
        s += ".0"
    return s + "f"


def _c_comment(text: str) -> str:
    return text.replace("*/", "* /")


def _ms(seconds: float) -> int:
    return round(seconds * 1000)


def generate_header(protocol: Protocol | None = None) -> str:
    """The C header of the firmware (C99 / C++, no allocation, little-endian wire)."""
    p = protocol or load_protocol()
    t = p.timing
    L = []
    a = L.append
    a("/* omnikin_protocol.h: the omnikin wheel-controller protocol for C and C++ (Arduino).")
    a(" *")
    a(" * GENERATED from src/omnikin/runtime/protocol.yaml by")
    a(f" *   {HEADER_COMMAND}")
    a(" * Do not edit: change protocol.yaml and regenerate. Specification: docs/protocol.md.")
    a(" */")
    a("#ifndef OMNIKIN_PROTOCOL_H")
    a("#define OMNIKIN_PROTOCOL_H")
    a("")
    a("#include <stdint.h>")
    a("#include <string.h>")
    a("")
    a(f"#define OMNIKIN_PROTOCOL_VERSION {p.version}")
    for i, b in enumerate(p.sync):
        a(f"#define OMNIKIN_SYNC_{i} 0x{b:02X}")
    a(f"#define OMNIKIN_SYNC_SIZE {len(p.sync)}")
    a(f"#define OMNIKIN_HEADER_SIZE {p.header_size} /* sync, version, type, sequence, length */")
    a(f"#define OMNIKIN_CRC_SIZE {CRC_BYTES}")
    a(f"#define OMNIKIN_MAX_PAYLOAD {p.max_payload}")
    a("#define OMNIKIN_MAX_FRAME (OMNIKIN_HEADER_SIZE + OMNIKIN_MAX_PAYLOAD + OMNIKIN_CRC_SIZE)")
    a(f"#define OMNIKIN_WHEEL_INDEX_MAX {p.wheel_index_max}")
    a(f"#define OMNIKIN_SEQ_RESYNC_AFTER {p.resync_after}")
    a(f"#define OMNIKIN_COUNTER_BITS {p.counter_bits}")
    a("")
    a("/* serial link */")
    a(f"#define OMNIKIN_BAUD {int(p.serial['baud'])}UL")
    a("")
    a("/* timing [ms] */")
    a(f"#define OMNIKIN_HEARTBEAT_PERIOD_MS {_ms(t.heartbeat_period)}UL")
    a(f"#define OMNIKIN_REPORT_PERIOD_MS {_ms(t.report_period)}UL")
    a(f"#define OMNIKIN_LINK_TIMEOUT_MS {_ms(t.link_timeout)}UL")
    a(f"#define OMNIKIN_CONNECT_TIMEOUT_MS {_ms(t.connect_timeout)}UL")
    a("")
    a(f"/* {p.crc.name}: {_c_comment(p.crc.covers)} */")
    a(f"#define OMNIKIN_CRC_POLY 0x{p.crc.poly:04X}u")
    a(f"#define OMNIKIN_CRC_INIT 0x{p.crc.init:04X}u")
    a(f"#define OMNIKIN_CRC_XOROUT 0x{p.crc.xorout:04X}u")
    a(f"#define OMNIKIN_CRC_CHECK 0x{p.crc.check:04X}u /* of the ASCII bytes \"123456789\" */")
    a("")
    a("/* frame types */")
    for ft in p.frames.values():
        a(f"#define OMNIKIN_TYPE_{ft.name} 0x{ft.id:02X} /* {ft.direction.replace('_', ' ')} */")
    a("")
    a("/* error codes (ERROR_REPORT.code) */")
    for c in p.error_codes:
        a(f"#define OMNIKIN_ERR_{c.name} {c.value} /* {_c_comment(c.description)} */")
    a("")
    a("/* status flags (HEARTBEAT.status), bit masks */")
    for c in p.status_flags:
        a(f"#define OMNIKIN_STATUS_{c.name} 0x{1 << c.value:02X} /* {_c_comment(c.description)} */")
    a("")
    a(_C_HELPERS)
    for ft in p.frames.values():
        low = ft.name.lower()
        a(f"/* {ft.name} (0x{ft.id:02X}, {ft.direction.replace('_', ' ')}): {_c_comment(ft.description)} */")
        if ft.text is None:
            a(f"#define OMNIKIN_{ft.name}_SIZE {ft.min_size}")
        else:
            a(f"#define OMNIKIN_{ft.name}_MIN_SIZE {ft.min_size}")
            a(f"#define OMNIKIN_{ft.name}_MAX_SIZE {ft.max_size}")
            a(f"#define OMNIKIN_{ft.name}_{ft.text.name.upper()}_MAX {ft.text.max_length}")
        for f in ft.fixed:
            if f.scale is not None:
                a(f"#define OMNIKIN_{ft.name}_{f.name.upper()}_SCALE {_c_float(f.scale)} /* {f.unit} per count */")
        a("typedef struct {")
        for f in ft.fixed:
            unit = f" [{f.unit}{' x ' + _c_float(f.scale)[:-1] if f.scale else ''}]" if f.unit else ""
            a(f"    {INT_TYPES[f.type][2]} {f.name};{' ' * max(1, 12 - len(f.name))}/* {_c_comment(f.description)}{unit} */")
        if ft.text is not None:
            a(f"    uint8_t {ft.text.name}_len;")
            a(f"    char {ft.text.name}[{ft.text.max_length}]; /* {_c_comment(ft.text.description)} */")
        a(f"}} omnikin_{low}_t;")
        a("")
        a(f"static inline uint8_t omnikin_pack_{low}(uint8_t *payload, const omnikin_{low}_t *m) {{")
        off = 0
        for f in ft.fixed:
            a("    " + _c_put(f, off))
            off += f.size
        if ft.text is not None:
            tn = ft.text.name
            a(f"    uint8_t n = m->{tn}_len > {ft.text.max_length} ? {ft.text.max_length} : m->{tn}_len;")
            a(f"    memcpy(payload + {off}, m->{tn}, n);")
            a(f"    return (uint8_t)({off} + n);")
        else:
            a(f"    return {off};")
        a("}")
        a("")
        a(f"static inline uint8_t omnikin_unpack_{low}(const uint8_t *payload, uint8_t len, omnikin_{low}_t *m) {{")
        if ft.text is None:
            a(f"    if (len != {ft.min_size}) return 0;")
        else:
            a(f"    if (len < {ft.min_size} || len > {ft.max_size}) return 0;")
        off = 0
        for f in ft.fixed:
            a("    " + _c_get(f, off))
            off += f.size
        if ft.text is not None:
            tn = ft.text.name
            a(f"    m->{tn}_len = (uint8_t)(len - {off});")
            a(f"    memcpy(m->{tn}, payload + {off}, m->{tn}_len);")
        a("    return 1;")
        a("}")
        a("")
        a(f"static inline uint8_t omnikin_encode_{low}(uint8_t *out, uint8_t seq, const omnikin_{low}_t *m) {{")
        a(f"    uint8_t payload[{ft.max_size}];")
        a(f"    uint8_t len = omnikin_pack_{low}(payload, m);")
        a(f"    return omnikin_frame(out, OMNIKIN_TYPE_{ft.name}, seq, payload, len);")
        a("}")
        a("")
    a("#endif /* OMNIKIN_PROTOCOL_H */")
    return "\n".join(L) + "\n"


def _c_put(f: Field, off: int) -> str:
    size = f.size
    if size == 1:
        return f"payload[{off}] = (uint8_t)m->{f.name};"
    return f"omnikin_put_u{8 * size}(payload + {off}, (uint{8 * size}_t)m->{f.name});"


def _c_get(f: Field, off: int) -> str:
    size, ctype = f.size, INT_TYPES[f.type][2]
    if size == 1:
        return f"m->{f.name} = ({ctype})payload[{off}];"
    return f"m->{f.name} = ({ctype})omnikin_get_u{8 * size}(payload + {off});"


_C_HELPERS = r"""/* --- little-endian helpers ------------------------------------------------------------ */
static inline void omnikin_put_u16(uint8_t *p, uint16_t v) {
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8);
}
static inline void omnikin_put_u32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline uint16_t omnikin_get_u16(const uint8_t *p) {
    return (uint16_t)(p[0] | ((uint16_t)p[1] << 8));
}
static inline uint32_t omnikin_get_u32(const uint8_t *p) {
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* --- CRC (bitwise: no table in RAM) ------------------------------------------------------ */
static inline uint16_t omnikin_crc16_update(uint16_t crc, uint8_t byte) {
    uint8_t i;
    crc ^= (uint16_t)((uint16_t)byte << 8);
    for (i = 0; i < 8; i++) {
        crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ OMNIKIN_CRC_POLY) : (uint16_t)(crc << 1);
    }
    return crc;
}
static inline uint16_t omnikin_crc16(const uint8_t *data, uint16_t n) {
    uint16_t crc = OMNIKIN_CRC_INIT;
    uint16_t i;
    for (i = 0; i < n; i++) crc = omnikin_crc16_update(crc, data[i]);
    return (uint16_t)(crc ^ OMNIKIN_CRC_XOROUT);
}

/* --- framing ------------------------------------------------------------------------------ */
/* Write a whole frame into out (room for OMNIKIN_MAX_FRAME bytes); returns its size. */
static inline uint8_t omnikin_frame(uint8_t *out, uint8_t type, uint8_t seq, const uint8_t *payload, uint8_t len) {
    uint16_t crc;
    if (len > OMNIKIN_MAX_PAYLOAD) return 0;
    out[0] = OMNIKIN_SYNC_0;
    out[1] = OMNIKIN_SYNC_1;
    out[2] = OMNIKIN_PROTOCOL_VERSION;
    out[3] = type;
    out[4] = seq;
    out[5] = len;
    memcpy(out + OMNIKIN_HEADER_SIZE, payload, len);
    crc = omnikin_crc16(out + OMNIKIN_SYNC_SIZE, (uint16_t)(OMNIKIN_HEADER_SIZE - OMNIKIN_SYNC_SIZE + len));
    omnikin_put_u16(out + OMNIKIN_HEADER_SIZE + len, crc);
    return (uint8_t)(OMNIKIN_HEADER_SIZE + len + OMNIKIN_CRC_SIZE);
}

/* Streaming parser: feed bytes one by one; omnikin_parse_byte returns 1 when a frame with a
 * valid CRC and this protocol version is complete: type p->buf[3], sequence p->buf[4],
 * payload p->buf + OMNIKIN_HEADER_SIZE of p->buf[5] bytes (valid until the next call).
 * After a rejected candidate it rescans from the byte after its first sync byte. */
typedef struct {
    uint8_t buf[OMNIKIN_MAX_FRAME];
    uint8_t n;           /* bytes held */
    uint8_t frame_size;  /* size of the frame returned by the previous call, to drop */
    uint16_t frames_ok, crc_errors, bad_version, skipped;
} omnikin_parser_t;

static inline void omnikin_parser_init(omnikin_parser_t *p) {
    memset(p, 0, sizeof(*p));
}

static inline void omnikin_parser_drop(omnikin_parser_t *p, uint8_t k) {
    memmove(p->buf, p->buf + k, (size_t)(p->n - k));
    p->n = (uint8_t)(p->n - k);
}

static inline uint8_t omnikin_parser_scan(omnikin_parser_t *p) {
    for (;;) {
        uint8_t len, size;
        if (p->n >= 1 && p->buf[0] != OMNIKIN_SYNC_0) { omnikin_parser_drop(p, 1); p->skipped++; continue; }
        if (p->n >= 2 && p->buf[1] != OMNIKIN_SYNC_1) { omnikin_parser_drop(p, 1); p->skipped++; continue; }
        if (p->n < OMNIKIN_HEADER_SIZE) return 0;
        len = p->buf[5];
        if (len > OMNIKIN_MAX_PAYLOAD) { p->crc_errors++; omnikin_parser_drop(p, 1); p->skipped++; continue; }
        size = (uint8_t)(OMNIKIN_HEADER_SIZE + len + OMNIKIN_CRC_SIZE);
        if (p->n < size) return 0;
        if (omnikin_crc16(p->buf + OMNIKIN_SYNC_SIZE, (uint16_t)(OMNIKIN_HEADER_SIZE - OMNIKIN_SYNC_SIZE + len))
                != omnikin_get_u16(p->buf + OMNIKIN_HEADER_SIZE + len)) {
            p->crc_errors++; omnikin_parser_drop(p, 1); p->skipped++; continue;
        }
        if (p->buf[2] != OMNIKIN_PROTOCOL_VERSION) {
            p->bad_version++; omnikin_parser_drop(p, size); p->skipped = (uint16_t)(p->skipped + size); continue;
        }
        p->frames_ok++;
        p->frame_size = size;
        return 1;
    }
}

static inline uint8_t omnikin_parse_byte(omnikin_parser_t *p, uint8_t b) {
    if (p->frame_size) { omnikin_parser_drop(p, p->frame_size); p->frame_size = 0; }
    if (p->n >= OMNIKIN_MAX_FRAME) { omnikin_parser_drop(p, 1); p->skipped++; }
    p->buf[p->n++] = b;
    return omnikin_parser_scan(p);
}

/* Sequence rules of one stream (one direction of one wheel), as the host applies them. */
#define OMNIKIN_SEQ_FIRST 0        /* first frame of the stream: accept */
#define OMNIKIN_SEQ_OK 1           /* next number: accept */
#define OMNIKIN_SEQ_GAP 2          /* numbers skipped (frames lost): accept */
#define OMNIKIN_SEQ_DUPLICATE 3    /* same number again: drop */
#define OMNIKIN_SEQ_OUT_OF_ORDER 4 /* a number from the past: drop */
#define OMNIKIN_SEQ_RESYNC 5       /* OMNIKIN_SEQ_RESYNC_AFTER out-of-order numbers in a row: sender restarted, accept */
typedef struct {
    uint8_t last;
    uint8_t have;
    uint8_t rejects;
} omnikin_seq_t;

static inline uint8_t omnikin_seq_check(omnikin_seq_t *s, uint8_t seq) {
    uint8_t d;
    if (!s->have) { s->have = 1; s->last = seq; s->rejects = 0; return OMNIKIN_SEQ_FIRST; }
    d = (uint8_t)(seq - s->last);
    if (d == 0) return OMNIKIN_SEQ_DUPLICATE;
    if (d < 128) { s->last = seq; s->rejects = 0; return d == 1 ? OMNIKIN_SEQ_OK : OMNIKIN_SEQ_GAP; }
    if (++s->rejects >= OMNIKIN_SEQ_RESYNC_AFTER) { s->last = seq; s->rejects = 0; return OMNIKIN_SEQ_RESYNC; }
    return OMNIKIN_SEQ_OUT_OF_ORDER;
}

static inline void omnikin_seq_restart(omnikin_seq_t *s, uint8_t seq) {
    s->have = 1; s->last = seq; s->rejects = 0;
}

/* --- frame types ----------------------------------------------------------------------------- */"""


def _md_table(head: list, rows: list) -> str:
    out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    out += ["| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |" for r in rows]
    return "\n".join(out)


def doc_blocks(protocol: Protocol | None = None) -> dict:
    """The generated parts of ``docs/protocol.md``, by block name."""
    p = protocol or load_protocol()
    t = p.timing
    h = p.header_size
    blocks = {}
    blocks["constants"] = _md_table(["constant", "value"], [
        ["protocol name", f"`{p.name}`"],
        ["version", p.version],
        ["sync bytes", " ".join(f"`0x{b:02X}`" for b in p.sync)],
        ["byte order", "little-endian (the CRC included)"],
        ["header", f"{h} bytes (sync, version, type, sequence, length)"],
        ["max payload", f"{p.max_payload} bytes (frame: {p.max_frame} bytes)"],
        ["wheel indices", f"0 to {p.wheel_index_max} (255 reserved)"],
        ["sequence", f"one byte, modulo {p.seq_modulo}, per direction and wheel; "
                     f"resync after {p.resync_after} out-of-order frames in a row"],
        ["encoder counter", f"{p.counter_bits}-bit two's complement, wraps"],
        ["serial defaults", f"{p.serial['baud']} baud, {p.serial['bytesize']} data bits, "
                            f"parity {p.serial['parity']}, {p.serial['stopbits']} stop bit"],
    ])
    blocks["envelope"] = _md_table(["offset", "size", "field", "content"], [
        [0, len(p.sync), "sync", " ".join(f"`0x{b:02X}`" for b in p.sync)],
        [h - 4, 1, "version", f"`{p.version}`"],
        [h - 3, 1, "type", "frame type id (table below)"],
        [h - 2, 1, "seq", "sequence number of the stream (direction, wheel), 0-255"],
        [h - 1, 1, "length", f"payload length n, 0-{p.max_payload}"],
        [h, "n", "payload", "fields of the type, the wheel index first"],
        [f"{h} + n", CRC_BYTES, "crc", f"{p.crc.name} of bytes {len(p.sync)} to {h - 1} + n, little-endian"],
    ])
    blocks["types"] = _md_table(["id", "type", "direction", "payload [bytes]", "meaning"], [
        [f"`0x{ft.id:02X}`", ft.name, ft.direction.replace("_", " "),
         ft.min_size if ft.text is None else f"{ft.min_size}-{ft.max_size}", ft.description]
        for ft in p.frames.values()])
    parts = []
    for ft in p.frames.values():
        rows, off = [], 0
        for f in ft.fields:
            size = f.size if f.type != "text" else f"0-{f.max_length}"
            notes = [f.description]
            if f.scale is not None:
                notes.append(f"value = raw x {f.scale:g}")
            if f.wraps:
                notes.append("wraps")
            if f.table:
                notes.append(f"see {f.table.replace('_', ' ')}")
            rows.append([off, size, f"`{f.name}`", f.type, f.unit or "-", "; ".join(n for n in notes if n)])
            off += f.size if f.type != "text" else 0
        example = encode(ft.name, 7, p, **_example_values(ft))
        parts.append(f"#### {ft.name} (`0x{ft.id:02X}`, {ft.direction.replace('_', ' ')})\n\n{ft.description}\n\n"
                     + _md_table(["offset", "size", "field", "type", "unit", "notes"], rows)
                     + f"\n\nExample, sequence 7, {_example_text(ft)}:\n`{example.hex(' ').upper()}`")
    blocks["payloads"] = "\n\n".join(parts)
    blocks["crc"] = _md_table(["parameter", "value"], [
        ["algorithm", p.crc.name], ["width", p.crc.width], ["polynomial", f"`0x{p.crc.poly:04X}`"],
        ["initial value", f"`0x{p.crc.init:04X}`"], ["reflect in / out", "no / no"],
        ["final xor", f"`0x{p.crc.xorout:04X}`"], ["check (`123456789`)", f"`0x{p.crc.check:04X}`"],
        ["covers", p.crc.covers], ["on the wire", "after the payload, low byte first"]])
    blocks["timing"] = _md_table(["name", "value", "meaning"], [
        ["heartbeat_period", f"{t.heartbeat_period:g} s", "each side sends HEARTBEAT at least this often, per wheel"],
        ["report_period", f"{t.report_period:g} s", "a controller sends ENCODER_REPORT this often"],
        ["link_timeout", f"{t.link_timeout:g} s",
         "no valid frame for this long: the link is lost (host: error and zero commands; controller: motor off)"],
        ["connect_timeout", f"{t.connect_timeout:g} s",
         "the host's wait for a controller's first frame after opening its port (boot loaders reset on open)"]])
    fr = {name: p.header_size + ft.min_size + CRC_BYTES for name, ft in p.frames.items()}
    up = fr["ENCODER_REPORT"] / t.report_period + fr["HEARTBEAT"] / t.heartbeat_period
    down = fr["SPEED_CMD"] * 50 + fr["HEARTBEAT"] / t.heartbeat_period
    bits = 1 + int(p.serial["bytesize"]) + (0 if str(p.serial["parity"]) == "none" else 1) + int(p.serial["stopbits"])
    capacity = int(p.serial["baud"]) / bits
    blocks["bandwidth"] = _md_table(["per wheel", "bytes/s", f"share of {p.serial['baud']} baud"], [
        [f"controller -> host: ENCODER_REPORT ({fr['ENCODER_REPORT']} B) every {t.report_period:g} s, "
         f"HEARTBEAT ({fr['HEARTBEAT']} B) every {t.heartbeat_period:g} s", f"{up:.0f}", f"{100 * up / capacity:.1f} %"],
        [f"host -> controller: SPEED_CMD ({fr['SPEED_CMD']} B) at a 50 Hz control rate, "
         f"HEARTBEAT every {t.heartbeat_period:g} s", f"{down:.0f}", f"{100 * down / capacity:.1f} %"]])
    blocks["errors"] = _md_table(["code", "name", "meaning"],
                                 [[c.value, c.name, c.description] for c in p.error_codes])
    blocks["status"] = _md_table(["bit", "mask", "name", "meaning"],
                                 [[c.value, f"`0x{1 << c.value:02X}`", c.name, c.description] for c in p.status_flags])
    return blocks


def _example_values(ft: FrameType) -> dict:
    v = {}
    for f in ft.fields:
        if f.name == "wheel":
            v[f.name] = 1
        elif f.type == "text":
            v[f.name] = "boot"
        elif f.table == "error_codes":
            v[f.name] = 8
        elif f.table == "status_flags":
            v[f.name] = 3
        elif f.scale is not None:
            v[f.name] = -2.5
        elif f.name == "count":
            v[f.name] = -1000
        else:
            v[f.name] = 123456
    return v


def _example_text(ft: FrameType) -> str:
    return ", ".join(f"{k} = {v!r}" if isinstance(v, str) else f"{k} = {v:g}"
                     for k, v in _example_values(ft).items())


_BLOCK = re.compile(r"(<!-- BEGIN GENERATED (\w+)[^>]*-->\n)(.*?)(<!-- END GENERATED \2 -->)", re.DOTALL)


def update_doc(text: str, protocol: Protocol | None = None) -> str:
    """``text`` with every generated block replaced by its current content."""
    blocks = doc_blocks(protocol)
    found = set()

    def repl(m):
        name = m.group(2)
        if name not in blocks:
            raise ProtocolError(f"docs/protocol.md: unknown generated block {name!r} (blocks: {sorted(blocks)})")
        found.add(name)
        return m.group(1) + blocks[name] + "\n" + m.group(4)

    out = _BLOCK.sub(repl, text)
    missing = set(blocks) - found
    if missing:
        raise ProtocolError(f"docs/protocol.md: generated block(s) {sorted(missing)} missing; add "
                            "'<!-- BEGIN GENERATED name -->' ... '<!-- END GENERATED name -->' for each")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omnikin.runtime.protocol",
                                 description="Generate the firmware header or the documentation tables from "
                                             "protocol.yaml.")
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--header", action="store_true", help="print the C header (omnikin_protocol.h)")
    g.add_argument("--update-doc", metavar="MD", help="rewrite the generated blocks of this Markdown file")
    g.add_argument("--check-doc", metavar="MD", help="exit 1 if the generated blocks of this file are stale")
    g.add_argument("--check-header", metavar="H", help="exit 1 if this header differs from the generated one")
    args = ap.parse_args(argv)
    try:
        if args.header:
            sys.stdout.write(generate_header())
            return 0
        path = Path(args.update_doc or args.check_doc or args.check_header)
        text = path.read_text(encoding="utf-8")
        new = generate_header() if args.check_header else update_doc(text)
        if args.update_doc:
            if new != text:
                path.write_text(new, encoding="utf-8")
            return 0
        if new != text:
            print(f"{path} is stale; regenerate it ({DOC_COMMAND if args.check_doc else HEADER_COMMAND})",
                  file=sys.stderr)
            return 1
        return 0
    except (OSError, ProtocolError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
