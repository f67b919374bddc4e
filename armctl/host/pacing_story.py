"""``armctl run -v``'s pacing story: why the next frame waits, and what evidence moved the bound.

Strategy: the streamer leaves why it decided as data (``write_reason``, ``bound_evidence``); this
module tells it through ``logging`` (logger ``armctl.host.runner``) only when that reason changes, so
a long job reads as a few lines, not one per frame.  The wire's own pace between two writes is
told only once ``WIRE_STORY_FRAMES`` frames in a row waited for it alone.
"""

from __future__ import annotations

import logging

from ..core.streamer import Evidence, WaitReason

_logger = logging.getLogger("armctl.host.runner")

# -v: the wire is told as the reason only once this many frames in a row waited for it alone
# (about a second at 9600 baud): between frames held back by the lead or the FIFO, the line's
# own pace between two writes is not news, and telling it would alternate with them frame by frame.
WIRE_STORY_FRAMES = 20


def telling() -> bool:
    """Whether -v's story is told (the logger's level)."""
    return _logger.isEnabledFor(logging.INFO)


class PacingStory:
    """The last reason and evidence told, for one run (``view``: its ``RunView``)."""

    def __init__(self, streamer, view) -> None:
        self.streamer, self.view = streamer, view
        self._told_wait: WaitReason | None = None  # the last wait reason logged
        self._wire_frames = 0  # frames in a row that waited for the wire alone (WIRE_STORY_FRAMES)
        self._wire_counted_at = -1  # frames_sent when a wire wait was last counted (once a frame)
        self._told_evidence: Evidence | None = None  # the last evidence logged

    def wait(self, now: float, when: float | None) -> None:
        """Log why the next write waits, when the reason differs from the last one logged."""
        reason = self.streamer.write_reason
        if reason is WaitReason.READY or not _logger.isEnabledFor(logging.INFO):
            return
        if reason is not WaitReason.WIRE:
            self._wire_frames = 0
        elif self._wire_counted_at != self.view.frames_sent:
            self._wire_frames += 1
            self._wire_counted_at = self.view.frames_sent
        if reason is self._told_wait or (reason is WaitReason.WIRE and self._wire_frames < WIRE_STORY_FRAMES):
            return
        self._told_wait = reason
        streamer, line = self.streamer, self.view.next_statement.line
        if reason is WaitReason.CAPACITY:
            why = (f"the FIFO's capacity: {streamer.frames_in_flight_bound} frames written and not known consumed, "
                   f"the bound is {streamer.limit_frames} (the connector's FIFO less a margin); only new evidence "
                   "that frames finished lets it go")
        elif reason is WaitReason.IN_ORDER:
            why = "every frame before it to be known finished: the arm acts on this control frame as it lands"
        elif reason is WaitReason.LEAD:
            why = (f"the lead: {streamer.waiting_seconds(now):.2f} s of motion waits behind the move in progress "
                   f"and this frame adds {streamer.next_frame_motion_s:.2f} s (lead {streamer.lead_s:g} s); "
                   f"it may go in {when - now:.2f} s")
        else:
            why = (f"the wire: the last {WIRE_STORY_FRAMES} frames waited only for the frame before to leave at "
                   f"the line's rate ({streamer.frame_s * 1000:.0f} ms a frame): the job is line-bound here")
        _logger.info("t=%.2f s: line %s waits for %s", now - self.view.started_s, line, why)

    def bound(self, now: float) -> None:
        """Log what advanced the lower bound of frames consumed, when the kind of evidence changes."""
        evidence = self.streamer.bound_evidence
        if evidence is None or evidence is self._told_evidence or not _logger.isEnabledFor(logging.INFO):
            return
        self._told_evidence = evidence
        streamer = self.streamer
        done = streamer.last_known_done()
        how = {
            Evidence.POSITION: "two agreeing position reports lie on the path of a later frame",
            Evidence.JOINTS: "two agreeing joint reports lie on the path of a later frame",
            Evidence.TIME: f"even an arm {streamer.slowest_factor:g}x slower than the model has finished them "
                           "(time the arm was seen running)",
            Evidence.AT_REST: "the arm is at rest at the last target",
            Evidence.PROGRAM_ENDED: "the arm worked after the SD program's frame landed, and rests since",
        }[evidence]
        _logger.info("t=%.2f s: evidence (%s): %s; frames known consumed: %d, through line %s",
                     now - self.view.started_s, evidence, how, streamer.consumed_lower_bound,
                     getattr(done, "line", "?"))
