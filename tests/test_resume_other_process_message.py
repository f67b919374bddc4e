"""A resume of a job on another process's simulated arm is refused without claiming that process
ended.  The serve review found ``armctl serve`` telling a second server, live beside the first on
one journal directory, that the first "has ended": armctl cannot know (a process id is reused),
and the refusal's reason is only that a simulated arm lives and dies with its process."""

from __future__ import annotations

import os
from types import SimpleNamespace

import pytest

from armctl.errors import ResumeRefused
from armctl.host.resume_port import refuse_gone_simulator

pytestmark = pytest.mark.timeout(30)


def test_the_refusal_does_not_say_the_other_process_ended():
    alive = SimpleNamespace(sim_process=f"{os.getpid()}-another0process", log_path="job.log", port="sim://")
    with pytest.raises(ResumeRefused) as refused:
        refuse_gone_simulator(alive)
    message = str(refused.value)
    assert "another armctl process" in message and "nothing was sent" in message, message
    assert "ended" not in message, message
