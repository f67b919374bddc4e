"""Review of trust at the edges (crashes, resumes, hostile inputs, arm variants): each fault found,
through the installed command in a fresh process and the API.

1. A network port URL urllib cannot read (``socket://127.0.0.1:99999``, ``socket://host:abc``,
   ``socket://[::1``) gave a ValueError traceback (exit 1) on ``status``, ``config``, ``run``,
   ``move`` and ``probe``: now one line naming the URL, exit 2, nothing opened.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest


ROOT = Path(__file__).resolve().parent.parent
PICK = ROOT / "scripts" / "pick_and_place.txt"


def _armctl(*args: str, cwd: Path, timeout: float = 30.0) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([sys.executable, "-m", "armctl", *args], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd, env=env, stdin=subprocess.DEVNULL)


# --- 1. a network port URL urllib cannot read --------------------------------------------------

@pytest.mark.timeout(60)
@pytest.mark.parametrize("url, why", [
    ("socket://127.0.0.1:99999", "Port out of range"),
    ("socket://host:abc", "Port could not be cast"),
    ("rfc2217://127.0.0.1:-1", "Port could not be cast"),
    ("socket://[::1", "Invalid IPv6 URL"),
])
@pytest.mark.parametrize("command", [["status", "--once"], ["config"], ["move", "z=200"],
                                     ["run", str(PICK), "--no-live"], ["run", str(PICK), "--dry-run"]])
def test_bad_network_port_url_is_a_usage_error(tmp_path, url, why, command):
    done = _armctl(*command, "--port", url, cwd=tmp_path)
    assert "Traceback" not in done.stderr, done.stderr
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert url in done.stderr and why in done.stderr, done.stderr
