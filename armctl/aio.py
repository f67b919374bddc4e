"""The asyncio API: ``from armctl.aio import AsyncArm`` — ``Arm``'s calls as coroutines.

Strategy: not a second engine.  An ``AsyncArm`` wraps one ``armctl.Arm`` (armctl/host/api.py) and
runs each of its blocking calls in a small thread pool of its own, so the event loop never
blocks and a long ``run`` does not starve the loop's default executor; the arm's own worker
thread still owns the link, so the checks, the pacing, the journal and the end-of-job proof are
``armctl run``'s, call for call.  While ``run`` waits, ``pause``, ``resume``, ``feed_override``
and ``stop`` go through other threads of the pool to the job engine, as the run panel's keys do.

Events: ``run(..., on_event=)`` is given the ``armctl run --json`` events (``started``,
``progress``, ``paused``, ``resumed``, ``override``, ``note`` and last ``summary``), each a
dict, called on the event loop (the job's observer runs on the arm's worker and hands each
event over with ``loop.call_soon_threadsafe``; it never waits for the loop).  Cancelling the
task that awaits ``run`` or ``move`` stops the arm as ``Arm.stop`` does (Ctrl-C's path).
"""
from __future__ import annotations

import asyncio
import os
import time
from concurrent.futures import ThreadPoolExecutor
from typing import IO, Any, Callable

from .host.api import Arm, ArmStatus, JobObserver, RunResult
from .host.arm_tasks import closed_error
from .core.streamer import DEFAULT_LEAD_S

__all__ = ["AsyncArm", "EventObserver"]

POOL_THREADS = 4  # a run, a control call, a status read, a close: never more at once on one arm
SNAPSHOT_EVERY_S = 0.05  # how often (wall) the observer refreshes ``EventObserver.latest``


class EventObserver(JobObserver):
    """A ``JobObserver`` that turns the job into ``armctl run --json``'s events (the same
    ``JsonEvents`` rules: a progress event every second and whenever the last line known
    executed moves on) and hands each, as a dict, to ``sink`` — called on the arm's worker, so
    ``sink`` must not block (``AsyncArm`` passes one that schedules the event on the loop).
    ``latest`` holds the job's counts as of the last ``SNAPSHOT_EVERY_S`` (for a status query
    between two events)."""

    def __init__(self, sink: Callable[[dict], None], script_name: str = "<script>") -> None:
        from .ui.run_json import JsonEvents

        observer = self

        class _Events(JsonEvents):
            def emit(self, event: str, **fields) -> None:
                observer.sink({"event": event, **fields})

        self.sink, self.script_name = sink, script_name
        self.events = _Events(None)
        self.latest: dict[str, Any] = {}
        self._latest_s = float("-inf")

    def started(self, view, plan) -> None:
        self.events.started(view, self.script_name, plan.from_line)
        self._snapshot(view)

    def update(self, view) -> None:
        self.events.update(view)
        now = time.monotonic()
        if now - self._latest_s >= SNAPSHOT_EVERY_S:
            self._latest_s = now
            self._snapshot(view)

    def note(self, text: str) -> None:
        self.sink({"event": "note", "text": text.strip()})

    def warning(self, diagnostic) -> None:
        pass  # the caller linted the script before: its warnings are in the lint findings

    def _snapshot(self, view) -> None:
        self.latest = {"frames_sent": view.frames_sent, "total_frames": view.total_frames,
                       "last_line_sent": getattr(view.last_sent, "line", None),
                       "last_line_executed": getattr(view.last_done, "line", None),
                       "eta_s": round(view.eta_s, 3), "pause_state": getattr(view, "pause_state", "running"),
                       "feed_percent": getattr(view, "feed_percent", 100)}


class AsyncArm:
    """One arm as coroutines; an async context manager that closes it.  Built on ``Arm``:
    ``AsyncArm(arm)`` takes an open one, ``await AsyncArm.open(...)`` opens one as
    ``Arm.open`` does (same arguments)."""

    def __init__(self, arm: Arm) -> None:
        self.arm = arm
        self._pool = ThreadPoolExecutor(POOL_THREADS, thread_name_prefix=f"armctl-aio {arm.url}")
        self._closed = False

    @classmethod
    async def open(cls, port: str | None = None, baud: int | None = None, profile=None, *,
                   lead_s: float = DEFAULT_LEAD_S, **options) -> AsyncArm:
        arm = await asyncio.to_thread(Arm.open, port, baud, profile, lead_s=lead_s, **options)
        return cls(arm)

    @property
    def url(self) -> str:
        return self.arm.url

    @property
    def baud(self) -> int:
        return self.arm.baud

    @property
    def profile(self):
        """The arm's ``Profile`` (the one its checks use)."""
        return self.arm.profile

    @property
    def is_virtual(self) -> bool:
        """A ``sim://?clock=virtual`` port: model time moves only while someone waits on it."""
        return self.arm.is_virtual

    async def __aenter__(self) -> AsyncArm:
        return self

    async def __aexit__(self, kind, error, traceback) -> None:
        if error is not None:
            self.arm.stop()
        await self.close()

    async def _call(self, function: Callable[..., Any], *args, **kwargs) -> Any:
        if self._closed:  # (the pool is shut down: say what the arm says)
            raise closed_error(self.url)
        return await self._in_pool(function, *args, **kwargs)

    async def _in_pool(self, function: Callable[..., Any], *args, **kwargs) -> Any:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self._pool, lambda: function(*args, **kwargs))

    async def _until_done(self, function: Callable[..., Any], *args, **kwargs) -> Any:
        """A call that streams: cancelling the awaiting task stops the arm (and still waits for
        the job to end, so the arm is never left to a thread nobody watches)."""
        future = asyncio.ensure_future(self._call(function, *args, **kwargs))
        try:
            return await asyncio.shield(future)
        except asyncio.CancelledError:
            self.arm.stop("stopped: the task awaiting it was cancelled")
            try:
                await future
            except Exception:
                pass
            raise

    # --- moving ------------------------------------------------------------------------------

    async def move(self, *, timeout: float | None = None, **words: float) -> RunResult:
        """``Arm.move(**words)``, waited for: the arm's reports prove it at rest at the target
        (no ``wait=``: for a move that streams while the loop goes on, make it a task)."""
        if "wait" in words:
            raise TypeError("AsyncArm.move() takes no wait=: it is always awaited (a move that streams while you "
                            "go on is a task: asyncio.create_task(arm.move(...)))")
        return await self._until_done(self.arm.move, timeout=timeout, **words)

    async def run(self, script, *, from_line: int = 1, on_event: Callable[[dict], Any] | None = None,
                  on_progress=None, timeout: float | None = None, log: IO[str] | None = None,
                  abort: str = "pause", resume: str | os.PathLike[str] | None = None,
                  observer: JobObserver | None = None) -> RunResult:
        """``Arm.run`` (same arguments), awaited.  ``on_event(dict)``: the ``run --json`` events,
        called on this loop; the last is the ``summary`` (the ``RunResult``'s words), sent also
        when the job ends ``JobFailed`` (its result; then the error is raised).  An exception
        ``on_event`` raises stops the job (``Arm.stop``): ``JobFailed`` from it, with the result."""
        from .host.jobflow import JobFailed

        loop = asyncio.get_running_loop()
        failed: list[Exception] = []  # what on_event raised: it stops the job, as on_progress's error does

        def deliver(event: dict) -> None:
            if on_event is None or (failed and event["event"] != "summary"):
                return
            try:
                on_event(event)
            except Exception as error:
                failed.append(error)
                self.arm.stop(f"stopped: on_event raised {type(error).__name__}: {error}")

        if observer is None and on_event is not None:
            named = isinstance(script, os.PathLike) or (isinstance(script, str) and "\n" not in script)
            name = getattr(script, "name", None) or (os.fspath(script) if named else "<script>")  # (Arm.run checks the type)

            def sink(event: dict) -> None:
                loop.call_soon_threadsafe(deliver, event)

            observer = EventObserver(sink, name)
        try:
            result = await self._until_done(self.arm.run, script, from_line=from_line, on_progress=on_progress,
                                            timeout=timeout, observer=observer, log=log, abort=abort, resume=resume)
        except JobFailed as error:
            if error.result is not None:
                deliver({"event": "summary", **error.result.to_json()})
            if not failed:
                raise
            result = error.result
        else:
            deliver({"event": "summary", **result.to_json()})
        if failed:
            raise JobFailed(f"on_event raised {type(failed[0]).__name__}: {failed[0]}: the job was stopped", result) \
                from failed[0]
        return result

    # --- reading and control -----------------------------------------------------------------

    async def status(self, timeout: float | None = None) -> ArmStatus:
        """``Arm.status``: after the moves and the job asked for before it."""
        return await self._call(self.arm.status, timeout)

    async def status_json(self, timeout: float | None = None) -> dict:
        """The arm's decoded report with the keys of ``armctl status --once --json``
        (``Arm.status_json``): on a wall-clock port read at once, even while a job runs; on a
        virtual-clock port by the arm's worker (model time moves only there), after a running job."""
        return await self._call(self.arm.status_json, timeout, at_once=True)

    async def pause(self) -> bool:
        return await self._call(self.arm.pause)

    async def resume(self) -> bool:
        return await self._call(self.arm.resume)

    async def toggle_pause(self) -> bool:
        return await self._call(self.arm.toggle_pause)

    async def feed_override(self, percent: float, *, relative: bool = False) -> int:
        return await self._call(self.arm.feed_override, percent, relative=relative)

    async def stop(self, why: str | None = None) -> None:
        """``Arm.stop``: returns at once; the awaited ``run`` ends "interrupted"."""
        self.arm.stop(why)

    async def write_frames(self, frames: list[bytes]) -> None:
        """Write control frames (a jog's joystick values) on the arm's worker, after every
        queued task; for ``armctl serve``'s jog buttons on an idle arm."""
        arm = self.arm

        def write() -> None:
            for frame in frames:
                arm._link.write(frame)

        await self._call(arm._call, write)

    async def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            await self._in_pool(self.arm.close)
        finally:
            self._pool.shutdown(wait=False)
