"""The streaming decoder: bytes in, :class:`Message` s out, whatever the bytes.

Implements ``docs/protocol.md`` (section *Receiving: resynchronisation and error counts*, and
the sequence rules of :mod:`.sequence`). :class:`StreamDecoder` never raises on bad bytes. It
resynchronises on the sync bytes and counts what it rejects (:class:`DecoderStats`):

* ``corrupt`` + ``short``: the *garbled stretches*. A stretch is a run of bytes between two
  frames with a valid CRC (or the stream's start, or its end at :meth:`StreamDecoder.flush`)
  that holds no such frame: a frame whose CRC fails or whose length byte is impossible, a
  frame cut off, noise, several of them in a row. Each counts once, when it ends, whatever
  it contains (sync bytes in a payload, a CRC or a damaged length byte start no second
  fault), as ``short`` if a frame start the decoder resynchronised on in it announced an end
  beyond the next valid frame's start (it was cut off; also a frame the stream stopped in),
  else as ``corrupt``. How many frames a stretch held cannot be known (one damaged length
  byte moves every frame boundary after it); the sequence numbers count the frames lost;
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

from ...common.messages import shorten
from ...errors import ProtocolError
from .codec import unpack_payload
from .schema import CRC_BYTES, DIRECTIONS, Protocol, load_protocol
from .sequence import SEQ_DUPLICATE, SEQ_OUT_OF_ORDER, SEQ_RESYNC, SequenceTracker


@dataclass(frozen=True)
class Message:
    """A decoded frame: ``fields`` physical (scaled) values, ``raw`` the wire integers;
    ``restarted``: its sequence number showed that the sender restarted (a resync, counted in
    ``resyncs``; the sender's RESET announcement was lost)."""

    name: str
    type_id: int
    seq: int
    wheel: int
    fields: dict
    raw: dict
    frame: bytes = b""
    restarted: bool = False

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

    def __init__(
        self,
        protocol: Protocol | None = None,
        direction: str | None = "controller_to_host",
        check_sequence: bool = True,
    ):
        if direction is not None and direction not in DIRECTIONS[:2]:
            raise ProtocolError(f"direction must be one of {DIRECTIONS[:2]} or None, got {shorten(direction)}")
        self.protocol = protocol or load_protocol()
        self.direction = direction
        self.check_sequence = check_sequence
        self.stats = DecoderStats()
        self.streams: dict[int, SequenceTracker] = {}
        self._buf = bytearray()
        self._reset_code = self.protocol.error_code("RESET")
        # the garbled stretch under way: bytes skipped since the last frame with a valid CRC, and
        # the farthest end announced by a frame start the decoder resynchronised on in it (an
        # offset into the buffer; > 0 at the next valid frame: that frame start was cut off)
        self._garbled = False
        self._reach = 0

    @property
    def pending(self) -> int:
        """Bytes held back waiting for the rest of a frame."""
        return len(self._buf)

    def feed(self, data) -> list[Message]:
        """Decode what ``data`` (bytes) completes; never raises on bad bytes (they are counted)."""
        held = len(self._buf)
        try:
            self._buf += data
        except TypeError:
            raise ProtocolError(f"StreamDecoder.feed: expected bytes, got {type(data).__name__}") from None
        self.stats.bytes_in += len(self._buf) - held
        return self._decode(final=False)

    def flush(self) -> list[Message]:
        """The stream stopped: decode the frames complete in the bytes held back (behind a frame
        start that announced more bytes than came), count the rest, and return the frames."""
        out = self._decode(final=True)
        self._end_stretch()
        return out

    def restart_stream(self, wheel: int | None = None) -> None:
        """Forget the sequence state of one wheel (None: all)."""
        if wheel is None:
            self.streams.clear()
        else:
            self.streams.pop(wheel, None)

    # -- internals --
    def _decode(self, final: bool) -> list[Message]:
        try:
            return self._parse(final)
        except Exception:  # a bug must not take the link down; counted and visible in stats
            self.stats.internal_errors += 1
            self._skip(len(self._buf))
            return []

    def _skip(self, n: int) -> None:
        """Drop ``n`` bytes that are no frame: they belong to the garbled stretch under way."""
        if n > 0:
            del self._buf[:n]
            self.stats.skipped_bytes += n
            self._garbled = True
            self._reach = max(0, self._reach - n)

    def _end_stretch(self) -> None:
        """A frame with a valid CRC follows (or the stream stopped): count the garbled stretch
        before it once, ``short`` if a frame start in it was cut off, else ``corrupt``."""
        if self._garbled:
            if self._reach > 0:
                self.stats.short += 1
            else:
                self.stats.corrupt += 1
        self._garbled, self._reach = False, 0

    def _candidate(self, j: int, final: bool) -> tuple[int, bool | None]:
        """The frame start (a sync) at offset ``j``: ``(end, verdict)``. ``end``: the offset just
        after the frame it announces (impossible length: after its header; header incomplete:
        the shortest frame). ``verdict``: True for a complete frame with a valid CRC, False for
        none, None when bytes are missing (``final``: none will come, so False)."""
        p, buf = self.protocol, self._buf
        h = p.header_size
        if len(buf) < j + h:
            return j + h + CRC_BYTES, False if final else None
        length = buf[j + h - 1]
        if length > p.max_payload:
            return j + h, False
        end = j + h + length + CRC_BYTES
        if len(buf) < end:
            return end, False if final else None
        return end, p.crc(buf[j + len(p.sync) : j + h + length]) == int.from_bytes(buf[end - 2 : end], "little")

    def _inner_frame(self, end: int, final: bool) -> int | None:
        """After the frame start at 0 was rejected, having announced ``end``: the offset of the
        first valid frame that starts inside it (then the rejected one was cut off), 0 if none,
        None to wait for bytes. A sync may start on its last byte (as the C parser scans)."""
        sync, buf = self.protocol.sync, self._buf
        stop = end + len(sync) - 1
        j = buf.find(sync, 1, stop)
        while j > 0:
            verdict = self._candidate(j, final)[1]
            if verdict is None:
                return None
            if verdict:
                return j
            j = buf.find(sync, j + 1, stop)
        if not final and len(buf) < stop and buf[-1] == sync[0]:
            return None  # the last byte held, inside the rejected frame, may begin a sync
        return 0

    def _parse(self, final: bool) -> list[Message]:
        """Resynchronisation (``docs/protocol.md``). Every byte is either part of a frame with a
        valid CRC or skipped; a frame start that is rejected is skipped whole (the frame it
        announced, up to a valid frame starting inside it), so that sync bytes inside a bad frame
        never start a second fault: the skipped bytes between two valid frames are one stretch,
        counted once (:meth:`_end_stretch`), whatever they contain."""
        p, buf, st = self.protocol, self._buf, self.stats
        sync, h = p.sync, p.header_size
        out = []
        while buf:
            i = buf.find(sync)
            if i < 0:  # no frame start: skip all, but a last byte that may begin a sync waits for more
                self._skip(len(buf) - (1 if not final and buf[-1] == sync[0] else 0))
                break
            self._skip(i)
            end, verdict = self._candidate(0, final)
            if verdict is None:
                break
            if verdict:
                self._end_stretch()
                length = buf[h - 1]
                version, type_id, seq = buf[len(sync)], buf[len(sync) + 1], buf[len(sync) + 2]
                payload, frame = bytes(buf[h : h + length]), bytes(buf[:end])
                del buf[:end]
                msg = self._accept(version, type_id, seq, payload, frame)
                if msg is None:
                    st.skipped_bytes += end
                else:
                    out.append(msg)
                continue
            self._reach = max(self._reach, end)
            inner = self._inner_frame(end, final)
            if inner is None:
                break
            self._skip(inner or min(end, len(buf)))
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
        restarted = False
        if self.check_sequence:
            tracker = self.streams.setdefault(wheel, SequenceTracker(p.resync_after))
            if ft.name == "ERROR_REPORT" and raw.get("code") == self._reset_code:
                tracker.restart(seq)
            else:
                verdict, lost = tracker.check(seq)
                restarted = verdict == SEQ_RESYNC
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
        return Message(ft.name, type_id, seq, wheel, phys, raw, frame, restarted)
