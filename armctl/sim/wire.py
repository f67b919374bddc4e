"""One direction of the serial line, in virtual time.

Strategy: a byte handed to the line at ``now_s`` starts after every byte still on the wire
and then occupies ``byte_seconds(baud)`` (8N1: 10 bits).  Bytes are kept as *runs* —
``(start_s, data)`` with no gap inside — so byte ``k`` of a run has fully arrived at
``start_s + (k + 1) · byte_s``.  Every question (how many bytes have arrived by ``t``, when does
the next one arrive, how many are still to go) is answered by arithmetic on runs, never by a
loop over bytes.  Pure: the time is always an argument.
"""

from __future__ import annotations

import math
from collections import deque

from ..core.protocol import DEFAULT_BAUD, byte_seconds

# Arrival times are sums of many byte times; a frame whose last bit lands at exactly ``t`` must
# count as arrived at ``t`` despite rounding, so comparisons allow this much slack.
TIME_EPSILON_S = 1e-9


class Wire:
    """Bytes in flight from one end of the line to the other, at the baud rate."""

    def __init__(self, baud: int = DEFAULT_BAUD, keeps_bytes: bool = True) -> None:
        """``keeps_bytes=False`` tracks timing only (the receiver parsed the bytes already)."""
        if not baud > 0:
            raise ValueError(f"baud rate must be positive, not {baud!r}")
        self.baud = baud
        self.byte_s = byte_seconds(baud)
        self.free_at_s = 0.0  # when the last byte handed over so far has fully arrived
        self.bytes_sent = 0
        self.keeps_bytes = keeps_bytes
        self._runs: deque[list] = deque()  # [start_s, bytearray, bytes already taken]

    def send(self, data: bytes, now_s: float) -> float:
        """Queue ``data`` behind the bytes still on the wire; return when its first byte starts."""
        start_s = max(now_s, self.free_at_s)
        if data and self.keeps_bytes:
            if self._runs and start_s == self.free_at_s:
                self._runs[-1][1] += data  # no gap: the run simply grows
            else:
                self._runs.append([start_s, bytearray(data), 0])
        if data:
            self.free_at_s = start_s + len(data) * self.byte_s
            self.bytes_sent += len(data)
        return start_s

    def arrival_s(self, start_s: float, index: int) -> float:
        """When byte ``index`` of a run that started at ``start_s`` has fully arrived."""
        return start_s + (index + 1) * self.byte_s

    def take(self, now_s: float) -> bytes:
        """Every byte whose last bit has arrived by ``now_s`` and was not taken before."""
        if not self._runs:
            return b""
        out = bytearray()
        while self._runs:
            run = self._runs[0]
            start_s, data, taken = run
            arrived = min(len(data), int(math.floor((now_s - start_s + TIME_EPSILON_S) / self.byte_s)))
            if arrived > taken:
                out += data[taken:arrived]
                run[2] = arrived
            if arrived < len(data):
                break
            self._runs.popleft()
        return bytes(out)

    def next_arrival_s(self) -> float | None:
        """When the next byte not yet taken will have arrived (None if the wire is empty)."""
        if not self._runs:
            return None
        start_s, _data, taken = self._runs[0]
        return self.arrival_s(start_s, taken)

    def run_end_s(self) -> float | None:
        """When the first run still on the wire has fully arrived (a whole status burst)."""
        if not self._runs:
            return None
        start_s, data, _taken = self._runs[0]
        return self.arrival_s(start_s, len(data) - 1)

    def in_flight(self, now_s: float) -> int:
        """Bytes handed over but not fully arrived by ``now_s``."""
        if now_s >= self.free_at_s - TIME_EPSILON_S:
            return 0
        return min(self.bytes_sent, math.ceil((self.free_at_s - now_s - TIME_EPSILON_S) / self.byte_s))
