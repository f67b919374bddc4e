"""The one host driver (armctl/host/driver.py): it carries out ``Write | Wait | Done`` on a link, the
host's hooks around each action; and the job's host hands the engine its status frames one way
(``Job.receive_statuses``), on a wall clock as on a virtual one."""

from __future__ import annotations

import pytest

from armctl.core.actions import Done, Wait, Write
from armctl.host.driver import Host, drive
from armctl.errors import PortError
from armctl.core.job import Job
from armctl.core.protocol import PauseStatus

pytestmark = pytest.mark.timeout(30)


class ScriptedEngine:
    """Answers the actions given, in order, and records the ``now`` it was asked at."""

    def __init__(self, *actions) -> None:
        self.actions, self.asked = list(actions), []

    def next_action(self, now: float):
        self.asked.append(now)
        return self.actions.pop(0)


class FakeLink:
    def __init__(self) -> None:
        self.now_s, self.error, self.calls = 0.0, None, []

    def clock(self) -> float:
        return self.now_s

    def write(self, frame: bytes) -> None:
        self.calls.append(("write", frame))

    def wait(self, until_s, news=None) -> None:
        self.calls.append(("wait", until_s, news))
        self.now_s = until_s if until_s is not None else self.now_s + 1.0


def test_the_driver_writes_waits_and_returns_the_engines_last_action():
    engine, link = ScriptedEngine(Write(b"a"), Wait(2.5), Wait(None), Write(b"b"), Done("over")), FakeLink()
    assert drive(engine, link) == Done("over")
    assert link.calls == [("write", b"a"), ("wait", 2.5, None), ("wait", None, None), ("write", b"b")]
    assert engine.asked == [0.0, 0.0, 2.5, 3.5, 3.5]


def test_the_hosts_hooks_come_around_each_action_and_a_refused_write_does_not_go():
    seen = []

    class Recording(Host):
        news = staticmethod(lambda frames, times: None)

        def turn(self):
            seen.append("turn")

        def writing(self, action, now):
            seen.append(("writing", action.frame))
            return action.frame != b"no"

        def wrote(self, action, now):
            seen.append(("wrote", action.frame))

        def waiting(self, action, now):
            seen.append("waiting")
            return action.until_s + 10.0

        def waited(self):
            seen.append("waited")

        def done(self, action, now):
            seen.append("done")

    host = Recording()
    engine, link = ScriptedEngine(Write(b"no"), Write(b"yes"), Wait(1.0), Done()), FakeLink()
    drive(engine, link, host)
    assert link.calls == [("write", b"yes"), ("wait", 11.0, host.news)]
    assert seen == ["turn", ("writing", b"no"), "turn", ("writing", b"yes"), ("wrote", b"yes"), "turn", "waiting",
                    "waited", "turn", "done"]


def test_a_lost_port_ends_the_drive_at_the_next_turn():
    engine, link = ScriptedEngine(Write(b"a"), Write(b"b")), FakeLink()

    class Losing(Host):
        def wrote(self, action, now):
            link.error = PortError("the port went away")

    with pytest.raises(PortError):
        drive(engine, link, Losing())
    assert link.calls == [("write", b"a")]


@pytest.mark.parametrize("url", ["sim://?clock=virtual", "sim://?speed=50"])
def test_the_job_takes_status_frames_only_through_receive_statuses(monkeypatch, url):
    """``Job.receive_status`` is never called by the host: a run ends as it does with it."""
    from armctl.host.api import Arm

    def refused(self, frame, now):
        raise AssertionError("the host handed a frame to Job.receive_status")

    taken = []
    receive_statuses = Job.receive_statuses

    def counting(self, frames, times):
        taken.append(len(frames))
        return receive_statuses(self, frames, times)

    monkeypatch.setattr(Job, "receive_status", refused)
    monkeypatch.setattr(Job, "receive_statuses", counting)
    with Arm.open(port=url) as arm:
        result = arm.run("G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\nG1 Y-40 F3000\n")
    assert result.finished and sum(taken) > 10


def test_the_wall_clocks_queued_frames_reach_the_engine_through_receive_statuses(monkeypatch):
    from armctl.host.runner import JobRunner
    from test_job import make_job

    class WallLink:
        clock = staticmethod(lambda: 0.0)
        error = None

    given = []
    monkeypatch.setattr(Job, "receive_status", lambda self, frame, now: pytest.fail("receive_status"))
    monkeypatch.setattr(Job, "receive_statuses", lambda self, frames, times: given.append((frames, times)))
    job = make_job()
    runner = JobRunner(WallLink(), job.streamer, [], job.view)
    frame = PauseStatus(0, 1500)
    runner.on_status(frame, 1.0)
    runner.on_status(frame, 1.27)
    runner.turn()
    assert given == [((frame,), (1.0,)), ((frame,), (1.27,))]
