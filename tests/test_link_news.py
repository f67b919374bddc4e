"""A virtual-clock ``Link.wait(…, news_only=True)`` drives the simulator burst after burst past
the frames ``on_status`` says are no news, and returns at the first that is (or at its time
limit); without ``news_only`` every frame ends the wait, whatever ``on_status`` answers."""

from __future__ import annotations

from armctl.link import Link
from armctl.protocol import STATUS_PERIOD_S

URL = "sim://?clock=virtual"


def _open(news_kinds):
    seen = []

    def on_status(frame, now):
        seen.append((frame.KIND, now))
        return frame.KIND in news_kinds

    return Link.open(URL, on_status=on_status), seen


def test_a_news_only_wait_reads_on_to_the_first_frame_that_is_news():
    link, seen = _open({4})
    with link:
        link.wait(None, news_only=True)
        assert [kind for kind, _ in seen] == [0, 1, 2, 3, 4]  # the rotation up to the first kind 4
        assert link.clock.now() == seen[-1][1]  # it stopped where that frame was read
        link.wait(None, news_only=True)
        assert [kind for kind, _ in seen[5:]] == [5, 100, 102, 103, 0, 1, 2, 3, 4]


def test_a_news_only_wait_still_ends_at_its_time():
    link, seen = _open(set())
    with link:
        link.wait(link.clock.now() + 10 * STATUS_PERIOD_S, news_only=True)
        assert 9 <= len(seen) <= 11 and link.clock.now() == 10 * STATUS_PERIOD_S


def test_without_news_only_every_frame_ends_the_wait():
    link, seen = _open(set())
    with link:
        link.wait(None)
        assert len(seen) == 1
