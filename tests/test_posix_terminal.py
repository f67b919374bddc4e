"""Windows, simulated: where Python has no termios, ``jog`` and ``sim --pty`` say they need a
POSIX terminal (exit 2, no traceback, nothing opened), and the rest — ``sim --tcp`` included —
still loads and runs.  ``sys.modules["termios"] = None`` makes ``import termios`` fail exactly
as it does on Windows (ModuleNotFoundError, an ImportError).  pyserial is loaded first: on POSIX
its backend needs termios, on Windows it loads its own (serialwin32), so loaded is how it is
there."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.host.posix_terminal import NeedsPosixTerminal, require_posix_terminal

NO_TERMIOS = ("import sys, armctl, serial  # armctl first: it hooks the sim:// scheme into pyserial\n"
              "sys.modules['termios'] = None; sys.modules['tty'] = None\n")
CLI = NO_TERMIOS + "from armctl.ui.cli import main; main(prog_name='armctl')\n"


def without_termios(code: str, *args: str, tmp_path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, cwd=tmp_path,
                          stdin=subprocess.DEVNULL, timeout=60)


def test_on_posix_the_check_passes():
    require_posix_terminal("armctl jog", "anything")  # this machine has termios: no error


def test_without_termios_the_check_names_the_command_and_what_to_do(monkeypatch):
    monkeypatch.setitem(sys.modules, "termios", None)
    with pytest.raises(NeedsPosixTerminal) as raised:
        require_posix_terminal("armctl jog", "run it under WSL")
    assert str(raised.value).startswith("armctl jog needs a POSIX terminal")
    assert str(raised.value).endswith("has no termios module: run it under WSL")


def test_jog_without_termios_says_so_before_anything_else(tmp_path):
    # stdin is not a terminal either: the platform is the reason given, being the one that stays
    done = without_termios(CLI, "jog", tmp_path=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("armctl: armctl jog needs a POSIX terminal (Linux, macOS, or WSL on Windows)")
    assert "Traceback" not in done.stderr and done.stdout == ""


def test_jog_alone_as_a_module_without_termios(tmp_path):
    code = NO_TERMIOS + "import runpy; sys.argv[0] = 'armctl.jog'; runpy.run_module('armctl.jog', run_name='__main__')\n"
    done = without_termios(code, tmp_path=tmp_path)
    assert done.returncode == 2, done.stderr
    assert "armctl jog needs a POSIX terminal" in done.stderr and "Traceback" not in done.stderr


def test_sim_pty_without_termios_says_so_and_points_to_tcp(tmp_path):
    done = without_termios(CLI, "sim", "--pty", tmp_path=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("armctl: armctl sim --pty needs a POSIX terminal")
    assert "armctl sim --tcp PORT" in done.stderr and "Traceback" not in done.stderr
    assert done.stdout == ""  # no "simulated arm on …": nothing was opened


def test_in_process_both_are_usage_errors(monkeypatch):
    import serial  # noqa: F401  (loaded as on Windows, see above)

    monkeypatch.setitem(sys.modules, "termios", None)
    monkeypatch.setitem(sys.modules, "tty", None)
    for args in (["jog"], ["sim", "--pty"]):
        result = CliRunner().invoke(main, args)
        assert result.exit_code == 2, (args, result.output)
        assert "needs a POSIX terminal" in result.output


def test_the_tcp_bridge_loads_and_serves_without_termios(tmp_path):
    """``sim --tcp`` is the simulator for Windows: its module must not need termios."""
    code = NO_TERMIOS + (
        "import json, threading\n"
        "from armctl.sim.bridge import serve_tcp\n"
        "from armctl.sim.model import SimOptions\n"
        "stop = threading.Event(); stop.set()  # bind, announce, then end at once: no client needed\n"
        "urls = []\n"
        "ended = serve_tcp(0, SimOptions(), urls.append, stop=stop)\n"
        "print(json.dumps([ended, urls, 'termios' in sys.modules and sys.modules['termios'] is not None]))\n"
    )
    done = without_termios(code, tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    ended, urls, had_termios = json.loads(done.stdout)
    assert ended == "stopped" and had_termios is False
    assert len(urls) == 1 and urls[0].startswith("socket://127.0.0.1:")


def test_the_other_commands_run_without_termios(tmp_path):
    script = tmp_path / "job.txt"
    script.write_text("G4 P250\n")
    (tmp_path / "frames.hex").write_text("ee360000007a4300000000000000000000000000000000000000000000000000000000000000000000000000000000ef\n")
    for args in (["estimate", "job.txt"], ["lint", "job.txt"], ["compile", "job.txt"], ["decode", "frames.hex"],
                 ["completion", "bash"], ["ports"], ["status", "--once", "--port", "sim://?clock=virtual"],
                 ["run", "job.txt", "--port", "sim://?clock=virtual", "--no-live"]):
        done = without_termios(CLI, *args, tmp_path=tmp_path)
        assert done.returncode == 0, (args, done.stderr)
