"""A sign of loss the streamer reads from positions: the arm seen back on a frame already known
finished (issue 9: "reported positions that skip or reverse the planned order").  Hand-fed
status frames on a verified profile: two reports in a row inside a finished frame's path, on no
pending path, are the sign; one report (a corrupted frame) is not."""

from __future__ import annotations

from armctl.core.motion import MotionModel
from armctl.host.profile import parse_profile
from armctl.core.protocol import LinearMove, PositionStatus
from armctl.core.streamer import Streamer

PATH = [(250.0, 0.0, 150.0), (250.0, 80.0, 150.0), (250.0, 80.0, 90.0), (190.0, 80.0, 90.0)]


def _streamer_past_two_moves():
    model = MotionModel(parse_profile({"connector": {"kinematics_verified": True}}))
    pose = model.initial_pose()
    streamer = Streamer(model, model.reported_pose(pose.xyz, pose.joints, 1500.0, (0.0, 0.0, 0.0)), lead_s=60.0)
    for k, (x, y, z) in enumerate(PATH):
        streamer.wrote(LinearMove(x, y, z, 180.0, 0.0, 0.0, 1500.0, 600.0), 0.05 * k)
    # the arm seen twice on the third move (line from PATH[1] to PATH[2]): the first two are finished
    for now in (40.0, 40.27):
        streamer.receive_status(PositionStatus(250.0, 80.0, 120.0), now)
    assert streamer.consumed_lower_bound == 2
    return streamer


def test_two_reports_back_on_a_finished_frame_are_a_sign_of_loss():
    streamer = _streamer_past_two_moves()
    for now in (40.54, 40.81):  # back inside the second move's path (PATH[0] → PATH[1])
        streamer.receive_status(PositionStatus(250.0, 40.0, 150.0), now)
    assert streamer.losses and "already finished" in streamer.losses[0]
    assert streamer.first_suspect_index == 2


def test_one_stray_report_is_not():
    streamer = _streamer_past_two_moves()
    streamer.receive_status(PositionStatus(250.0, 40.0, 150.0), 40.54)  # a corrupted frame, say
    streamer.receive_status(PositionStatus(250.0, 80.0, 110.0), 40.81)  # back on the third move
    streamer.receive_status(PositionStatus(250.0, 40.0, 150.0), 41.08)
    assert streamer.losses == []
