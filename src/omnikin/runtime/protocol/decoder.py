"""The streaming decoder: bytes in, :class:`Message` s out, whatever the bytes.

Implements ``docs/protocol.md`` (section *Receiving: resynchronisation and error counts*, and
the sequence rules of :mod:`.sequence`). :class:`StreamDecoder` never raises on bad bytes. It
resynchronises on the sync bytes and counts what it rejects (:class:`DecoderStats`):

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

Decoded fields are physical values (the units of ``protocol.yaml``: rad/s, us, counts) in
:attr:`Message.fields`, wire integers in :attr:`Message.raw`.
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import fields as dc_fields

from .codec import unpack_payload
from .schema import CRC_BYTES, DIRECTIONS, Protocol, ProtocolError, load_protocol
from .sequence import SEQ_DUPLICATE, SEQ_OUT_OF_ORDER, SEQ_RESYNC, SequenceTracker


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
