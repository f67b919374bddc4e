"""Issue 22: a signal in the first instant of ``armctl run`` — before the job's own handlers —
printed a KeyboardInterrupt traceback (SIGINT) or ended the process silently (SIGTERM -15,
SIGHUP -1).  Now the program takes the three signals at its first line: exit 130, no traceback.

The signal must land at a known point, on any machine however loaded, so the child sends it to
itself: a ``sitecustomize`` module (on PYTHONPATH, imported by Python's start-up before any of
armctl's code) puts a finder on ``sys.meta_path`` that calls ``os.kill(getpid(), SIGNAL)`` the
moment a chosen module is first imported — ``click`` (armctl.ui.cli's imports, before any command),
``armctl.ui.run_job`` (inside ``run``, before the port opens) or ``serial`` (the port opening).
The test runner's own signal handling plays no part: the signal is the child's, to itself.
Through the installed command and ``python -m armctl``, each in a fresh process.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
INSTALLED = Path(sys.executable).with_name("armctl")
TIMEOUT_S = 60

SITECUSTOMIZE = '''
import os, signal, sys

class _Trip:
    """Sends ARMCTL_TEST_SIGNAL to this process when ARMCTL_TEST_TRIP is first imported."""

    def find_spec(self, name, path=None, target=None):
        if name == os.environ["ARMCTL_TEST_TRIP"]:
            sys.meta_path.remove(self)
            os.kill(os.getpid(), getattr(signal, os.environ["ARMCTL_TEST_SIGNAL"]))
        return None

if os.environ.get("ARMCTL_TEST_TRIP"):
    sys.meta_path.insert(0, _Trip())
'''

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")


def run_tripped(tmp_path, command, trip: str, signal_name: str):
    (tmp_path / "sitecustomize.py").write_text(SITECUSTOMIZE)
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env.update(PYTHONPATH=str(tmp_path), ARMCTL_TEST_TRIP=trip, ARMCTL_TEST_SIGNAL=signal_name)
    done = subprocess.run([*command, "run", "scripts/pick_and_place.txt", "--no-live", "--port", "sim://?speed=20"],
                          capture_output=True, text=True, timeout=TIMEOUT_S, cwd=ROOT, env=env,
                          preexec_fn=lambda: [signal.signal(s, signal.SIG_DFL) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)])
    return done.returncode, done.stdout, done.stderr


COMMANDS = {"installed": [str(INSTALLED)], "python -m": [sys.executable, "-m", "armctl"]}


@pytest.mark.parametrize("signal_name", ["SIGINT", "SIGTERM", "SIGHUP"])
@pytest.mark.parametrize("trip", ["click", "armctl.ui.run_job", "serial"])
@pytest.mark.parametrize("how", COMMANDS, ids=COMMANDS.keys())
def test_a_signal_before_the_job_is_exit_130_without_a_traceback(tmp_path, how, trip, signal_name):
    code, out, err = run_tripped(tmp_path, COMMANDS[how], trip, signal_name)
    assert code == 130, (code, err)
    assert "Traceback" not in err, err
    assert "finished" not in out + err  # it stopped: nothing was sent (the sim:// job takes seconds)


def test_the_trip_really_fires(tmp_path):
    """The finder is what it seems: without armctl's handlers the same trip kills the child."""
    (tmp_path / "sitecustomize.py").write_text(SITECUSTOMIZE)
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "ARMCTL_TEST_TRIP": "json", "ARMCTL_TEST_SIGNAL": "SIGTERM"}
    done = subprocess.run([sys.executable, "-c", "import json; print('alive')"], capture_output=True, text=True,
                          timeout=TIMEOUT_S, env=env, preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))
    assert done.returncode == -signal.SIGTERM and "alive" not in done.stdout


def test_importing_the_cli_installs_no_handler():
    """The library (a test, a user's script importing armctl.ui.cli) keeps its own handlers."""
    code = ("import signal; before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}; "
            "import armctl.ui.cli, armctl; armctl.Arm; "
            "assert before == {s: signal.getsignal(s) for s in before}, 'changed'")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr


# A signal while `arm.run` checks the script (run's own handlers are in place, the job is not yet
# registered): SIGTERM and SIGHUP called arm.stop(), which the API did not count before the job
# existed — the job then ran to its end and exited 0.  The child sends the signal from inside
# armctl.host.api.Arm._checked (run's check of the script it is handed), patched in when armctl.host.api loads.
CHECK_TRIP = '''
import importlib.abc, importlib.util, os, signal, sys

class _PatchCheck(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name != "armctl.host.api":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        load = spec.loader.exec_module

        def exec_module(module):
            load(module)
            real = module.Arm._checked
            calls = []

            def _checked(*args):
                calls.append(1)
                if len(calls) == 1:
                    os.kill(os.getpid(), getattr(signal, os.environ["ARMCTL_TEST_SIGNAL"]))
                return real(*args)

            module.Arm._checked = _checked

        spec.loader.exec_module = exec_module
        return spec

sys.meta_path.insert(0, _PatchCheck())
'''


@pytest.mark.parametrize("signal_name", ["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_signal_while_run_checks_the_script_is_not_lost(tmp_path, signal_name):
    (tmp_path / "sitecustomize.py").write_text(CHECK_TRIP)
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env.update(PYTHONPATH=str(tmp_path), ARMCTL_TEST_SIGNAL=signal_name)
    done = subprocess.run([str(INSTALLED), "run", "scripts/pick_and_place.txt", "--no-live", "--port", "sim://?clock=virtual"],
                          capture_output=True, text=True, timeout=TIMEOUT_S, cwd=ROOT, env=env,
                          preexec_fn=lambda: [signal.signal(s, signal.SIG_DFL) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)])
    assert done.returncode == 130, (done.returncode, done.stdout[-500:], done.stderr)
    assert "Traceback" not in done.stderr and "finished" not in done.stdout
