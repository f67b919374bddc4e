"""A virtual-clock ``Link.wait(…, news)`` drives the simulator burst after burst past the frames
``news`` says are no news, and returns at the first that is (or at its time limit); without
``news`` every frame ends the wait, whatever ``on_status`` answers."""

from __future__ import annotations

from armctl.host.link import Link
from armctl.core.protocol import STATUS_PERIOD_S, STATUS_SIZE
from armctl.host.virtual_wait import VIRTUAL_BUILD_FRAMES

URL = "sim://?clock=virtual"


def news_of(on_status):
    """A wait's ``news`` from a per-frame answer (True: news): the place of the first, or None."""

    def news(frames, times):
        for k, frame in enumerate(frames):
            if on_status(frame, times[k]):
                return k
        return None

    return news


def _open(news_kinds):
    seen = []

    def on_status(frame, now):
        seen.append((frame.KIND, now))
        return frame.KIND in news_kinds

    return Link.open(URL, on_status=on_status), seen, news_of(on_status)


def test_a_news_only_wait_reads_on_to_the_first_frame_that_is_news():
    link, seen, news = _open({4})
    with link:
        link.wait(None, news)
        assert [kind for kind, _ in seen] == [0, 1, 2, 3, 4]  # the rotation up to the first kind 4
        assert link.clock.now() == seen[-1][1]  # it stopped where that frame was read
        link.wait(None, news)
        assert [kind for kind, _ in seen[5:]] == [5, 100, 102, 103, 0, 1, 2, 3, 4]


def test_a_news_only_wait_still_ends_at_its_time():
    link, seen, news = _open(set())
    with link:
        link.wait(link.clock.now() + 10 * STATUS_PERIOD_S, news)
        assert 9 <= len(seen) <= 11 and link.clock.now() == 10 * STATUS_PERIOD_S


def test_without_news_every_frame_ends_the_wait():
    link, seen, _ = _open(set())
    with link:
        link.wait(None)
        assert len(seen) == 1


def _news_every(count):
    """A link whose ``on_status`` answers news for every ``count``-th frame, and what it read."""
    seen = []

    def on_status(frame, now):
        seen.append((now, frame.encode()))
        return len(seen) % count == 0

    return Link.open(URL), seen, news_of(on_status)


def test_the_steps_of_a_run_past_the_news_are_read_by_the_next_wait_as_a_new_run_would_time_them(monkeypatch):
    """The link keeps a status run's steps past the frame that was news, and the frames built for
    them, for the next wait (``VirtualWaits.tail``): the same frames at the same times as timing
    each wait's run afresh, with fewer runs timed and no frame built twice; a wait's own end
    cuts them, and a write forgets them."""
    from armctl.core.protocol import PauseToggle

    def read(keep_tails: bool):
        link, seen, news = _news_every(7)
        runs = []
        status_run = link.port.virtual_status_run

        def timed(*args):
            runs.append(args)
            return status_run(*args)

        link.port.virtual_status_run = timed
        status_frames, built = link.port.status_frames, []

        def building(steps):
            built.extend(steps)
            return status_frames(steps)

        link.port.status_frames = building
        advance_to, by_bursts = link.port.advance_to, []

        def bursting(*args):  # every burst is read by advance_to (the runs are not)
            data = advance_to(*args)
            by_bursts.append(len(data) // STATUS_SIZE)
            return data

        link.port.advance_to = bursting
        if not keep_tails:
            waits = link._virtual
            take_run = waits._take_run

            def forgetting(run, built, news, *read_before):
                result = take_run(run, built, news, *read_before)
                waits.tail = None
                return result

            waits._take_run = forgetting
        with link:
            for k in range(60):
                if k == 30:
                    link.write(PauseToggle().encode())
                    link.write(PauseToggle().encode())
                until_s = link.clock.now() + 0.2 if k % 3 == 0 else None  # some waits end by their time
                link.wait(until_s, news)
            return seen, len(runs), link.clock.now(), len(built) + sum(by_bursts)

    kept, kept_runs, kept_end_s, kept_built = read(True)
    fresh, fresh_runs, fresh_end_s, _ = read(False)
    assert len(kept) > 250
    assert kept == fresh and kept_end_s == fresh_end_s
    assert kept_runs < fresh_runs  # the tails were read, not timed again
    # nor built again (the frames read burst by burst, where the simulator did more than send
    # status frames, counted with the built): a frame built and not read is one of a batch
    # forgotten by a write, by a wait that ended at its time (20 of them) or by the end
    assert len(kept) <= kept_built <= len(kept) + (1 + 20 + 1) * VIRTUAL_BUILD_FRAMES



def test_a_burst_is_decoded_as_the_reader_feeds_it_clean_or_damaged(monkeypatch):
    """A burst of one whole frame is decoded as a run's frames are (``StatusReader._one_frame``);
    the frames, their times and the reader's counts are those the reader's scan gives, on a clean
    line and on one with noise and damaged frames (fed)."""

    def read(url: str, by_feed: bool):
        seen = []
        news = news_of(lambda frame, now: seen.append((frame, now)) or frame.KIND == 4)
        link = Link.open(url)
        if by_feed:
            monkeypatch.setattr(link.reader, "_one_frame", lambda data: [])  # every burst to the scan
        with link:
            for k in range(200):
                until_s = link.clock.now() + 0.05 if k % 2 else None  # timed waits read bursts
                link.wait(until_s, news)
            reader = link.reader
            return seen, reader.frames, reader.skipped_bytes, link.bytes_received, link.clock.now()

    for url in (URL, URL + "&noise=0.2&corrupt=0.1&seed=3"):
        ours, fed = read(url, False), read(url, True)
        assert len(ours[0]) > 300 and ours == fed
