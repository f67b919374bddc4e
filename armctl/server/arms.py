"""One served arm: its ``AsyncArm``, its jobs and their journals, its controller, its viewers.

Strategy: the server's state of one arm, and nothing about HTTP.  A job is checked here
(``checked.check``, once, off the event loop and one script at a time: ``off_loop``; errors →
``ScriptError``, nothing sent; ``Arm.run`` takes the ``CheckedScript``), given an id, its
script kept and its journal opened (``run --log``'s journal, through ``Arm.run``'s ``log=``:
``<journal dir>/<id>.txt`` and ``<id>.log``), then run as an asyncio task that no client owns:
it survives its client going away, and a restarted server resumes it from its journal
(``Arm.run(resume=)``).  One job (or move) at a time: another is ``Busy``.  At most one client
controls the arm (the first WebSocket that asks, until its client's last such socket closes);
while one does, state-changing calls from any other client are ``NotController``.

Jog: continuous jog is ``armctl jog``'s dead-man (armctl/jog/deadman.py) with a lease the
controlling page renews with a heartbeat: a ``jog`` message starts or renews an axis, the lease
ends ``JOG_LEASE_S`` after the last one, and the neutral goes out at once when it ends, when
the page says ``jog_stop`` or when its WebSocket closes — so the arm gets the neutral within
``JOG_LEASE_S`` + a poll of a lost heartbeat or a closed tab.
"""
from __future__ import annotations

import asyncio
import contextlib
import json
import re
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ArmctlError
from .hub import Hub

NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]{1,32}")
MAX_VIEWERS = 200  # WebSockets on one arm (each holds at most its queue): more are refused (503)
STATUS_EVERY_S = 0.25  # a status event this often while someone watches
JOG_LEASE_S = 0.075  # the jog stops this long after the page's last heartbeat
JOG_POLL_S = 0.01  # how often the dead-man's lease is looked at
JOB_END_WAIT_S = 30.0  # a stopping server waits this long for a stopped job to end (the arm to come to rest)
_SCRIPT_WORK = threading.Lock()  # one script's check or path at a time in the process (``off_loop``)
_WAITING: set[asyncio.Future] = set()  # the answers script work owes (``abandon_script_work``)


async def off_loop(function, *args):
    """``function(*args)`` — a script's check or path, seconds of CPU for a big one (a 128 MiB
    one minutes) — in a thread, one at a time in the process.  Off the event loop, which carries
    every viewer's events and the jog dead-man; one at a time, because two at once starve the
    arms' worker threads of the GIL (three 12 MB lints at once made a 48.3 s job take 49.4 s and
    85.1 s of arm time; one at a time, 48.3 s and 48.5 s).  A daemon thread: the work changes nothing, so a
    stopping server abandons it (``abandon_script_work``) rather than wait for it."""
    loop = asyncio.get_running_loop()
    answer = loop.create_future()

    def settle(done: bool, value) -> None:
        if not answer.done():
            answer.set_result(value) if done else answer.set_exception(value)

    def work() -> None:
        with _SCRIPT_WORK:
            if answer.done():
                return  # abandoned while it waited for its turn
            try:
                done, value = True, function(*args)
            except BaseException as error:  # (handed to the request, as the call's own)
                done, value = False, error
        try:
            loop.call_soon_threadsafe(settle, done, value)
        except RuntimeError:
            pass  # the loop is closed: the server stopped meanwhile

    _WAITING.add(answer)
    answer.add_done_callback(_WAITING.discard)
    threading.Thread(target=work, name="armctl serve: script work", daemon=True).start()
    return await answer


def abandon_script_work() -> None:
    """The requests of this loop waiting for script work end now (cancelled): a stopping server
    does not wait for checks (with three 12 MB lints in flight it exited after 31.5 s)."""
    loop = asyncio.get_running_loop()
    for answer in list(_WAITING):
        if answer.get_loop() is loop:
            answer.cancel()


class Busy(ArmctlError):
    """A job or a move is running on the arm."""


class NotController(ArmctlError):
    """Another client controls the arm: this one is read-only."""


class UnknownJob(ArmctlError):
    pass


@dataclass
class Job:
    id: str
    name: str
    script_path: Path
    log_path: Path
    observer: Any = None  # the EventObserver while it runs
    streaming: asyncio.Event = field(default_factory=asyncio.Event)  # set at its first frame (or its end)
    result: dict | None = None  # the RunResult's words once it ended
    error: str | None = None
    task: asyncio.Task | None = field(default=None, repr=False)

    def to_json(self) -> dict:
        if self.result is not None:
            return {"id": self.id, "name": self.name, **self.result, "running": False,
                    **({"error": self.error} if self.error else {})}
        latest = dict(self.observer.latest) if self.observer is not None else {}
        return {"id": self.id, "name": self.name, "outcome": None, "running": True,
                "frames_sent": latest.pop("frames_sent", 0), "total_frames": latest.pop("total_frames", None),
                "last_line_sent": latest.pop("last_line_sent", None),
                "last_line_executed": latest.pop("last_line_executed", None), **latest}


class ArmService:
    """One arm as the server serves it."""

    def __init__(self, name: str, port: str, arm, journal_dir: Path) -> None:
        self.name, self.port, self.arm = name, port, arm
        self.journal_dir = journal_dir
        self.hub = Hub()
        self.jobs: dict[str, Job] = {}
        self.running: Job | None = None
        self.moving = False
        self._stop_asked = False  # the running job or move was asked to stop (``stop_once``)
        self.controller: str | None = None
        self._control_sockets = 0  # the controller's WebSockets that asked for control (a duplicated tab: 2)
        self.status: dict | None = None
        self._status_task: asyncio.Task | None = None
        self._status_read = asyncio.Lock()  # one status read at a time (``read_status``)
        self._jog = None  # the Deadman, once a jog started
        self._jog_task: asyncio.Task | None = None

    # --- what it is --------------------------------------------------------------------------

    def describe(self) -> dict:
        return {"name": self.name, "port": self.port, "url": self.arm.url, "baud": self.arm.baud,
                "virtual_clock": self.arm.is_virtual, "busy": self.busy,
                "job": None if self.running is None else self.running.id,
                "controlled": self.controller is not None, "viewers": len(self.hub.viewers)}

    @property
    def busy(self) -> bool:
        return self.running is not None or self.moving

    def check_not_jogging(self) -> None:
        if self._jog is not None and self._jog.active:
            raise Busy(f"arm {self.name!r} is jogging: release the jog button first")

    def publish(self, event: dict, but=None) -> None:
        self.hub.publish({"arm": self.name, **event}, but)

    # --- control -----------------------------------------------------------------------------

    def take_control(self, client: str) -> bool:
        """A WebSocket of ``client`` asks for control: True when it has it (call
        ``release_control`` when that socket closes)."""
        if self.controller in (None, client):
            self.controller = client
            self._control_sockets += 1
            return True
        return False

    def release_control(self, client: str) -> None:
        """A socket that took control closed: control is free once the client's last one did."""
        if self.controller == client:
            self._control_sockets -= 1
            if self._control_sockets == 0:
                self.controller = None
                self.publish({"event": "control", "controller": None})

    def check_control(self, client: str | None) -> None:
        if self.controller is not None and client != self.controller:
            raise NotController(f"arm {self.name!r} is controlled by another client: this one is read-only")

    # --- jobs --------------------------------------------------------------------------------

    async def check(self, snapshot, *, errors_raise: bool = True):
        """``snapshot`` checked for this arm's profile (``Arm.run``'s check, made once: the
        ``CheckedScript`` is what the job runs): ``errors`` and ``diagnostics`` are ``armctl lint``'s."""
        from ..core.checked import check

        checked = await off_loop(check, snapshot, self.arm.profile)
        if errors_raise and checked.refusal() is not None:
            raise checked.refusal()
        return checked

    def check_free(self, client: str | None) -> None:
        """``client`` may start a job or a move now (``NotController``, ``Busy`` otherwise)."""
        self.check_control(client)
        if self.busy:
            raise Busy(f"arm {self.name!r} is running job {self.running.id if self.running else '(a move)'}: "
                       "wait for it to end or stop it")
        self.check_not_jogging()

    async def start_job(self, snapshot, client: str | None, resume=None, claim=None) -> tuple[Job, Any]:
        """Check, journal and start ``snapshot`` (``ScriptError``: nothing sent; ``Busy``);
        ``resume``: the ``joblog.ResumePoint`` of an earlier job of this script; ``claim``: what
        the job holds until it ends (a resume's lock on the log it continues), closed then."""
        self.check_free(client)  # before the check's work, and again after it (another job may have begun)
        checked = await self.check(snapshot)
        self.check_free(client)
        job_id = time.strftime("%Y%m%dT%H%M%S") + "-" + uuid.uuid4().hex[:6]
        self.journal_dir.mkdir(parents=True, exist_ok=True)
        job = Job(job_id, snapshot.name, self.journal_dir / f"{job_id}.txt", self.journal_dir / f"{job_id}.log")
        job.script_path.write_bytes(snapshot.data)
        self.jobs[job_id] = self.running = job
        self._stop_asked = False
        job.task = asyncio.ensure_future(self._run(job, checked, resume, claim))
        return job, checked

    def journal_script(self, job_id: str) -> Path:
        """The script file of job ``job_id`` of this arm's journal; ``UnknownJob`` if none."""
        script = self.journal_dir / f"{job_id}.txt"
        if not NAME_PATTERN.fullmatch(job_id.replace("T", "")) or not script.is_file():
            raise UnknownJob(f"no job {job_id!r} in the journal of arm {self.name!r}")
        return script

    async def resume_job(self, job_id: str, client: str | None) -> tuple[Job, Any]:
        """A job of the journal (this server's or an earlier one's), continued from the line its
        log and the arm's report prove (``Arm.run(resume=)``)."""
        from ..host.log_lock import resume_claim
        from ..host.resume_words import served

        script = self.journal_script(job_id)
        log = self.journal_dir / f"{job_id}.log"
        self.check_control(client)
        words = served(self.name)  # (a refusal in the server's words: ?resume=ID, not armctl run's --resume LOG)
        # (off the event loop: the script alone may be 128 MiB)
        snapshot, resume = await off_loop(_read_resume, job_id, script, log, self.arm.url, words)
        claim = contextlib.ExitStack()  # held until the job ends (``_run``): no second resume of the log meanwhile
        try:  # (taken after the read, as armctl run --resume takes it: the read probes for it)
            claim.enter_context(resume_claim(log, words))  # another resume of it running: refused (422), nothing sent
            return await self.start_job(snapshot, client, resume=resume, claim=claim)
        except BaseException:
            claim.close()
            raise

    async def _run(self, job: Job, checked, resume, claim=None) -> None:
        from ..aio import EventObserver
        from ..host.jobflow import JobFailed

        loop = asyncio.get_running_loop()

        def event(item: dict) -> None:
            if item["event"] == "started":
                job.streaming.set()
            self.publish({"job": job.id, **item})

        observer = job.observer = EventObserver(lambda item: loop.call_soon_threadsafe(event, item), checked.name)
        self.publish({"event": "job", "job": job.id, "name": job.name, "state": "started"})
        try:
            with open(job.log_path, "w", encoding="utf-8", buffering=1) as log:
                try:
                    result = await self.arm.run(checked, observer=observer, log=log, resume=resume)
                    job.result = result.to_json()
                except JobFailed as error:
                    job.error = str(error)
                    job.result = error.result.to_json() if error.result is not None else _failed(str(error))
                except ArmctlError as error:
                    job.error = str(error)
                    job.result = _failed(str(error))
        except OSError as error:  # the journal could not be written
            job.error = f"cannot write the journal {job.log_path}: {error.strerror or error}"
            job.result = job.result or _failed(job.error)
        except Exception as error:  # never leave a job without an outcome; the server goes on
            job.error = f"{type(error).__name__}: {error}"
            job.result = job.result or _failed(job.error)
        finally:
            if claim is not None:
                claim.close()
            if job.result is None:
                job.result = _failed("the server stopped before the job ended")
            self.running = None
            job.streaming.set()
            self.publish({"event": "summary", "job": job.id, **job.result})

    def job(self, job_id: str) -> Job:
        try:
            return self.jobs[job_id]
        except KeyError:
            raise UnknownJob(f"no job {job_id!r} on arm {self.name!r}") from None

    async def running_job(self, job_id: str, client: str | None, action: str = "stop") -> Job:
        """The running job ``job_id``, once its first frame went (a pause or a feed asked while
        the arm is read and the job planned waits for that, up to the status timeout); a stopping
        one takes only a stop (a resume would be sent to the arm its stop paused, once it ended)."""
        job = self.job(job_id)
        self.check_control(client)
        if job is self.running:
            try:
                await asyncio.wait_for(job.streaming.wait(), self.arm.arm.status_timeout_s + 1.0)
            except asyncio.TimeoutError:
                pass
        if job is not self.running:
            raise Busy(f"job {job_id} is not running (outcome {job.result.get('outcome') if job.result else None})")
        if action != "stop" and self._stop_asked:
            raise Busy(f"job {job_id} is stopping: no {action} now; wait for its end")
        return job

    async def stop(self, client: str | None) -> bool:
        """Stop whatever the arm is doing — a job or a move — as Ctrl-C does (``Arm.stop``); False
        when nothing was running."""
        self.check_control(client)
        if not self.busy:
            return False
        await self.stop_once("stopped from the API")
        return True

    async def stop_once(self, why: str, *, again: bool = False) -> None:
        """``Arm.stop``, once for the running job or move: asked again while it stops, ``Arm.stop``
        cuts short its wait for the arm to come to rest — a second Ctrl-C (``again``: the server's),
        which a double-clicked Stop, a second client's, or the shutdown's close after its stop is not."""
        if again or not self._stop_asked:
            self._stop_asked = True
            await self.arm.stop(why)

    async def stop_and_wait(self, why: str) -> None:
        """``stop_once``, then the job's end waited for (``JOB_END_WAIT_S`` at most): its summary published."""
        if self.busy:
            await self.stop_once(why)
        if self.running is not None:
            with contextlib.suppress(Exception):  # (its end, or the time out: the job's faults are its record's)
                await asyncio.wait_for(asyncio.shield(self.running.task), JOB_END_WAIT_S)

    async def move(self, words: dict, client: str | None) -> dict:
        self.check_free(client)
        self.moving, self._stop_asked = True, False
        try:
            result = await self.arm.move(**words)
        finally:
            self.moving = False
        return result.to_json()

    # --- status ------------------------------------------------------------------------------

    async def read_status(self, timeout: float | None = None) -> dict:
        """The arm's report (``status_json``), one read at a time: on a virtual-clock arm a read
        waits for the running job, and readers in every thread of the arm's pool (four) would leave
        a pause or a feed waiting for the job's end — then pausing the idle arm."""
        async with self._status_read:
            return await self.arm.status_json(timeout)

    def start(self) -> None:
        self._status_task = asyncio.ensure_future(self._poll_status())

    async def _poll_status(self) -> None:
        """A status event every ``STATUS_EVERY_S`` while someone watches (on a virtual-clock port
        only between jobs: its model time belongs to the job)."""
        while True:
            await asyncio.sleep(STATUS_EVERY_S)
            if not self.hub.viewers or (self.arm.is_virtual and self.busy):
                continue
            try:
                self.status = await self.read_status(timeout=1.0)
            except ArmctlError as error:
                self.publish({"event": "status", "status": None, "error": str(error)})
                continue
            self.publish({"event": "status", "status": self.status})

    # --- jog ---------------------------------------------------------------------------------

    async def jog(self, action: str, client: str) -> None:
        """A jog heartbeat from the controlling page: start or renew ``action`` (a jog key name:
        ``j1_plus``, ``x_minus``…) for ``JOG_LEASE_S``."""
        from ..jog.deadman import Deadman, DeadmanTiming
        from ..jog.keymap import _jog_actions
        from ..jog.session import joystick_for
        from ..jog.settings import JogSettings

        if client != self.controller:
            raise NotController(f"only the controlling client jogs arm {self.name!r}")
        if self.busy:
            raise Busy(f"arm {self.name!r} is busy: no jog during a job")
        if self.arm.is_virtual:
            raise ArmctlError("a virtual-clock arm cannot jog: time does not pass by itself")
        jog = _jog_actions().get(action)
        if jog is None:
            raise ArmctlError(f"unknown jog {action!r}")
        if self._jog is None:
            line_s = 48 * 10 / self.arm.baud
            self._jog = Deadman(DeadmanTiming(initial_delay_s=JOG_LEASE_S, repeat_gap_s=JOG_LEASE_S, line_s=line_s,
                                              wake_margin_s=0.0))
            self._jog_task = asyncio.ensure_future(self._jog_loop())
        settings = JogSettings()  # armctl jog's starting speed level
        offset = settings.joystick_offsets[settings.level - 1]
        await self._write(self._jog.press(joystick_for(jog, offset), time.monotonic()))

    async def jog_stop(self) -> None:
        """Neutral now on every axis that may move (a released button, a closed page)."""
        if self._jog is not None:
            await self._write(self._jog.stop(time.monotonic()))

    async def _jog_loop(self) -> None:
        while True:
            await asyncio.sleep(JOG_POLL_S)
            await self._write(self._jog.poll(time.monotonic()))

    async def _write(self, commands) -> None:
        if commands:
            await self.arm.write_frames([command.encode() for command in commands])
            self.publish({"event": "jog", "frames": [json.loads(json.dumps(list(c.values))) for c in commands]})

    async def close(self) -> None:
        for task in (self._status_task, self._jog_task):
            if task is not None:
                task.cancel()
        await self.jog_stop()
        await self.stop_and_wait("the server is stopping")
        await self.arm.close()


def _read_resume(job_id: str, script: Path, log: Path, port: str, words):
    """(the script, the ``ResumePoint``) of job ``job_id`` of a journal — the script, then its log:
    before the 201, a log that is no log of it, or of a job on another arm than the one on ``port``,
    is refused (``ResumeRefused``: 422, in ``words``), nothing sent."""
    from ..host.jobflow import read_resume_point
    from ..host.resume_port import refuse_another_arm
    from ..script.files import ScriptSnapshot

    snapshot = ScriptSnapshot(_journal_name(log, job_id), script.read_bytes())
    point = read_resume_point(log, snapshot, words=words)  # (reads the whole journal)
    refuse_another_arm(point, port, f"stop this server and resume it with `armctl run --resume {log} --port {port} "
                       "--other-port`", words=words)  # (Arm.run's check, in the server's words)
    return snapshot, point


def _journal_name(log: Path, default: str) -> str:
    """The script's name as the journal's first record (``run --log``'s job record) keeps it."""
    try:
        with open(log, encoding="utf-8") as file:
            return str(json.loads(file.readline()).get("script") or default)
    except (OSError, ValueError, AttributeError):
        return default


def _failed(message: str) -> dict:
    from ..host.api import RunResult

    return RunResult.nothing_sent("failed", message=message).to_json()
