"""The arm's host connector: it finds frames in the byte stream and buffers them, FIFO.

Strategy: the connector's framing does not depend on timing, so the byte stream is framed the
moment the host writes it (``Framer.feed``), and each frame carries the offset of its last byte;
the link then knows the exact time the frame lands.  The FIFO (``Connector``) only sees whole
frames, at their arrival time, and answers "accepted or dropped".  Pure: no clock, no I/O.

Decisions (PROTOCOL.md):
- **H7** — a frame starts at a head byte (0xEE or 0xFC); the connector takes 48 bytes and
  discards them all if the last is not the matching tail (``bad_frames``).  Bytes that are not a
  head byte while the connector hunts for one are skipped (``skipped_bytes``).
- **H6** — a frame that lands while the buffer is full is dropped whole; nothing tells the host.
- The records for tests and the benchmark (``received``, ``dropped_indexes``, ``cleared_indexes``)
  keep the most recent ``HISTORY_FRAMES`` entries or more (``RecentList``); their counts cover
  the whole run.
- ``capacity_frames`` counts the frames *waiting* behind the one the arm executes: H6's two
  readings (the executing frame keeps its slot until done, or frees it when taken) differ only
  in that one observable number, so the simulator takes the number (``SimOptions.fifo_frames``,
  the profile's ``[connector] fifo_frames``), not a reading.  The frames the arm has taken stay in
  ``executing`` until they finish, for the record only.
"""

from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass, field

from ..errors import ArmctlError
from ..core.protocol import (
    CONNECTOR_BUFFER_FRAMES,
    CONTROL_HEAD,
    CONTROL_TAIL,
    FRAME_SIZE,
    MOTION_HEAD,
    MOTION_TAIL,
    AnyCommand,
    decode_command,
)

# The simulator's records (frames received, dropped, cleared; executions) keep only the most recent
# this many entries, and counters for the rest, so a long virtual run takes flat memory.
HISTORY_FRAMES = 1024

_TAIL_FOR_HEAD = {MOTION_HEAD: MOTION_TAIL, CONTROL_HEAD: CONTROL_TAIL}
_HEAD_PATTERN = re.compile(bytes([ord("["), MOTION_HEAD, CONTROL_HEAD, ord("]")]))


class RecentList(list):
    """A record that keeps only its most recent entries: at least ``limit`` of them, at most twice
    that (the oldest are cut in blocks, so appending stays cheap); ``total`` counts every entry
    ever appended and ``complete`` says whether all are still here.  A list, so tests compare it
    with one."""

    def __init__(self, limit: int = HISTORY_FRAMES) -> None:
        super().__init__()
        self.limit = limit
        self.total = 0

    def append(self, item) -> None:
        super().append(item)
        self.total += 1
        if len(self) >= 2 * self.limit:
            del self[: len(self) - self.limit]

    def extend(self, items) -> None:
        for item in items:
            self.append(item)

    @property
    def complete(self) -> bool:
        return self.total == len(self)


class Framer:
    """H7 — cuts a byte stream fed in arbitrary chunks into 48-byte frames."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.skipped_bytes = 0
        self.bad_frames = 0

    def feed(self, data: bytes) -> list[tuple[int, bytes | None]]:
        """Frame ``data``; return ``(end, frame)`` pairs where ``end`` is the offset in ``data``
        of the frame's last byte and ``frame`` is None for a frame discarded for its tail."""
        carried = len(self._buffer)
        buffer = self._buffer + data
        found: list[tuple[int, bytes | None]] = []
        position = 0
        while True:
            match = _HEAD_PATTERN.search(buffer, position)
            if match is None:
                self.skipped_bytes += len(buffer) - position
                position = len(buffer)
                break
            self.skipped_bytes += match.start() - position
            position = match.start()
            if len(buffer) - position < FRAME_SIZE:
                break  # the rest of this frame is still to come
            frame = bytes(buffer[position : position + FRAME_SIZE])
            position += FRAME_SIZE
            if frame[-1] == _TAIL_FOR_HEAD[frame[0]]:
                found.append((position - 1 - carried, frame))
            else:
                self.bad_frames += 1
                found.append((position - 1 - carried, None))
        self._buffer = buffer[position:]
        return found


@dataclass(eq=False)
class ReceivedFrame:
    """A well-framed frame that landed at the connector (accepted or dropped)."""

    index: int  # arrival index: 0 for the first frame that landed, counting dropped ones
    arrival_s: float
    raw: bytes
    command: AnyCommand | None  # None when the bytes are framed but carry no valid command
    error: str | None = None
    accepted: bool = True


def decode_received(index: int, arrival_s: float, raw: bytes) -> ReceivedFrame:
    """The frame with its command decoded; a frame the arm cannot read still takes a slot."""
    try:
        return ReceivedFrame(index, arrival_s, raw, decode_command(raw))
    except (ArmctlError, ValueError) as error:
        return ReceivedFrame(index, arrival_s, raw, None, str(error))


@dataclass
class Connector:
    """The FIFO (H6): ``capacity_frames`` frames wait behind the one executing (200 by the document)."""

    capacity_frames: int = CONNECTOR_BUFFER_FRAMES
    queue: deque = field(default_factory=deque)  # ReceivedFrame waiting, oldest first
    executing: list = field(default_factory=list)  # taken by the arm, still holding a slot
    # The most recent well-framed frames, by arrival index (``received.total`` counts them all).
    received: RecentList = field(default_factory=RecentList)
    dropped_indexes: RecentList = field(default_factory=RecentList)
    cleared_indexes: RecentList = field(default_factory=RecentList)  # flushed by a connector reset
    peak_occupancy: int = 0

    @property
    def occupancy(self) -> int:
        """Frames waiting: what ``capacity_frames`` bounds (the executing ones are behind the arm)."""
        return len(self.queue)

    @property
    def dropped(self) -> int:
        return self.dropped_indexes.total

    def next_index(self) -> int:
        return self.received.total

    def land(self, frame: ReceivedFrame) -> bool:
        """A frame has fully arrived: buffer it, or drop it whole if the buffer is full (H6)."""
        self.received.append(frame)
        if self.occupancy >= self.capacity_frames:
            frame.accepted = False
            self.dropped_indexes.append(frame.index)
            return False
        self.queue.append(frame)
        self.peak_occupancy = max(self.peak_occupancy, self.occupancy)
        return True

    def record_unbuffered(self, frame: ReceivedFrame) -> None:
        """A frame acted on as it landed, never buffered (control frames, H5 alternative)."""
        self.received.append(frame)

    def head(self) -> ReceivedFrame | None:
        return self.queue[0] if self.queue else None

    def peek(self, offset: int) -> ReceivedFrame | None:
        return self.queue[offset] if offset < len(self.queue) else None

    def take(self) -> ReceivedFrame:
        """The arm takes the head frame: it leaves the queue (and is recorded until ``finish``)."""
        frame = self.queue.popleft()
        self.executing.append(frame)
        return frame

    def finish(self, frame: ReceivedFrame) -> None:
        """The arm has finished ``frame``: its slot is free."""
        for position, held in enumerate(self.executing):
            if held is frame:
                del self.executing[position]
                return

    def clear_waiting(self, before_index: int | None = None) -> list[ReceivedFrame]:
        """Flush the frames still waiting (only those that landed before ``before_index``)."""
        keep, gone = deque(), []
        for frame in self.queue:
            (gone if before_index is None or frame.index < before_index else keep).append(frame)
        self.queue = keep
        self.cleared_indexes.extend(frame.index for frame in gone)
        return gone
