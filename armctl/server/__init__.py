"""``armctl serve``: the arm on the network — an HTTP + WebSocket API and a web page.

Strategy: a thin edge over the asyncio API (armctl/aio.py), itself over ``armctl.Arm``: every
job the server runs takes ``armctl run``'s checks, pacing, journal and end-of-job proof.  The
web stack is aiohttp (the ``serve`` extra), imported only by ``armctl serve``:

- ``arms.py``: one ``ArmService`` an arm — its ``AsyncArm``, its jobs and their journals, the
  one controlling client, the status poller, the jog dead-man;
- ``hub.py``: the events fanned out to WebSocket viewers, a bounded queue each (a slow viewer
  loses events, the server never buffers without bound);
- ``auth.py``: the token, the Origin and Host checks;
- ``app.py``: the routes (docs/server.md documents each);
- ``run.py``: opening the arms and listening;
- ``page/index.html``: the page at ``/`` (no external file: works offline).
"""
from __future__ import annotations

EXTRA_MISSING = ("armctl serve needs the web server extra, not installed here: "
                 "pip install -e '.[serve]' (in armctl's checkout; installs aiohttp)")


def extra_installed() -> bool:
    """True when the ``serve`` extra (aiohttp) can be imported."""
    try:
        import aiohttp  # noqa: F401
    except ImportError:
        return False
    return True
