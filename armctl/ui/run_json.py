"""``armctl run --json``: JSON lines of progress events, then one summary object.

Strategy: the run's only output on stdout — one JSON object a line, flushed as it is written,
so a web UI, a job queue or a notebook can follow a job by reading lines.  Every object has an
``event``: ``started``; ``progress`` (every ``PROGRESS_EVERY_S`` of wall time, and whenever the
last line known executed changes; with the pause state, the feed override and whether the last
frame's speed was held to the profile's limit); ``paused``/``resumed``/``override`` when the
job's control state changes; and last, exactly once, ``summary``: the Python API's
``RunResult`` itself (``RunResult.to_json``: ``outcome``, ``frames_sent``, ``total_frames``,
``last_line_sent``, ``last_line_executed``, ``arm_time_s``, ``estimated_job_s``,
``resume_line``, ``resume_command``, ``messages``, ``exit_code``).  A script that
fails its check gives a summary with outcome ``refused`` and, besides, its ``diagnostics``
(lint's JSON records).  Everything meant for people goes to stderr.

The reader may go away mid-job (``armctl run --json | head -1``): the write that finds the pipe
broken is the last one tried (``reader_gone``), and ``on_reader_gone`` stops the job the way
Ctrl-C does — the abort sequence goes and the arm is waited for, so the summary (on stderr) and
its resume line are what the arm's reports prove; the run then ends as a broken pipe ends (141).
"""

from __future__ import annotations

import json
import time

PROGRESS_EVERY_S = 1.0


def _line(statement):
    return None if statement is None else statement.line


class JsonEvents:
    """Writes the events of one run to ``stream`` (the real stdout)."""

    def __init__(self, stream, clock=time.monotonic) -> None:
        self.stream, self.clock = stream, clock
        self._last_s = None
        self._last_done = None
        self._state, self._percent = "running", 100  # the control state last told
        self.summarised = False
        self.reader_gone = False  # a write found the pipe broken: nothing more is written
        self.on_reader_gone = lambda: None  # armctl run: stop the job as Ctrl-C does

    def emit(self, event: str, **fields) -> None:
        if self.reader_gone:
            return
        try:
            self.stream.write(json.dumps({"event": event, **fields}, ensure_ascii=False) + "\n")
            self.stream.flush()
        except BrokenPipeError:
            self.reader_gone = True
            self.on_reader_gone()

    def started(self, view, script: str, from_line: int) -> None:
        self.emit("started", script=script, from_line=from_line, total_frames=view.total_frames,
                  estimated_job_s=round(view.estimated_job_s, 3), lead_s=view.lead_s)
        self._last_s = self.clock()

    def update(self, view) -> None:
        """The runner's ``on_update``: a progress event when due or when the line done moved."""
        state, percent = getattr(view, "pause_state", "running"), getattr(view, "feed_percent", 100)
        if state != self._state:  # "pausing" and "resuming" are on their way, not events
            if state == "paused" or (state == "running" and self._state in ("paused", "resuming")):
                self.emit("paused" if state == "paused" else "resumed", last_line_sent=_line(view.last_sent))
            self._state = state
        if percent != self._percent:
            self._percent = percent
            self.emit("override", feed_percent=percent)
        now = self.clock()
        done = _line(view.last_done)
        if done != self._last_done or self._last_s is None or now - self._last_s >= PROGRESS_EVERY_S:
            self._last_done, self._last_s = done, now
            self.emit("progress", frames_sent=view.frames_sent, total_frames=view.total_frames,
                      last_line_sent=_line(view.last_sent), last_line_executed=done,
                      elapsed_s=round(view.elapsed_s, 3), eta_s=round(view.eta_s, 3),
                      position_mm=None if view.position_mm is None else list(view.position_mm),
                      pause_state=state, feed_percent=percent, feed_clamped=bool(getattr(view, "feed_clamped", False)))

    def summary(self, result: dict) -> None:
        if not self.summarised:
            self.summarised = True
            self.emit("summary", **result)


def failure_result(outcome: str, exit_code: int, *, message: str | None = None, diagnostics=()) -> dict:
    """The summary of a run that sent nothing (``RunResult.nothing_sent``): refused (the
    script's errors, which it adds as ``diagnostics``: lint's JSON records), failed before the
    first frame (no arm, a bad --resume LOG), interrupted before the job was checked, or nothing
    to send (interrupted once it was: ``RunResult.interrupted_before_start``)."""
    from ..host.api import RunResult
    from ..lint.formatters import as_record

    result = RunResult.nothing_sent(outcome, exit_code=exit_code, message=message).to_json()
    if diagnostics:
        result["diagnostics"] = [as_record(diagnostic) for diagnostic in diagnostics]
    return result
