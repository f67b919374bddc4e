"""Issue 25's load row: 50 WebSocket viewers on one arm while a job streams through
``armctl serve`` on ``sim://`` at 9600 baud — frames dropped, the job's arm time against the
same job with no viewer (measured in the same run), and a viewer too slow to read.

  baseline   ``armctl serve --arm a=sim://?speed=S`` (a subprocess, as users run it), the job
             POSTed, its record polled until it has an outcome: the arm time, frames sent.
  viewers    the same server, the same job, with 50 WebSocket viewers reading every event, and
             one more viewer that never reads (its socket's receive buffer 4 kB): the arm time
             again, every reading viewer's events (each must get the summary), and the server's
             own count of events it queued and dropped (``GET /api/server``).
  slow       in this process: the server's event hub (armctl/server/hub.py) and aiohttp on
             loopback, one viewer that never reads, 40,000 events of 1 kB published at it —
             the largest queue it held and the Python memory the server grew by
             (tracemalloc), against the 40 MB published.

The job is ``--moves`` moves of 10 mm at F3000 (a frame every 0.2 s of arm time, 4 times a
frame's 50 ms on the wire: the lead, not the line, paces it; 200 moves: about a minute of arm
time).  ``finished`` means the arm's reports
proved every frame executed: no frame dropped.  Pairs alternate (baseline, viewers, baseline,
…) and the ratio is of their medians; wall-clock load from other processes moves both alike.

    .venv/bin/python benchmarks/server_load.py              # 1 pair, speed 4
    .venv/bin/python benchmarks/server_load.py --pairs 3 --speed 2
"""
from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import aiohttp  # noqa: E402
from serve_process import flood_a_slow_viewer, never_reading_viewer, served  # noqa: E402

VIEWERS = 50
TARGET_RATIO = 0.01  # the arm time with viewers within 1 % of the time without


def job(moves: int) -> str:
    lines = ["G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000"]
    lines += [f"G1 X{250 + (i % 2) * 10} Y{(i // 2) % 5 * 10} F3000" for i in range(moves)]
    return "\n".join(lines) + "\n"


START = {"x": 250, "y": 0, "z": 150, "a": 180, "b": 0, "c": 0, "s": 1000, "f": 3000}  # the job's first pose


def run_job(server, script: str) -> dict:
    """The job from its first pose (a move there first: every run's first move is the same)."""
    status, moved = server.request("POST", "/api/arms/a/move", START, timeout=120)
    assert status == 200 and moved["outcome"] == "finished", moved
    status, created = server.request("POST", "/api/arms/a/jobs?name=load.txt", script)
    assert status == 201, created
    return server.wait_job("a", created["id"], timeout_s=3600)


async def with_viewers(server, script: str) -> tuple[dict, list[list[dict]], dict]:
    url = server.base.replace("http://", "ws://") + "/api/arms/a/events"
    async with aiohttp.ClientSession() as session:
        sockets = [await session.ws_connect(url) for _ in range(VIEWERS)]
        host, port = server.base.removeprefix("http://").split(":")
        slow = never_reading_viewer(host, int(port), "/api/arms/a/events")
        received: list[list[dict]] = [[] for _ in sockets]

        async def read(index: int, ws) -> None:
            async for message in ws:
                event = json.loads(message.data)
                received[index].append(event)
                if event["event"] == "summary":
                    return

        readers = [asyncio.ensure_future(read(i, ws)) for i, ws in enumerate(sockets)]
        result = await asyncio.to_thread(run_job, server, script)
        await asyncio.wait_for(asyncio.gather(*readers), 30)
        stats = (await asyncio.to_thread(server.request, "GET", "/api/server"))[1]["a"]
        for ws in sockets:
            await ws.close()
        slow.close()
    return result, received, stats


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=1)
    parser.add_argument("--speed", type=float, default=4.0, help="sim:// time scale (the wire is 9600 baud in model time)")
    parser.add_argument("--moves", type=int, default=200)
    options = parser.parse_args()
    script = job(options.moves)
    url = f"sim://?speed={options.speed:g}"
    base_times, view_times, ok = [], [], True
    with tempfile.TemporaryDirectory() as journal, served("--arm", f"a={url}", journal=Path(journal)) as server:
        for pair in range(options.pairs):
            started = time.monotonic()
            alone = run_job(server, script)
            wall_alone = time.monotonic() - started
            started = time.monotonic()
            watched, received, stats = asyncio.run(with_viewers(server, script))
            wall_watched = time.monotonic() - started
            for name, result, wall in (("no viewers", alone, wall_alone), (f"{VIEWERS} viewers", watched, wall_watched)):
                print(f"pair {pair + 1} {name:>10}: {result['outcome']}, {result['frames_sent']}/{result['total_frames']} "
                      f"frames, arm time {result['arm_time_s']:.3f} s (wall {wall:.1f} s)")
                ok &= result["outcome"] == "finished" and result["frames_sent"] == result["total_frames"]
            counts = [len(events) for events in received]
            summaries = sum(1 for events in received if events and events[-1]["event"] == "summary")
            lost = sum(1 for events in received for e in events if e["event"] == "dropped")
            print(f"  viewers: {summaries}/{VIEWERS} got the summary, {min(counts)}-{max(counts)} events each, "
                  f"'dropped' notices to reading viewers: {lost}; server: {stats['published']} events published, "
                  f"{stats['dropped']} dropped (for any viewer, the one that never reads included: its socket's "
                  f"buffers held what it was sent), {stats['queued']} queued at the end")
            ok &= summaries == VIEWERS and lost == 0
            base_times.append(alone["arm_time_s"])
            view_times.append(watched["arm_time_s"])
    base, viewed = statistics.median(base_times), statistics.median(view_times)
    ratio = viewed / base
    within = abs(ratio - 1) <= TARGET_RATIO
    print(f"arm time with {VIEWERS} viewers / without: {viewed:.3f} / {base:.3f} s = {ratio:.4f} "
          f"({'within' if within else 'NOT within'} 1 %)")
    slow = asyncio.run(flood_a_slow_viewer())
    print(f"slow viewer: {slow['published']} events ({slow['published_mb']:.0f} MB) published at a viewer that never "
          f"reads: largest queue {slow['largest_queue']} events, {slow['dropped']} dropped, the server's Python memory "
          f"peaked {slow['peak_growth_mb']:.2f} MB above the start")
    ok &= within and slow["largest_queue"] <= 256 and slow["peak_growth_mb"] < 5
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
