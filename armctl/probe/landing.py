"""When the probe's frames reached the arm, as far as the port's own reports prove it; pure.

Strategy: a frame is a run of bytes in the stream the probe writes; ``write()`` returning says
only that the port took them (a host-side buffer — the OS's, an adapter's, some KB — may hold
them for a while), so a landing time is never derived from it.  The host reports instead,
after each write and each wait, how many written bytes the port still holds
(``out_waiting``, pyserial's count of bytes not yet sent); ``written − unsent`` bytes have then
left it.  From those reports, for the byte that ends a frame:

- ``landed_by``: the first report at which it had left, plus the bytes a port may still hold
  after it counts them as sent (``after_sent_bytes``: a USB adapter's own FIFO) at the line
  rate — the frame has surely landed by then (an upper bound; ``Probe.landed_by`` also keeps it
  no sooner than the line model allows, for a bridge that takes every byte at once);
- ``not_landed_at``: the last report at which it had not left — it surely had not landed then
  (a lower bound; ``write()``'s own time plus one frame's wire time is another).

Bytes written before the probe's (another program's, still in the buffer) only make
``written − unsent`` smaller while they wait, never larger: both bounds stay true.  A port that
cannot say (``socket://``, ``rfc2217://``: no ``out_waiting``) reports nothing, and every bound
is unknown (None / −∞): the caller says so rather than assume.
"""

from __future__ import annotations

import bisect


class WireLog:
    """The bytes the probe wrote and what the port said has left it; see the module docstring."""

    def __init__(self, byte_s: float, after_sent_bytes: int = 0) -> None:
        self.byte_s = byte_s
        self.after_sent_bytes = after_sent_bytes
        self.written_bytes = 0
        self.reporting = False  # the port has said at least once what it still holds
        # runs of reports that agree: bytes known to have left (rising from run to run), and the
        # first and the last report of the run
        self._left: list[int] = []
        self._first_s: list[float] = []
        self._last_s: list[float] = []
        self._moving_s = 0.0  # the last report that showed a byte leave, or nothing held

    def wrote(self, size: int) -> int:
        """``size`` bytes handed to the port; the stream position just past them."""
        self.written_bytes += size
        return self.written_bytes

    def report(self, now_s: float, unsent_bytes: int) -> None:
        """The port holds ``unsent_bytes`` of what was written, at ``now_s``."""
        self.reporting = True
        left = max(0, self.written_bytes - unsent_bytes)
        if unsent_bytes <= 0 or not self._left or left > self._left[-1]:
            self._moving_s = now_s
        if self._left and left <= self._left[-1]:  # no news (a byte that left stays gone)
            self._last_s[-1] = max(self._last_s[-1], now_s)
            return
        self._left.append(left)
        self._first_s.append(now_s)
        self._last_s.append(now_s)

    def unsent_bytes(self) -> int:
        """Bytes written that the latest report does not show gone."""
        return self.written_bytes - (self._left[-1] if self._left else 0)

    def stuck_s(self, now_s: float) -> float:
        """How long the port has held bytes without sending one (0 while it sends or holds none)."""
        return 0.0 if not self.reporting or self.unsent_bytes() <= 0 else max(0.0, now_s - self._moving_s)

    def left_s(self, end: int) -> float | None:
        """When a report first showed the bytes up to stream position ``end`` gone (None: none yet)."""
        k = bisect.bisect_left(self._left, end)
        return self._first_s[k] if k < len(self._left) else None

    def landed_by(self, end: int) -> float | None:
        """The frame ending at stream position ``end`` has surely landed by this time (None: unknown)."""
        left_s = self.left_s(end)
        return None if left_s is None else left_s + self.after_sent_bytes * self.byte_s

    def not_landed_at(self, end: int) -> float:
        """The frame ending at ``end`` had surely not landed at this time (−∞: nothing known)."""
        k = bisect.bisect_left(self._left, end)  # runs before k: its last byte had not left yet
        return self._last_s[k - 1] if k > 0 else float("-inf")
