"""Generator of the tables of ``docs/protocol.md`` (between ``<!-- BEGIN GENERATED name -->``
and ``<!-- END GENERATED name -->`` markers), from ``protocol.yaml``.

Blocks: ``constants``, ``envelope``, ``types``, ``payloads`` (one table per frame type, with
an example frame in hex), ``crc``, ``timing`` (seconds), ``bandwidth`` (bytes/s per wheel and
share of the baud rate; a character on the wire is a start bit, the data bits, the parity bit if
any and the stop bits of the description), ``errors`` and ``status``. The prose around them is
written by hand. A test checks that the committed page is up to date::

    python -m omnikin.runtime.protocol --update-doc docs/protocol.md
"""

from __future__ import annotations

import re
from typing import Any

from ...common.messages import shorten
from ...errors import ProtocolError
from .codec import encode
from .schema import CRC_BYTES, FrameType, Protocol, load_protocol

DOC_COMMAND = "python -m omnikin.runtime.protocol --update-doc docs/protocol.md"


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
    blocks["constants"] = _md_table(
        ["constant", "value"],
        [
            ["protocol name", f"`{p.name}`"],
            ["version", p.version],
            ["sync bytes", " ".join(f"`0x{b:02X}`" for b in p.sync)],
            ["byte order", "little-endian (the CRC included)"],
            ["header", f"{h} bytes (sync, version, type, sequence, length)"],
            ["max payload", f"{p.max_payload} bytes (frame: {p.max_frame} bytes)"],
            ["wheel indices", f"0 to {p.wheel_index_max} (255 reserved)"],
            [
                "sequence",
                f"one byte, modulo {p.seq_modulo}, per direction and wheel; "
                f"resync after {p.resync_after} out-of-order frames in a row",
            ],
            ["encoder counter", f"{p.counter_bits}-bit two's complement, wraps"],
            [
                "serial defaults",
                f"{p.serial['baud']} baud, {p.serial['bytesize']} data bits, "
                f"parity {p.serial['parity']}, {p.serial['stopbits']} stop bit",
            ],
        ],
    )
    blocks["envelope"] = _md_table(
        ["offset", "size", "field", "content"],
        [
            [0, len(p.sync), "sync", " ".join(f"`0x{b:02X}`" for b in p.sync)],
            [h - 4, 1, "version", f"`{p.version}`"],
            [h - 3, 1, "type", "frame type id (table below)"],
            [h - 2, 1, "seq", "sequence number of the stream (direction, wheel), 0-255"],
            [h - 1, 1, "length", f"payload length n, 0-{p.max_payload}"],
            [h, "n", "payload", "fields of the type, the wheel index first"],
            [f"{h} + n", CRC_BYTES, "crc", f"{p.crc.name} of bytes {len(p.sync)} to {h - 1} + n, little-endian"],
        ],
    )
    blocks["types"] = _md_table(
        ["id", "type", "direction", "payload [bytes]", "meaning"],
        [
            [
                f"`0x{ft.id:02X}`",
                ft.name,
                ft.direction.replace("_", " "),
                ft.min_size if ft.text is None else f"{ft.min_size}-{ft.max_size}",
                ft.description,
            ]
            for ft in p.frames.values()
        ],
    )
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
        parts.append(
            f"#### {ft.name} (`0x{ft.id:02X}`, {ft.direction.replace('_', ' ')})\n\n{ft.description}\n\n"
            + _md_table(["offset", "size", "field", "type", "unit", "notes"], rows)
            + f"\n\nExample, sequence 7, {_example_text(ft)}:\n`{example.hex(' ').upper()}`"
        )
    blocks["payloads"] = "\n\n".join(parts)
    blocks["crc"] = _md_table(
        ["parameter", "value"],
        [
            ["algorithm", p.crc.name],
            ["width", p.crc.width],
            ["polynomial", f"`0x{p.crc.poly:04X}`"],
            ["initial value", f"`0x{p.crc.init:04X}`"],
            ["reflect in / out", "no / no"],
            ["final xor", f"`0x{p.crc.xorout:04X}`"],
            ["check (`123456789`)", f"`0x{p.crc.check:04X}`"],
            ["covers", p.crc.covers],
            ["on the wire", "after the payload, low byte first"],
        ],
    )
    blocks["timing"] = _md_table(
        ["name", "value", "meaning"],
        [
            [
                "heartbeat_period",
                f"{t.heartbeat_period:g} s",
                "each side sends HEARTBEAT at least this often, per wheel",
            ],
            ["report_period", f"{t.report_period:g} s", "a controller sends ENCODER_REPORT this often"],
            [
                "link_timeout",
                f"{t.link_timeout:g} s",
                "no valid frame for this long: the link is lost (host: error and zero commands; controller: motor off)",
            ],
            [
                "connect_timeout",
                f"{t.connect_timeout:g} s",
                "the host's wait for a controller's first frame after opening its port (boot loaders reset on open)",
            ],
        ],
    )
    fr = {name: p.header_size + ft.min_size + CRC_BYTES for name, ft in p.frames.items()}
    up = fr["ENCODER_REPORT"] / t.report_period + fr["HEARTBEAT"] / t.heartbeat_period
    down = fr["SPEED_CMD"] * 50 + fr["HEARTBEAT"] / t.heartbeat_period
    bits = 1 + int(p.serial["bytesize"]) + (0 if str(p.serial["parity"]) == "none" else 1) + int(p.serial["stopbits"])
    capacity = int(p.serial["baud"]) / bits
    blocks["bandwidth"] = _md_table(
        ["per wheel", "bytes/s", f"share of {p.serial['baud']} baud"],
        [
            [
                f"controller -> host: ENCODER_REPORT ({fr['ENCODER_REPORT']} B) every {t.report_period:g} s, "
                f"HEARTBEAT ({fr['HEARTBEAT']} B) every {t.heartbeat_period:g} s",
                f"{up:.0f}",
                f"{100 * up / capacity:.1f} %",
            ],
            [
                f"host -> controller: SPEED_CMD ({fr['SPEED_CMD']} B) at a 50 Hz control rate, "
                f"HEARTBEAT every {t.heartbeat_period:g} s",
                f"{down:.0f}",
                f"{100 * down / capacity:.1f} %",
            ],
        ],
    )
    blocks["errors"] = _md_table(["code", "name", "meaning"], [[c.value, c.name, c.description] for c in p.error_codes])
    blocks["status"] = _md_table(
        ["bit", "mask", "name", "meaning"],
        [[c.value, f"`0x{1 << c.value:02X}`", c.name, c.description] for c in p.status_flags],
    )
    return blocks


def _example_values(ft: FrameType) -> dict[str, Any]:
    v: dict[str, Any] = {}
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
    return ", ".join(f"{k} = {v!r}" if isinstance(v, str) else f"{k} = {v:g}" for k, v in _example_values(ft).items())


_BLOCK = re.compile(r"(<!-- BEGIN GENERATED (\w+)[^>]*-->\n)(.*?)(<!-- END GENERATED \2 -->)", re.DOTALL)


def update_doc(text: str, protocol: Protocol | None = None) -> str:
    """``text`` with every generated block replaced by its current content."""
    if not isinstance(text, str):
        raise ProtocolError(f"update_doc: expected the page as text, got {type(text).__name__}")
    blocks = doc_blocks(protocol)
    found = set()

    def repl(m):
        name = m.group(2)
        if name not in blocks:
            raise ProtocolError(f"docs/protocol.md: unknown generated block {shorten(name)} (blocks: {sorted(blocks)})")
        found.add(name)
        return m.group(1) + blocks[name] + "\n" + m.group(4)

    out = _BLOCK.sub(repl, text)
    missing = set(blocks) - found
    if missing:
        raise ProtocolError(
            f"docs/protocol.md: generated block(s) {sorted(missing)} missing; add "
            "'<!-- BEGIN GENERATED name -->' ... '<!-- END GENERATED name -->' for each"
        )
    return out
