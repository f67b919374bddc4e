"""The arm's status after its port went away is an error, not the last report served as live.
Found by the serve review: after killing ``armctl sim --tcp`` under ``armctl serve``, ``GET
/status`` stayed 200 and status events kept coming every 0.25 s with the old position: once
every kind had been seen, ``Arm.status`` never looked at the link's error again.
"""

from __future__ import annotations

import threading

import pytest
import serial

import armctl
import armctl.host.link

pytestmark = pytest.mark.timeout(30)


class Unplugged:
    """A port that reads as the one it wraps until ``unplug`` is set, then fails as a pulled cable does."""

    def __init__(self, port) -> None:
        self.port, self.unplug = port, threading.Event()

    def read(self, size=1):
        if self.unplug.is_set():
            raise serial.SerialException("read failed: [Errno 5] Input/output error")
        return self.port.read(size)

    def __getattr__(self, name):
        return getattr(self.port, name)


@pytest.mark.realtime
def test_status_after_the_port_went_away_raises(monkeypatch):
    ports = []
    real_open = armctl.host.link.open_port

    def open_port(url, *args, **kwargs):
        ports.append(Unplugged(real_open(url, *args, **kwargs)))
        return ports[-1]

    monkeypatch.setattr(armctl.host.link, "open_port", open_port)
    with armctl.Arm.open("sim://?speed=20") as arm:
        assert arm.status(timeout=5).position_mm is not None
        ports[0].unplug.set()
        with pytest.raises(armctl.PortError, match="went away"):
            for _ in range(200):  # the reader thread meets the failure within a read or two
                arm.status_json(timeout=5)
                threading.Event().wait(0.01)
        with pytest.raises(armctl.PortError, match="went away"):
            arm.status(timeout=5)
