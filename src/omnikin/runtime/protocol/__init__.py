"""The wheel-controller protocol: description, framing, encoding, decoding, generators.

``protocol.yaml`` (package data of :mod:`omnikin.runtime`, next to this package) is the single
source of truth; ``docs/protocol.md`` is the specification. This package reads the description
and implements it on the host, and generates from it the firmware's C header and the tables of
the documentation::

    python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h
    python -m omnikin.runtime.protocol --update-doc docs/protocol.md

Frame (every multi-byte integer little-endian, the CRC included)::

    | sync (0xAA 0x55) | version | type | seq | length | payload (length bytes) | CRC-16 |

Modules:

* :mod:`.schema`: :func:`load_protocol` / :func:`parse_protocol` check the description and give
  a :class:`Protocol` (frame types, fields, units and scales, timing [s], codes);
  :class:`ProtocolError`;
* :mod:`.crc`: the CRC-16 (:class:`Crc`, :func:`crc16_ccitt_false`);
* :mod:`.codec`: physical values -> frames (:func:`encode`, :class:`FrameEncoder`, ...);
* :mod:`.sequence`: the sequence rules of one stream (:class:`SequenceTracker`, ``SEQ_*``);
* :mod:`.decoder`: bytes -> messages, never raising on bad bytes (:class:`StreamDecoder`,
  :class:`DecoderStats`, :class:`Message`);
* :mod:`.c_header`, :mod:`.markdown`: the generators; :mod:`.cli`: their command line.

Every error raised on purpose is a :class:`ProtocolError`, an :class:`omnikin.errors.InputError`.
"""

from ...errors import ProtocolError
from .c_header import HEADER_COMMAND, generate_header
from .cli import main
from .codec import FrameEncoder, encode, frame_bytes, pack_payload, round_half_away, to_raw, unpack_payload
from .crc import Crc, crc16_ccitt_false
from .decoder import DecoderStats, Message, StreamDecoder
from .markdown import DOC_COMMAND, doc_blocks, update_doc
from .schema import (
    CRC_BYTES,
    DIRECTIONS,
    HEADER_BYTES,
    INT_TYPES,
    Code,
    Field,
    FrameType,
    Protocol,
    Timing,
    load_protocol,
    parse_protocol,
)
from .sequence import (
    SEQ_DUPLICATE,
    SEQ_FIRST,
    SEQ_GAP,
    SEQ_OK,
    SEQ_OUT_OF_ORDER,
    SEQ_RESYNC,
    SequenceTracker,
)

__all__ = [
    "CRC_BYTES",
    "DIRECTIONS",
    "DOC_COMMAND",
    "HEADER_BYTES",
    "HEADER_COMMAND",
    "INT_TYPES",
    "SEQ_DUPLICATE",
    "SEQ_FIRST",
    "SEQ_GAP",
    "SEQ_OK",
    "SEQ_OUT_OF_ORDER",
    "SEQ_RESYNC",
    "Code",
    "Crc",
    "DecoderStats",
    "Field",
    "FrameEncoder",
    "FrameType",
    "Message",
    "Protocol",
    "ProtocolError",
    "SequenceTracker",
    "StreamDecoder",
    "Timing",
    "crc16_ccitt_false",
    "doc_blocks",
    "encode",
    "frame_bytes",
    "generate_header",
    "load_protocol",
    "main",
    "pack_payload",
    "parse_protocol",
    "round_half_away",
    "to_raw",
    "unpack_payload",
    "update_doc",
]
