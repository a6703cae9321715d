"""The frame check of the wheel-controller protocol: a table-driven 16-bit CRC.

Implements the CRC of ``docs/protocol.md`` (section *CRC*): CRC-16/CCITT-FALSE, polynomial
0x1021, initial value 0xFFFF, no reflection, no final xor, check value 0x29B1 (of the ASCII
bytes ``123456789``). It covers every byte of a frame after the sync bytes and before the
CRC, and goes on the wire low byte first. Inputs are bytes, results 16-bit unsigned integers.

:class:`Crc` holds any non-reflected 16-bit CRC; ``protocol.yaml`` chooses the parameters
and :func:`~.schema.parse_protocol` checks them against the file's check value. The firmware
computes the same CRC bitwise (no table in RAM) in the generated C header.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Crc:
    """A non-reflected 16-bit CRC: ``crc(data)`` is the CRC of the bytes ``data``."""

    name: str
    width: int
    poly: int
    init: int
    refin: bool
    refout: bool
    xorout: int
    check: int
    covers: str
    _table: tuple = field(init=False, repr=False, compare=False)

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


_CCITT_FALSE = Crc("CRC-16/CCITT-FALSE", 16, 0x1021, 0xFFFF, False, False, 0, 0x29B1, "")


def crc16_ccitt_false(data) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor) of ``data``."""
    return _CCITT_FALSE(data)
