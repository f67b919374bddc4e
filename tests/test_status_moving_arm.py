"""``armctl status`` on a moving arm shows it moving.

This session's agreed view (armctl/core/agreed_view.py) showed a kind only once two consecutive
reports of it agreed: on a noisy line a lone corrupted report is never shown, but on a moving arm
the position and joints 1-3 never agree, so ``status --once`` printed them as null and every
``--watch`` line showed them unknown for as long as the arm moved — the one thing a user watches
the arm for.  The moving kinds are judged as ``ArmState`` judges them (each report against the
one before, at the arm's top speed; a jump held back until the next report confirms it).
"""

from __future__ import annotations

import json

import pytest


@pytest.mark.timeout(60)
def test_once_on_a_moving_arm_shows_where_it_is(capsys):
    from armctl.core.protocol import JointMove
    from armctl.host.link import connect
    from armctl.ui import status_watch

    link, baud = connect("sim://?clock=virtual", None)
    with link:
        link.write(JointMove(30, 0, 0, 0, 90, 0, pwm_us=1500, speed_deg_s=5).encode())
        status_watch.print_once(link, baud, 2.0, True)
        truth = link.port.model.snapshot().joints_deg
    out, err = capsys.readouterr()
    record = json.loads(out)
    assert None not in record["joints"] and record["x"] is not None, record
    assert 0.0 < record["joints"][0] < 30.0  # on its way, not at either end
    # the report before the latest, read up to a rotation before now: at most two rotations (and a
    # bit) behind the arm at 5 °/s
    assert abs(record["joints"][0] - truth[0]) <= 5 * 0.6
    assert "not known" not in err, err


@pytest.mark.timeout(60)
def test_watch_lines_follow_a_moving_arm_on_a_noisy_line():
    """The JSON lines of a watch while J1 turns 30° at 5 °/s, on ``noise=corrupt=0.05``: J1 shown
    on most lines, each value on the arm's way (0-30°), never a corrupted jump."""
    from armctl.core.protocol import JointMove
    from armctl.host.link import connect
    from armctl.ui import status_watch

    for seed in (2, 3, 5):
        link, baud = connect(f"sim://?clock=virtual&noise=0.05&corrupt=0.05&seed={seed}", None)
        with link:
            reports = status_watch._agreed_reports(link)
            status_watch.read_state(link, 5.0, reports)
            link.write(JointMove(30, 0, 0, 0, 90, 0, pwm_us=1500, speed_deg_s=5).encode())
            shown = []
            for _ in range(20):  # 20 rotations: 5.4 s of the 6 s move
                end_s = link.clock() + 0.27
                while link.clock() < end_s:  # (a virtual wait returns at each status burst)
                    link.wait(end_s)
                shown.append(reports.shown(link.snapshot()[0]).joints_deg[0])
        known = [j1 for j1 in shown if j1 is not None]
        assert len(known) >= 15, (seed, shown)
        assert all(-0.1 <= j1 <= 30.1 for j1 in known), (seed, shown)
        assert known[-1] > 20.0, (seed, shown)
