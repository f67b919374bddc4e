"""Events to WebSocket viewers: one bounded queue each.

Strategy: the arm's events (job events, status updates) are published once, on the event loop,
and put in every viewer's queue without waiting (``put_nowait``).  Each viewer has its own
sender task that writes its queue to its socket; a viewer that does not read fills its socket's
buffers, its sender waits, its queue fills, and from then on events meant for it are dropped
and counted — the viewer is told how many (a ``dropped`` event) when it catches up.  So the
memory a viewer can hold is its queue's ``QUEUE_EVENTS`` plus the socket's buffers, whatever
the job, and a slow viewer never slows the job or the other viewers.
"""
from __future__ import annotations

import asyncio
import json
from typing import Any

QUEUE_EVENTS = 256  # events held for one viewer before newer ones are dropped for it


class Viewer:
    """One WebSocket viewer: its queue, and how many events it lost."""

    def __init__(self, client: str, capacity: int = QUEUE_EVENTS) -> None:
        self.client = client
        self.queue: asyncio.Queue[str] = asyncio.Queue(capacity)
        self.dropped = 0  # events lost since the viewer was last told
        self.dropped_total = 0

    def offer(self, text: str) -> None:
        try:
            self.queue.put_nowait(text)
        except asyncio.QueueFull:
            self.dropped += 1
            self.dropped_total += 1

    async def send_all(self, send) -> None:
        """The sender: ``await send(text)`` each queued event, in order, until cancelled."""
        while True:
            text = await self.queue.get()
            if self.dropped:
                lost, self.dropped = self.dropped, 0
                await send(json.dumps({"event": "dropped", "count": lost}))
            await send(text)


class Hub:
    """The viewers of one arm."""

    def __init__(self) -> None:
        self.viewers: set[Viewer] = set()
        self.published = 0

    def add(self, viewer: Viewer, limit: int | None = None) -> bool:
        """Add ``viewer`` — unless ``limit`` viewers are here already (False): checked and
        counted in one step, so connects arriving together cannot all pass the check."""
        if limit is not None and len(self.viewers) >= limit:
            return False
        self.viewers.add(viewer)
        return True

    def remove(self, viewer: Viewer) -> None:
        self.viewers.discard(viewer)

    def publish(self, event: dict[str, Any], but: Viewer | None = None) -> None:
        """Give ``event`` to every viewer (``but`` that one: it is about it) on the event loop; never waits."""
        self.published += 1
        if not self.viewers:
            return
        text = json.dumps(event, ensure_ascii=False)
        for viewer in self.viewers:
            if viewer is not but:
                viewer.offer(text)

    def stats(self) -> dict:
        return {"viewers": len(self.viewers), "published": self.published,
                "queued": sum(v.queue.qsize() for v in self.viewers),
                "dropped": sum(v.dropped_total for v in self.viewers)}
