"""Issue 26 item 2: a move without ``f`` runs at the profile's default speed, and an error's
message leads with its first real diagnostic (a wrong word before the value it leaves missing).

The design rule is "never send a value the user did not write or a profile did not define":
``[speed] default_linear_mm_min`` / ``default_joint_deg_s`` are profile-defined, so ``Arm.move``
and ``armctl move`` may send them.  Scripts still write F (E004): a script is a file people share,
and its speed should not change with the profile it is checked against.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from armctl import Arm, ScriptError
from armctl.host.profile import default_profile, parse_profile
from armctl.core.protocol import JointMove, LinearMove

VIRTUAL = "sim://?clock=virtual"


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)


def test_profile_defines_default_speeds():
    speed = default_profile().speed
    assert speed.default_linear_mm_min == 3000.0 and speed.default_joint_deg_s == 30.0
    from armctl.errors import ProfileError

    with pytest.raises(ProfileError, match="default_linear_mm_min"):
        parse_profile({"speed": {"default_linear_mm_min": 0}}, "p.toml")


@pytest.mark.timeout(30)
def test_move_without_f_uses_the_profiles_default_speed():
    with Arm.open(VIRTUAL) as arm:
        linear = arm.move(z=200)
        joint = arm.move(j1=20)
        assert linear.finished and joint.finished
        assert arm.status().position_mm[2] == pytest.approx(200, abs=0.2)


@pytest.mark.timeout(30)
def test_move_sends_the_profile_speed():
    with Arm.open(VIRTUAL) as arm:
        arm.move(z=200)
        arm.move(j1=20, h=0)
        received = [frame.command for frame in arm._link.port.model.frames_received]
    assert [type(command) for command in received] == [LinearMove, JointMove]
    assert (received[0].speed_mm_min, received[1].speed_deg_s) == (3000.0, 30.0)


def test_error_message_leads_with_the_wrong_word_not_the_missing_one():
    with Arm.open(VIRTUAL) as arm:
        with pytest.raises(ScriptError) as caught:
            arm.move(s=3000)
        assert str(caught.value).startswith("<move>:1:4: E005 S = 3000 is outside 500…2500")
        # a script without F: both errors are there, the wrong word leads
        with pytest.raises(ScriptError) as caught:
            arm.run("G1 X200 Y0 Z200 A180 B0 C0 S3000\n")
        message = str(caught.value)
        assert "E005 S = 3000 is outside 500…2500" in message.split(" (and ")[0], message
        assert {d.code for d in caught.value.diagnostics} >= {"E004", "E005"}
        assert "more error" in message


def test_scripts_still_need_f():
    from armctl.script import compile_text

    compilation = compile_text("G1 X200 Y0 Z200 A180 B0 C0 S1500\n", "t.txt")
    list(compilation)
    assert [d.code for d in compilation.diagnostics if d.is_error] == ["E004"]


@pytest.mark.timeout(60)
def test_fresh_process_api_move_without_f(tmp_path):
    program = (
        "from armctl import Arm, ScriptError\n"
        "with Arm.open('sim://?clock=virtual') as arm:\n"
        "    print(arm.move(z=180).outcome)\n"
        "    try:\n"
        "        arm.move(s=3000)\n"
        "    except ScriptError as error:\n"
        "        print(error)\n"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=50)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["finished", "<move>:1:4: E005 S = 3000 is outside 500…2500"]
