"""The jog session against the pure simulated arm, in virtual time (armctl/jog/session.py).

``Rig`` is the edge loop without a terminal or a clock: it advances the ``SimulatedArm`` in
5 ms steps, feeds the status bytes that reached the host to a ``StatusReader`` and an
``ArmState`` (as the link's reader thread does), ticks the session and writes the frames it
returns into the simulated line.  So steps, gripper, pause, teach and the dead-man rules are
checked against the arm model itself, deterministically.
"""

from __future__ import annotations

from datetime import datetime, timezone

import pytest

from armctl.core.armstate import ArmState
from armctl.jog.deadman import neutral
from armctl.jog.keymap import JOG_ACTIONS, default_keymap
from armctl.jog.moves import Refused, Reported, step_move
from armctl.jog.session import EXIT_INTERRUPTED, EXIT_OK, JogSession, Record, Send
from armctl.jog.settings import JogSettings
from armctl.jog.teach import taught_line
from armctl.core.protocol import JointMove, Joystick, LinearMove, PauseToggle, StatusReader, frame_seconds
from armctl.script import compile_text
from armctl.sim import SimOptions, SimulatedArm

WHEN = datetime(2024, 5, 1, 12, 0, 0, tzinfo=timezone.utc)
REPEAT_S = 0.033


class Rig:
    def __init__(self, mode: str = "joint", recording: bool = True, settings: JogSettings = JogSettings()):
        self.sim = SimulatedArm(SimOptions())
        self.profile = self.sim.profile
        self.reader = StatusReader()
        self.state = ArmState()
        self.session = JogSession(settings, default_keymap(), self.profile, mode, line_s=frame_seconds(),
                                  recording=recording)
        self.now = 0.0
        self.sent: list[tuple[float, object]] = []
        self.records: list[Record] = []
        self.advance(0.4)  # a full status rotation

    def _apply(self, effects) -> None:
        for effect in effects:
            if isinstance(effect, Send):
                self.sim.write(effect.command.encode(), self.now)
                self.sent.append((round(self.now, 6), effect.command))
            elif isinstance(effect, Record):
                self.records.append(effect)

    def advance(self, seconds: float, step: float = 0.005) -> None:
        end = self.now + seconds
        while self.now < end - 1e-9:
            self.now = min(end, self.now + step)
            for frame in self.reader.feed(self.sim.advance(self.now)):
                self.state.update(frame, self.now)
            self._apply(self.session.tick(self.now, self.state))

    def key(self, name: str) -> list:
        before = len(self.sent)
        self._apply(self.session.key(name, self.now, self.state))
        return [c for _, c in self.sent[before:]]

    def hold(self, name: str, seconds: float, delay: float = 0.4) -> float:
        """Hold a key: press, auto-repeat after ``delay`` every 33 ms; returns the last repeat's time."""
        self.key(name)
        self.advance(delay)
        end = self.now + seconds
        last = self.now
        while self.now < end:
            self.key(name)
            last = self.now
            self.advance(REPEAT_S)
        return last

    def commands(self, kind) -> list:
        return [c for _, c in self.sent if isinstance(c, kind)]

    @property
    def joints(self):
        return self.sim.pose.joints


def test_holding_q_turns_joint_1_and_release_stops_it_within_150ms():
    rig = Rig()
    last_repeat = rig.hold("q", 1.0)
    rig.advance(0.5)
    assert [c for _, c in rig.sent] == [Joystick(0, (152,)), neutral(0)]
    assert rig.sent[1][0] - last_repeat <= 0.150
    turned = rig.joints[0]
    assert turned > 10.0
    rig.advance(1.0)
    assert rig.joints[0] == pytest.approx(turned)  # it stays where it stopped


def test_a_tap_moves_no_longer_than_the_initial_delay():
    rig = Rig()
    rig.key("e")
    rig.advance(1.0)
    (t_on, on), (t_off, off) = rig.sent
    assert on == Joystick(2, (152,)) and off == neutral(2)
    assert t_off - t_on <= 0.5


@pytest.mark.parametrize("key", ["space", "m", "tab", "p", "+", "o", "enter", "z", "x", "esc", "ctrl-c"])
def test_any_other_key_sends_the_neutral_at_once(key):
    rig = Rig()
    rig.hold("w", 0.3)
    sent = rig.key(key)
    assert sent[0] == neutral(1)
    assert rig.sent[-len(sent)][0] == rig.now  # in the same instant


def test_quit_and_ctrl_c_end_the_session_with_their_exit_codes():
    for key, code in (("x", EXIT_OK), ("esc", EXIT_OK), ("ctrl-c", EXIT_INTERRUPTED)):
        rig = Rig()
        rig.key(key)
        assert rig.session.done and rig.session.exit_code == code
        assert rig.key("q") == []


def test_finish_on_an_error_stops_a_moving_axis():
    rig = Rig(mode="linear")
    rig.hold("up", 0.2)
    sent = rig.session.finish(rig.now, "the port went away", 1)
    assert sent == [Send(Joystick(100, (128, 128, 128)))]


def test_joint_step_moves_by_the_increment_of_the_speed_level():
    rig = Rig()
    rig.key("tab")
    rig.key("q")
    rig.advance(1.5)
    assert rig.state.joints_deg[0] == pytest.approx(1.0)
    rig.key("+")
    rig.key("+")
    rig.key("a")
    rig.advance(2.5)
    assert rig.state.joints_deg[0] == pytest.approx(-9.0)
    assert [c.j1_deg for c in rig.commands(JointMove)] == [1.0, -9.0]
    assert not rig.commands(Joystick)


def test_linear_step_moves_x_y_z_by_the_increment_keeping_the_attitude():
    rig = Rig(mode="linear")
    start = (rig.state.x_mm, rig.state.y_mm, rig.state.z_mm)
    rig.key("tab")
    for key in ("up", "left", "pageup"):
        rig.key(key)
        rig.advance(1.2)
    assert (rig.state.x_mm, rig.state.y_mm, rig.state.z_mm) == pytest.approx((start[0] + 1, start[1] + 1, start[2] + 1))
    moves = rig.commands(LinearMove)
    assert len(moves) == 3
    for move in moves:  # the attitude the joints report, at their 0.01 deg resolution
        first = moves[0]
        assert (move.b0_deg, move.b1_deg, move.w_deg) == pytest.approx((first.b0_deg, first.b1_deg, first.w_deg), abs=0.05)


def test_never_more_than_one_step_queued_ahead():
    rig = Rig()
    rig.key("tab")
    for _ in range(6):  # six quick presses: one step runs, one waits, the rest replace it
        rig.key("q")
        rig.advance(0.01)
    rig.advance(2.0)
    assert len(rig.commands(JointMove)) == 2
    assert rig.sim.peak_fifo_occupancy == 1
    assert rig.state.joints_deg[0] == pytest.approx(2.0)


def test_a_jog_key_while_a_step_runs_is_ignored():
    rig = Rig()
    rig.key("tab")
    rig.key("q")
    rig.key("tab")
    assert rig.key("q") == []
    assert "waiting" in rig.session.message


def test_gripper_open_and_close_use_the_profile_and_do_not_move_the_arm():
    rig = Rig()
    joints, xyz = rig.joints, rig.sim.pose.xyz
    rig.key("o")
    rig.advance(1.0)
    assert rig.state.pwm_us == rig.profile.pwm.gripper_open_us
    rig.key("c")
    rig.advance(1.0)
    assert rig.state.pwm_us == rig.profile.pwm.gripper_close_us
    assert rig.joints == pytest.approx(joints, abs=0.01)
    assert rig.sim.pose.xyz == pytest.approx(xyz, abs=0.05)
    assert [m.pwm_us for m in rig.commands(JointMove)] == [1000.0, 2000.0]


def test_pause_sends_the_toggle_and_nothing_else_until_resumed():
    rig = Rig()
    assert rig.key("p") == [PauseToggle()]
    rig.advance(0.6)
    assert rig.state.paused is True
    assert rig.key("q") == [] and "paused" in rig.session.message
    rig.key("tab")
    assert rig.key("q") == []
    rig.advance(0.5)
    assert rig.key("p") == [PauseToggle()]
    rig.advance(0.6)
    assert rig.state.paused is False
    rig.key("tab")
    assert rig.key("q") == [Joystick(0, (152,))]


def test_enter_while_moving_stops_then_records_the_pose_where_the_arm_stopped():
    rig = Rig()
    rig.hold("q", 0.5)
    rig.key("enter")
    assert rig.records == []  # not yet: the status still shows the arm moving
    rig.advance(0.6)
    assert len(rig.records) == 1
    record = rig.records[0]
    assert record.mode == "joint"
    assert record.pose.joints_deg == pytest.approx(rig.joints, abs=0.006)


def test_record_without_a_file_says_so():
    rig = Rig(recording=False)
    rig.key("enter")
    rig.advance(0.5)
    assert rig.records == [] and "--record" in rig.session.message


def test_taught_lines_compile_clean_and_replay_to_the_taught_poses():
    rig = Rig()
    rig.hold("q", 0.3)
    rig.hold("s", 0.3)
    rig.advance(0.3)
    rig.key("enter")
    rig.advance(0.6)
    joint_pose = rig.joints
    rig.key("m")
    rig.hold("pageup", 0.3)
    rig.advance(0.3)
    rig.key("enter")
    rig.advance(0.6)
    linear_pose = rig.sim.pose
    text = "".join(taught_line(r.mode, r.pose, r.speed, WHEN) for r in rig.records)
    assert text.splitlines()[0].startswith("G6 J1=") and text.splitlines()[1].startswith("G1 X")
    compilation = compile_text(text, "taught.txt")
    statements = list(compilation)
    assert compilation.finish() == []
    # Replay on a fresh arm: it reaches each taught pose.
    arm = SimulatedArm(SimOptions())
    arm.write(statements[0].command.encode(), 0.0)
    arm.advance_until_idle()
    assert arm.pose.joints == pytest.approx(joint_pose, abs=0.01)
    arm.write(statements[1].command.encode(), arm.now_s)
    arm.advance_until_idle()
    assert arm.pose.xyz == pytest.approx(linear_pose.xyz, abs=0.1)


def test_mode_and_speed_level_changes_show_on_the_view():
    rig = Rig()
    rig.key("m")
    rig.key("+")
    rig.key("tab")
    view = rig.session.view("sim://")
    assert (view.mode, view.level, view.stepping, view.step_size) == ("linear", 2, True, "5 mm")
    rig.key("-")
    rig.key("-")
    assert rig.session.view().level == 1


def _reported(joints=(0.0, 0.0, 0.0, 0.0, 90.0, 0.0), xyz=(210.0, 0.0, 300.0)):
    return Reported(xyz, (180.0, 0.0, 0.0), joints, 1500.0, (0.0, 0.0, 0.0))


def test_a_joint_step_stops_at_the_limit_and_is_refused_beyond_it():
    profile = SimulatedArm(SimOptions()).profile
    high = profile.joint_limits_deg[0][1]
    command, _ = step_move(JOG_ACTIONS["j1_plus"], 10.0, _reported(joints=(high - 3, 0, 0, 0, 90, 0)), 10.0, profile)
    assert command.j1_deg == high
    with pytest.raises(Refused, match="limit"):
        step_move(JOG_ACTIONS["j1_plus"], 1.0, _reported(joints=(high, 0, 0, 0, 90, 0)), 10.0, profile)


def test_a_linear_step_out_of_the_workspace_is_refused():
    profile = SimulatedArm(SimOptions()).profile
    top = profile.workspace.z_mm[1]
    with pytest.raises(Refused, match="Z"):
        step_move(JOG_ACTIONS["z_plus"], 10.0, _reported(xyz=(100.0, 0.0, top - 5)), 600.0, profile)
