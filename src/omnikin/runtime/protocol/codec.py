"""Frame encoding: physical values -> wire integers -> payload -> framed bytes.

Implements ``docs/protocol.md`` (sections *Frame*, *Frame types* and *Units and signs*)::

    | sync (0xAA 0x55) | version | type | seq | length | payload (length bytes) | CRC-16 |

Every multi-byte integer little-endian (the CRC included), signed ones two's complement.
A field's wire integer is its physical value (in the field's ``unit``, e.g. rad/s or us)
divided by its ``scale`` and rounded half away from zero, as C's ``lround``; fields marked
``wraps`` (the encoder count, the microsecond clock) wrap modulo their range, the others
refuse values outside it. ``seq`` numbers the frames of one stream (one direction of one
wheel) modulo 256: :class:`FrameEncoder` keeps that numbering for one sender.

Values that cannot be encoded raise :class:`~omnikin.errors.ProtocolError` (an InputError).
"""

from __future__ import annotations

import math
import struct

from ...common.messages import shorten
from ...errors import ProtocolError
from .schema import INT_TYPES, Field, FrameType, Protocol, load_protocol


def round_half_away(x: float) -> int:
    """Nearest integer of the finite number ``x``, halves away from zero (as C's ``lround``)."""
    if isinstance(x, int):
        return int(x)
    if not isinstance(x, float) or not math.isfinite(x):
        raise ProtocolError(f"expected a finite number to round, got {shorten(x)}")
    return math.floor(abs(x) + 0.5) * (1 if x >= 0 else -1)


def to_raw(f: Field, value) -> int:
    """Physical value -> wire integer of field ``f`` (checked against its type's range)."""
    if isinstance(value, bool):
        value = int(value)
    _, _, _, lo, hi = INT_TYPES[f.type]
    unit = f" {f.unit}" if f.unit else ""
    outside = f"field {f.name}: {shorten(value)}{unit} is outside the range of {f.type}" + (
        f" at scale {f.scale:g}" if f.scale else ""
    )
    if f.scale is not None:
        if not isinstance(value, (int, float)) or isinstance(value, float) and not math.isfinite(value):
            raise ProtocolError(f"field {f.name}: expected a finite number, got {shorten(value)}")
        try:
            counts = value / f.scale
        except OverflowError:  # an int beyond any float
            raise ProtocolError(outside) from None
        if not math.isfinite(counts):
            raise ProtocolError(outside)
        raw = round_half_away(counts)
    else:
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if not isinstance(value, int):
            raise ProtocolError(f"field {f.name}: expected an integer, got {shorten(value)}")
        raw = value
    if f.wraps and f.scale is None:
        span = hi - lo + 1
        raw = (raw - lo) % span + lo
    if not lo <= raw <= hi:
        raise ProtocolError(outside)
    return raw


def pack_payload(ft: FrameType, values: dict, raw: bool = False) -> bytes:
    """Payload bytes of frame type ``ft``; ``values`` physical (``raw``: wire integers)."""
    names = {f.name for f in ft.fields}
    unknown = set(values) - names
    if unknown:
        raise ProtocolError(
            f"{ft.name}: unknown field(s) {shorten(sorted(map(str, unknown)))} (fields: {[f.name for f in ft.fields]})"
        )
    ints = []
    for f in ft.fixed:
        if f.name not in values:
            raise ProtocolError(f"{ft.name}: field {f.name!r} is missing")
        v = values[f.name]
        ints.append(to_raw(f, v) if not raw else to_raw(Field(f.name, f.type, wraps=f.wraps), v))
    out = struct.pack(ft.struct_format, *ints)
    if ft.text is not None:
        text = values.get(ft.text.name, "")
        if isinstance(text, str):
            data = text.encode("ascii", "replace")
        elif isinstance(text, (bytes, bytearray, memoryview)):
            data = bytes(text)
        else:
            raise ProtocolError(f"{ft.name}: field {ft.text.name}: expected text or bytes, got {shorten(text)}")
        if len(data) > ft.text.max_length:
            raise ProtocolError(f"{ft.name}: text of {len(data)} bytes exceeds {ft.text.max_length}")
        out += data
    return out


def unpack_payload(ft: FrameType, payload: bytes) -> tuple[dict, dict]:
    """``(raw, physical)`` field values of a payload whose length ``ft`` accepts."""
    if not ft.accepts(len(payload)):
        raise ProtocolError(
            f"{ft.name}: a payload of {len(payload)} bytes does not fit the type ({ft.min_size} to {ft.max_size} bytes)"
        )
    ints = struct.unpack_from(ft.struct_format, payload)
    raw, phys = {}, {}
    for f, v in zip(ft.fixed, ints, strict=True):
        raw[f.name] = v
        phys[f.name] = v * f.scale if f.scale is not None else v
    if ft.text is not None:
        text = bytes(payload[ft.min_size :])
        raw[ft.text.name] = text
        phys[ft.text.name] = text.decode("ascii", "replace")
    return raw, phys


def frame_bytes(protocol: Protocol, type_id: int, seq: int, payload: bytes, version: int | None = None) -> bytes:
    """A complete frame around ``payload`` (``version`` overrides the protocol's, for tests)."""
    version = protocol.version if version is None else version
    for what, v in (("sequence number", seq), ("type id", type_id), ("version", version)):
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 255:
            raise ProtocolError(f"{what} must be an integer from 0 to 255, got {shorten(v)}")
    if not isinstance(payload, (bytes, bytearray, memoryview)):
        raise ProtocolError(f"payload: expected bytes, got {shorten(payload)}")
    if len(payload) > protocol.max_payload:
        raise ProtocolError(f"payload of {len(payload)} bytes exceeds max_payload {protocol.max_payload}")
    body = bytes((version, type_id, seq, len(payload))) + bytes(payload)
    return protocol.sync + body + protocol.crc(body).to_bytes(2, "little")


def encode(name: str, seq: int, protocol: Protocol | None = None, raw: bool = False, **values) -> bytes:
    """One frame of type ``name`` with sequence number ``seq`` (``values``: physical, or wire with ``raw``)."""
    p = protocol or load_protocol()
    ft = p.frame(name)
    if "wheel" in values:
        _wheel_index(p, ft, values["wheel"])
    return frame_bytes(p, ft.id, seq, pack_payload(ft, values, raw))


def _wheel_index(p: Protocol, ft: FrameType, value) -> int:
    """The wire wheel index of ``value``, refused beyond ``wheel_index_max`` (255 is reserved)."""
    wheel = to_raw(ft.field("wheel"), value)
    if wheel > p.wheel_index_max:
        raise ProtocolError(f"wheel index {wheel} is beyond {p.wheel_index_max} (255 is reserved)")
    return wheel


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
        """The next frame of type ``name`` of the stream of ``values["wheel"]``."""
        ft = self.protocol.frame(name)
        if "wheel" not in values:
            raise ProtocolError(f"{ft.name}: field 'wheel' is missing")
        wheel = _wheel_index(self.protocol, ft, values["wheel"])
        frame = encode(name, self.peek(wheel), self.protocol, raw, **values)
        self.next_seq(wheel)
        return frame

    def reset(self, wheel: int | None = None) -> None:
        if wheel is None:
            self._seq.clear()
        else:
            self._seq.pop(wheel, None)
