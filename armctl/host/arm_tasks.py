"""The order of an arm's tasks: one worker thread, the moves queued on it, the running job.

Strategy: ``Tasks`` is what makes ``Arm`` thread-safe.  Public calls put a task on the worker's
queue (``Worker``, the only thread that touches the link); a blocking call waits for its task
(``call``), a move with ``wait=False`` is queued (``queue``) and returns at once.  A queued move
that fails cancels the moves queued after it — the arm is no longer where they assume — and
its error is raised by the next blocking call (``raise_deferred``).  The worker is a daemon
thread, so an arm still open when the interpreter exits is closed then as leaving a ``with`` block
closes it (``close_at_exit``): its queued moves run, each once — unless the program died of an
exception (Ctrl-C too): then it is stopped first.  The exit hook holds the arm weakly: an arm no
one holds any more (so with nothing queued: a queued move holds it) is closed as it goes
(``_close_dropped``), not kept with its worker and port until the exit.  ``stop`` counts the stops (a job whose call
began before one sends nothing), cancels the queue and asks the running job (``attach``/``detach``
make it reachable) to stop; ``ask_job`` hands a request to its engine (none while it stops).
"""
from __future__ import annotations

import atexit
import logging
import queue
import sys
import threading
import weakref
from concurrent.futures import Future
from functools import partial
from typing import Any, Callable

from .arm_worker import JOB_ENDED, JobControl
from ..errors import ArmctlError
from .jobflow import JobFailed

SKIPPED = object()  # a task not run: a queued move before it failed (its error is raised instead)


def closed_error(url: str) -> ArmctlError:
    """What a call on an arm closed already raises (``Arm``'s and ``AsyncArm``'s)."""
    return ArmctlError(f"the arm on {url} is closed")


class Worker:
    """One thread that runs tasks in order: the only one that touches the arm's link."""

    def __init__(self, name: str) -> None:
        self._tasks: queue.SimpleQueue = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self._thread.start()

    def submit(self, task: Callable[[], Any]) -> Future:
        future: Future = Future()
        self._tasks.put((task, future))
        return future

    def call(self, task: Callable[[], Any]) -> Any:
        """Run ``task`` on the worker and return its result (at once when already on it)."""
        if self.is_current():
            return task()
        return self.submit(task).result()

    def is_current(self) -> bool:
        return threading.current_thread() is self._thread

    def stop(self, join: bool = True) -> None:
        self._tasks.put(None)
        if join and not self.is_current():
            self._thread.join()

    def _loop(self) -> None:
        while (item := self._tasks.get()) is not None:
            self._run(*item)
            item = None  # (a task done is not held while the next is waited for: it would hold its arm)

    @staticmethod
    def _run(task: Callable[[], Any], future: Future) -> None:
        if not future.set_running_or_notify_cancel():
            return  # cancelled while queued (stop, or a queued move before it failed)
        try:
            future.set_result(task())
        except BaseException as error:  # handed to whoever waits; the worker goes on
            future.set_exception(error)


class Tasks:
    """The worker of the arm on ``url``, the moves queued on it and the job it runs."""

    def __init__(self, url: str, link: Any = None) -> None:
        """``link``: the port the arm's worker owns, closed at the interpreter's exit if still open."""
        self.url = url
        self.lock = threading.RLock()  # reentrant: stop() from a signal handler may come while this thread holds it
        self.worker = Worker(f"armctl-arm {url}")
        self.queued: list[Future] = []  # moves queued with wait=False, not yet finished
        self.deferred: BaseException | None = None  # the error of a queued move, for the next blocking call
        self.job: JobControl | None = None
        self.stops = 0  # how many times stop() was called: a queued move from before it is not sent
        self.closed = False
        self._link = link
        self._failed: list[str] = []  # ``deferred`` in words, for ``_close_dropped`` (it may not hold the error)
        self._at_exit = None if link is None else partial(_close_if_open, weakref.ref(self))  # (its own: unregistered alone)
        if self._at_exit is not None:
            atexit.register(self._at_exit)
            self._dropped = weakref.finalize(self, _close_dropped, self.worker, link, self._at_exit, url, self._failed)
            self._dropped.atexit = False  # (at the exit, ``_at_exit`` closes it, waiting for its queue)

    def call(self, task: Callable[[], Any], waiting: str | None = None) -> Any:
        """Run ``task`` on the worker after everything queued — unless a queued move failed:
        then its error is raised and ``task`` does not run.  ``waiting``: the name of a call that
        waits for the arm (``run``, ``wait``), refused from a hook of the running job; Ctrl-C while
        it waits stops the arm (the job it started, the moves it waits for), as ``armctl run``'s
        does, rather than let them run on behind a program that catches the exception and goes on."""
        self.check_open()
        if waiting is not None:
            self.refuse_on_worker(waiting)

        def unless_failed():
            return SKIPPED if self.deferred is not None else task()

        try:
            result = self.worker.call(unless_failed)
        except KeyboardInterrupt:
            if waiting is not None:
                self.stop_once()
            raise
        finally:
            self.raise_deferred()
        if result is SKIPPED:  # another thread took the queued move's error first
            raise JobFailed("not run: a move queued before it failed")
        return result

    def check_open(self) -> None:
        if self.closed:
            raise closed_error(self.url)

    def refuse_on_worker(self, call: str) -> None:
        """``ArmctlError`` for ``call`` (one that waits for the arm) made on the worker: from
        ``on_progress`` or an observer, whose job is the task running — it would run inside that
        job's stream (its frames between the job's), or never see the queue it waits for."""
        if self.worker.is_current():
            raise ArmctlError(f"arm.{call}() was called from on_progress or an observer of the job running on {self.url}: "
                              f"it would run inside that job; queue a move with wait=False, or call {call}() after "
                              "run() returns (stop() and status() may be called there)")

    def queue(self, task: Callable[[], Any], stops: int) -> None:
        """``task`` queued on the worker, not waited for: not run if ``stop()`` came since
        ``stops``, nor if a move queued before it failed (its error is kept, the rest cancelled)."""
        self.check_open()

        def queued() -> Any:
            if stops != self.stops:
                return None  # stop() came after this move was queued (it cancels the queue)
            if self.deferred is not None:
                raise JobFailed("not sent: a move queued before it failed")
            return task()

        with self.lock:
            future = self.worker.submit(queued)
            self.queued.append(future)
        future.add_done_callback(self._queued_done)

    def raise_deferred(self) -> None:
        with self.lock:
            error, self.deferred = self.deferred, None
            self._failed.clear()
        if error is not None:
            raise error

    def _queued_done(self, future: Future) -> None:
        """A queued move ended (on the worker): keep its error; a failure cancels the rest."""
        error = None if future.cancelled() else future.exception()
        with self.lock:
            if future in self.queued:
                self.queued.remove(future)
            if error is None:
                return
            self.deferred = self.deferred or error
            self._failed[:] = [str(self.deferred)]
            later, self.queued = self.queued, []
        for queued in later:  # outside the lock: cancel() calls this method again at once
            queued.cancel()

    def attach(self, control: JobControl, stops: int) -> bool:
        """``control`` is the running job (``pause``, ``stop`` reach it); True when a ``stop()``
        came since the call began (``stops``)."""
        with self.lock:
            self.job = control
            return stops != self.stops

    def detach(self, control: JobControl) -> None:
        with self.lock:
            self.job = None
            control.end()

    def ask_job(self, action: Callable[[Any], Any]) -> Any:
        """``action(job)`` carried out by the running job's engine at the runner's next turn
        (at once when called on the worker, from ``on_progress``: that is between two turns);
        ``JOB_ENDED`` when no job is running or it ended first; ``ArmctlError`` while it stops (its
        abort pauses the arm itself, and a resume now would run the frames it left queued)."""
        self.check_open()
        with self.lock:
            job = self.job
            if job is None:
                return JOB_ENDED
            if job.stopping:
                raise ArmctlError(f"the job on {self.url} is stopping (its abort sequence pauses the arm): no pause, "
                                  "resume or feed override now; ask again once run() has returned")
            if self.worker.is_current():
                return action(job.runner.job)
            future = job.request(action)
        return future.result()

    def stop(self, why: str | None = None) -> None:
        """Count the stop, cancel the queued moves, ask the running job to stop (see ``Arm.stop``)."""
        with self.lock:
            self.stops += 1
            queued, self.queued = self.queued, []
            job = self.job
        for future in queued:  # outside the lock: cancel() calls _queued_done at once
            future.cancel()
        if job is not None:
            job.request_stop(why)

    def stop_once(self, why: str | None = None) -> None:
        """``stop``, unless the running job is stopping already: a Ctrl-C that leaves a waiting
        call or a ``with`` block after a stop was asked is that stop's, not a second one (which
        would cut the wait for the arm to come to rest short)."""
        with self.lock:
            stopping = self.job is not None and self.job.stop_asked
        if not stopping:
            self.stop(why)

    def close(self, link, raise_deferred: bool = True) -> None:
        """Wait for the queued tasks (each run exactly once), stop the worker, close ``link``."""
        self.refuse_on_worker("close")
        with self.lock:
            if self.closed:
                return
            self.closed = True
        if self._at_exit is not None:
            atexit.unregister(self._at_exit)
            self._dropped.detach()
        try:
            self.worker.call(lambda: None)  # every task queued before has run
        except KeyboardInterrupt:  # Ctrl-C while the queue runs out: stop the arm, as leaving a with block by it does
            self.stop_once()
            raise
        finally:
            self.worker.stop()
            link.close()
        if raise_deferred:
            self.raise_deferred()

    def close_at_exit(self) -> None:
        """At the interpreter's exit, an arm nobody closed: closed as leaving a ``with`` block
        would — stopped first if the program died of an exception (``sys.last_value``: Ctrl-C
        too) — and a queued move's error said on the ``armctl.host.api`` logger (WARNING: on
        stderr when logging is not set up), not dropped without a word."""
        if getattr(sys, "last_value", None) is not None:
            self.stop_once()
        try:
            self.close(self._link, raise_deferred=False)
        except KeyboardInterrupt:  # (close stopped the arm and waited for it)
            pass
        error = self.deferred
        if error is not None:
            _say_failed(self.url, "at exit", error)


def _close_if_open(tasks: "weakref.ref[Tasks]") -> None:
    """The exit hook of one arm: closed (``close_at_exit``) if it is still open; held weakly."""
    alive = tasks()
    if alive is not None:
        alive.close_at_exit()


def _close_dropped(worker: Worker, link, at_exit, url: str, failed: list[str]) -> None:
    """An arm no one holds any more — so its worker is idle: a queued move holds the arm — closed
    as it goes: its port closed and its worker ended, both on the worker and never waited for here
    (a collection may come on any thread, the worker's or the port reader's among them); its exit
    hook unregistered; a queued move's error no call raised (``failed``) said, as at the exit."""
    atexit.unregister(at_exit)
    worker.submit(link.close)
    for error in failed:
        worker.submit(partial(_say_failed, url, "as the program dropped it", error))
    worker.stop(join=False)


def _say_failed(url: str, when: str, error) -> None:
    logging.getLogger("armctl.host.api").warning("armctl: the arm on %s was closed %s; a move queued on it with "
                                                 "wait=False failed: %s", url, when, error)
