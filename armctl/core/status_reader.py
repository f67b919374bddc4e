"""The resynchronising status reader: status frames found in a byte stream fed in arbitrary chunks.

Strategy: H9 — a status frame has no checksum, so after noise ``StatusReader.feed`` slides one
byte and tries again; bytes that may begin a frame not fully arrived are held back.  The common
cases cost least: a burst of whole, valid frames and nothing held (``_aligned``: no scan), and
bursts of one frame each — the arm's, and a virtual run's (``_one_frame``, ``decode_frame``/
``decode_frames``: the kinds that repeat
for minutes are given again from the bytes seen, the three-word kinds decoded by a decoder made
once per kind).  The frames are armctl/core/status_frames.py's; ``armctl.core.protocol`` offers
``StatusReader`` (imported on first use, as the status frames are).  Bytes only, no I/O.
"""

from __future__ import annotations

from ..errors import FieldError, FrameError
from .frame_fields import STATUS_HEAD, STATUS_SIZE, STATUS_TAIL
from .status_frames import STATUS_KINDS, StatusFrame, ThreeWordStatus, is_status_frame


# decode_frame keeps the frames of the kinds that repeat unchanged for long (worktable origin,
# pause and PWM, SD file length, status and run position, and the wrist while it holds: two
# thirds of its frames in a job of straight moves), at most this many.
_REPEATING_KINDS = frozenset((3, 4, 5, 100, 102, 103))
_SEEN_FRAMES = 64
_WORD_DECODERS: dict = {}  # kind → its ThreeWordStatus._decoder, for decode_frame (made on first use)


class StatusReader:
    """Finds status frames in a byte stream fed in arbitrary chunks.

    H9 — there is no checksum, so after noise the reader slides one byte and tries again.
    ``skipped_bytes`` counts every byte that belonged to no frame; ``frames`` every frame
    returned.  Plausibility (a value that jumps faster than the arm can move) is judged where
    the arm's state is merged, not here: this reader only knows bytes.
    """

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.frames = 0
        self.skipped_bytes = 0
        self._seen: dict[bytes, StatusFrame] = {}  # decode_frame: bytes → frame, the repeating kinds

    @property
    def pending(self) -> int:
        """Bytes held back because they may begin a frame that has not fully arrived."""
        return len(self._buffer)

    def feed(self, data: bytes) -> list[StatusFrame]:
        if not self._buffer:  # the common case: whole frames, nothing held, nothing to skip
            found = self._one_frame(data) if len(data) == STATUS_SIZE else self._aligned(data)
            if found:
                self.frames += len(found)
                return found
        buffer = self._buffer
        buffer += data
        found: list[StatusFrame] = []
        start = 0
        while True:
            head = buffer.find(STATUS_HEAD, start)
            if head < 0:
                self.skipped_bytes += len(buffer) - start
                start = len(buffer)
                break
            self.skipped_bytes += head - start
            start = head
            if len(buffer) - start < STATUS_SIZE:
                break  # wait for the rest of a frame that may have begun here
            if is_status_frame(buffer, start):
                try:  # decode_status's work, the checks it repeats apart (one frame per 30 ms)
                    found.append(STATUS_KINDS[buffer[start + 7]]._from_data(bytes(buffer[start + 1 : start + 7])))
                except (FrameError, FieldError):
                    pass  # a well-framed frame with an impossible value: treated as noise
                else:
                    start += STATUS_SIZE
                    continue
            self.skipped_bytes += 1
            start += 1
        del buffer[:start]
        self.frames += len(found)
        return found

    def decode_frame(self, data: bytes) -> StatusFrame | None:
        """The frame of a burst that is one whole status frame and nothing else (the simulator's
        quiet stretches, armctl/host/virtual_wait.py's ``_take_run``): what ``feed`` finds in it,
        without counting it (the caller counts what it reads), or None if it is not one valid frame.  Bytes seen
        before give the same (immutable) frame again for the kinds that repeat for minutes
        (worktable, pause and PWM, SD program): no decode at all for half the frames."""
        if self._buffer:
            return None  # bytes held from before come first: feed's job
        frame = self._seen.get(data)
        if frame is not None:
            return frame
        if len(data) != STATUS_SIZE or data[0] != STATUS_HEAD or data[8] != STATUS_TAIL:
            return None
        kind = data[7]
        decode = _WORD_DECODERS.get(kind)
        if decode is not None:
            frame = decode(data, 1)  # words: any bytes are a frame
        else:
            frame_class = STATUS_KINDS.get(kind)
            if frame_class is None:
                return None
            if issubclass(frame_class, ThreeWordStatus):
                _WORD_DECODERS[kind] = decode = frame_class._decoder()
                frame = decode(data, 1)
            else:
                try:
                    frame = frame_class._from_data(data[1:7])
                except (FrameError, FieldError):
                    return None
        if kind in _REPEATING_KINDS:
            if len(self._seen) >= _SEEN_FRAMES:
                self._seen.clear()
            self._seen[data] = frame
        return frame

    def decode_frames(self, bursts: list) -> list[StatusFrame]:
        """``decode_frame`` of each burst in order, up to the first that is not one valid frame
        (the list is then shorter): a batch of a virtual run's frames (armctl/host/virtual_wait.py's
        ``_take_run``), the kinds that change all the time (position, joints) decoded here without a call each."""
        if self._buffer:
            return []
        seen, decoders, decode_frame = self._seen, _WORD_DECODERS, self.decode_frame
        found = []
        for data in bursts:
            frame = seen.get(data)
            if frame is None:
                kind = data[7] if len(data) == STATUS_SIZE and data[0] == STATUS_HEAD and data[8] == STATUS_TAIL else None
                decode = decoders.get(kind) if kind not in _REPEATING_KINDS else None
                frame = decode(data, 1) if decode is not None else decode_frame(data)
                if frame is None:
                    break
            found.append(frame)
        return found

    def _one_frame(self, data: bytes) -> list[StatusFrame]:
        """A burst of one whole, valid frame, as the arm sends them (40,000 in 20 minutes; a
        virtual wait's bursts): decoded as a run's frames are (``decode_frames``: a repeating
        kind's bytes decoded once); [] for anything else, which the scan takes from the start."""
        return self.decode_frames((data,))

    @staticmethod
    def _aligned(data: bytes) -> list[StatusFrame] | None:
        """The frames of a burst made of whole, valid status frames and nothing else (what a
        clean line delivers, 40,000 in 20 minutes) — what the scan below finds in it; None for
        anything else (noise, a frame cut short or damaged, a value no frame can carry), which
        the scan takes from the start."""
        size = len(data)
        if not size or size % STATUS_SIZE:
            return None
        found = []
        for start in range(0, size, STATUS_SIZE):
            frame_class = STATUS_KINDS.get(data[start + 7])
            if frame_class is None or data[start] != STATUS_HEAD or data[start + 8] != STATUS_TAIL:
                return None
            try:
                found.append(frame_class._from_data(bytes(data[start + 1 : start + 7])))
            except (FrameError, FieldError):
                return None
        return found
