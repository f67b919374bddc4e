"""Issue 22: the Python API's arguments of the wrong type gave AttributeError from deep inside
(``Arm.open(port=5)``: 'int' object has no attribute 'strip'; ``run(log="path")``: 'str' object
has no attribute 'write', after the arm was read; ``observer=5``; a ``connect`` returning None),
and ``feed_override(inf)`` (or a number too large for a float) raised OverflowError inside the
job, which ended "failed".  Now each is a TypeError or ValueError at the call, naming the
argument, before a port opens or a frame is sent — in-process, and once in a fresh process.
"""

from __future__ import annotations

import io
import math
import subprocess
import sys
from pathlib import Path

import pytest

from armctl import Arm, JobObserver
ROOT = Path(__file__).resolve().parents[1]
VIRTUAL = "sim://?clock=virtual"
JOB = ROOT / "scripts" / "pick_and_place.txt"


def recording_connect(written: list, opened: list):
    from armctl.host.link import connect as real_connect

    def connect(port, baud, profile=None):
        link, baud = real_connect(port, baud, profile=profile)
        opened.append(link)
        write = link.write
        link.write = lambda frame: (written.append(bytes(frame)), write(frame))[1]
        return link, baud

    return connect


OPEN_CASES = {
    "port=5": (dict(port=5), TypeError, r"^port must be a path"),
    "port=bytes": (dict(port=b"sim://"), TypeError, r"^port must be a path"),
    "profile=5": (dict(port=VIRTUAL, profile=5), TypeError, r"^profile must be a path .* or Profile"),
    "connect=5": (dict(port=VIRTUAL, connect=5), TypeError, r"^connect must be a function"),
    "connect returns None": (dict(port=VIRTUAL, connect=lambda *a, **k: None), TypeError, r"^connect must return \(an"),
}


@pytest.mark.parametrize("kwargs, error, message", OPEN_CASES.values(), ids=OPEN_CASES.keys())
def test_arm_open_names_a_wrong_argument(kwargs, error, message):
    with pytest.raises(error, match=message):
        Arm.open(**kwargs)


def test_a_connect_returning_a_bare_link_is_refused_and_the_link_closed():
    from armctl.host.link import connect as real_connect

    links = []

    def bare(port, baud, profile=None):
        link, _baud = real_connect(port, baud, profile=profile)
        links.append(link)
        return link  # forgot the baud

    with pytest.raises(TypeError, match=r"^connect must return \(an armctl.host.link.Link, the baud rate\)"):
        Arm.open(VIRTUAL, connect=bare)
    assert links and not links[0].port.is_open


class _NoNote:
    def started(self, view, plan): pass
    def update(self, view): pass
    def warning(self, diagnostic): pass


RUN_CASES = {
    "log=path": (dict(log="job.log"), TypeError, r"^log must be an open text file .*not a path"),
    "log=Path": (dict(log=Path("job.log")), TypeError, r"^log must be an open text file .*not a path"),
    "log=binary": (dict(log=io.BytesIO()), TypeError, r"^log must be a text file"),
    "log=5": (dict(log=5), TypeError, r"^log must be an open text file"),
    "observer=5": (dict(observer=5), TypeError, r"^observer must be a JobObserver"),
    "observer without note": (dict(observer=_NoNote()), TypeError, r"^observer must be a JobObserver .* no note\(\)"),
    "on_progress=5": (dict(on_progress=5), TypeError, r"^on_progress must be a function"),
    "resume=open file": (dict(resume=io.StringIO("")), TypeError, r"^resume must be a path .* not an open file"),
    "resume=5": (dict(resume=5), TypeError, r"^resume must be a path"),
    "from_line='2'": (dict(from_line="2"), ValueError, r"^from_line='2' must be a whole number"),
    "script=5": (dict(script=5), TypeError, r"^script must be a path"),
}


@pytest.mark.parametrize("kwargs, error, message", RUN_CASES.values(), ids=RUN_CASES.keys())
def test_arm_run_names_a_wrong_argument_before_anything_is_sent(kwargs, error, message):
    written, opened = [], []
    kwargs = {"script": JOB, **kwargs}
    with Arm.open(VIRTUAL, connect=recording_connect(written, opened)) as arm:
        with pytest.raises(error, match=message):
            arm.run(kwargs.pop("script"), **kwargs)
        assert written == []
        assert arm.run(JOB, observer=JobObserver(), log=io.StringIO()).outcome == "finished"  # the arm is fine


@pytest.mark.parametrize("percent", [math.inf, -math.inf, math.nan, 10**60, 10**400, 1001, -1001], ids=repr)
def test_feed_override_out_of_range_is_a_value_error_and_the_job_goes_on(percent):
    seen = {}

    def on_progress(progress):
        if "error" not in seen:
            try:
                arm.feed_override(percent)
                seen["error"] = None
            except ValueError as error:  # caught here: the job must not be ended by it
                seen["error"] = error

    with Arm.open(VIRTUAL) as arm:
        result = arm.run(JOB, on_progress=on_progress)
    assert isinstance(seen["error"], ValueError) and "percent=" in str(seen["error"])
    assert result.outcome == "finished"


def test_in_range_overrides_still_clamp():
    answers = []
    with Arm.open(VIRTUAL) as arm:
        arm.run(JOB, on_progress=lambda p: answers.append(arm.feed_override(1000)) if not answers else None)
    assert answers == [200]


def test_a_fresh_process_gets_the_same_errors():
    code = ("from armctl import Arm\n"
            "for kwargs in ({'port': 5}, {'port': 'sim://?clock=virtual', 'connect': lambda *a, **k: None}):\n"
            "    try:\n        Arm.open(**kwargs)\n    except TypeError as error:\n        print(type(error).__name__, error)\n"
            "with Arm.open('sim://?clock=virtual') as arm:\n"
            "    try:\n        arm.run('scripts/pick_and_place.txt', log='x.log')\n"
            "    except TypeError as error:\n        print(type(error).__name__, error)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert [line.split(" ", 2)[:2] for line in lines] == [["TypeError", "port"], ["TypeError", "connect"], ["TypeError", "log"]]


def test_a_stop_while_run_checks_the_script_ends_the_job_with_nothing_sent(monkeypatch):
    """Issue 22's early window, in the API: ``stop()`` (another thread, armctl run's signal
    handler) while ``run`` reads and checks its script was not counted — the job then ran to its
    end.  It ends the job now, nothing sent, as a stop while the arm is read does."""
    import armctl.host.api as api

    written, opened = [], []
    real_check = api.Arm._checked
    with Arm.open(VIRTUAL, connect=recording_connect(written, opened)) as arm:
        calls = []

        def check_and_stop(*args):  # the first check is run()'s own, before the job is handed to the worker
            calls.append(1)
            if len(calls) == 1:
                arm.stop("stopped while checking")
            return real_check(*args)

        monkeypatch.setattr(api.Arm, "_checked", check_and_stop)
        result = arm.run(JOB)
        monkeypatch.setattr(api.Arm, "_checked", real_check)
        assert result.outcome == "interrupted" and result.frames_sent == 0
        assert not [frame for frame in written if frame[:1] == b"\xee"]  # no motion frame
        assert arm.run(JOB).outcome == "finished"  # the next job runs
