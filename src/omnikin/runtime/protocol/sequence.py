"""The sequence rules of one stream (one direction of one wheel), as the host applies them.

Implements ``docs/protocol.md`` (section *Sequence numbers*): ``seq`` is one byte counting
the frames of a stream modulo 256. With ``d = (seq - last) mod 256``: 0 is a duplicate
(drop), 1-127 is in order (accept; ``d - 1`` frames were lost), 128-255 is from the past
(drop, unless ``resync_after`` such frames in a row show that the sender restarted: then
adopt the new numbering). The generated C header has the same rules (``omnikin_seq_check``,
``OMNIKIN_SEQ_*``); a test compares the two verdict by verdict.
"""

from __future__ import annotations

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
