"""``armctl serve`` as users run it, for the server tests and the load benchmark: the installed
command in a subprocess on a free loopback port, and small HTTP/WebSocket helpers (urllib)."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from contextlib import contextmanager
from pathlib import Path

ARMCTL = Path(sys.executable).with_name("armctl")
START_TIMEOUT_S = 20.0


def free_port() -> int:
    """A port nobody listens on now (bound to 0 and released)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class Served:
    def __init__(self, process: subprocess.Popen, base: str, banner: str) -> None:
        self.process, self.base, self.banner = process, base, banner
        self.stderr_lines: list[str] = []

    def request(self, method: str, path: str, body: bytes | str | dict | None = None, headers: dict | None = None,
                timeout: float = 20.0) -> tuple[int, object]:
        """(status, the JSON answer) — 4xx/5xx answers included."""
        data = json.dumps(body).encode() if isinstance(body, dict) else body.encode() if isinstance(body, str) else body
        request = urllib.request.Request(self.base + path, data=data, method=method, headers=headers or {})
        try:
            with urllib.request.urlopen(request, timeout=timeout) as response:
                text = response.read()
                if response.headers.get_content_type() != "application/json":
                    return response.status, text.decode("utf-8", "replace")
                return response.status, json.loads(text or b"null")
        except urllib.error.HTTPError as error:
            text = error.read()
            try:
                return error.code, json.loads(text)
            except ValueError:
                return error.code, text.decode("utf-8", "replace")

    def wait_job(self, arm: str, job_id: str, timeout_s: float = 60.0, headers: dict | None = None) -> dict:
        """The job's record once it has an outcome."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            status, job = self.request("GET", f"/api/arms/{arm}/jobs/{job_id}", headers=headers)
            assert status == 200, job
            if job["outcome"] is not None:
                return job
            time.sleep(0.05)
        raise AssertionError(f"job {job_id} on {arm} did not end within {timeout_s} s")


@contextmanager
def served(*arguments: str, journal: Path, listen_host: str = "127.0.0.1", connect_host: str = "127.0.0.1",
           env: dict | None = None):
    """``armctl serve ARGUMENTS --listen HOST:PORT --journal-dir JOURNAL``, until the block ends
    (then SIGINT: it must exit 130)."""
    port = free_port()
    command = [str(ARMCTL), "serve", *arguments, "--listen", f"{listen_host}:{port}", "--journal-dir", str(journal)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, **(env or {})})
    banner: list[str] = []
    ready = threading.Event()

    def read() -> None:
        for line in process.stderr:
            banner.append(line)
            if " on http://" in line:
                ready.set()
        ready.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        if not ready.wait(START_TIMEOUT_S) or process.poll() is not None:
            raise AssertionError(f"armctl serve did not start: {''.join(banner)}")
        server = Served(process, f"http://{connect_host}:{port}", "".join(banner))
        server.stderr_lines = banner
        yield server
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
            try:
                process.wait(20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def never_reading_viewer(host: str, port: int, path: str) -> socket.socket:
    """A WebSocket client that asks to upgrade and then never reads (its receive buffer 4 kB)."""
    raw = socket.socket()
    raw.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    raw.connect((host, port))
    raw.sendall(f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n".encode())
    return raw


async def flood_a_slow_viewer(events: int = 40_000, size: int = 1000) -> dict:
    """The server's event hub (armctl/server/hub.py) behind aiohttp on loopback, one viewer that
    never reads (its socket's receive buffer 4 kB), ``events`` events of ``size`` bytes
    published at it: the largest queue it held, the events dropped for it, and how far the
    Python memory (tracemalloc) grew."""
    import asyncio
    import tracemalloc

    from aiohttp import web

    from armctl.server.hub import Hub, Viewer

    hub = Hub()

    async def handler(request):
        ws = web.WebSocketResponse()
        await ws.prepare(request)
        viewer = Viewer("slow")
        hub.add(viewer)
        sender = asyncio.ensure_future(viewer.send_all(ws.send_str))
        try:
            async for _ in ws:
                pass
        finally:
            sender.cancel()
            hub.remove(viewer)
        return ws

    app = web.Application()
    app.router.add_get("/events", handler)
    runner = web.AppRunner(app)
    await runner.setup()
    site = web.TCPSite(runner, "127.0.0.1", 0)
    await site.start()
    port = site._server.sockets[0].getsockname()[1]
    raw = never_reading_viewer("127.0.0.1", port, "/events")
    while not hub.viewers:
        await asyncio.sleep(0.01)
    viewer = next(iter(hub.viewers))
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    largest = 0
    for i in range(events):
        hub.publish({"event": "status", "n": i, "pad": "x" * size})
        largest = max(largest, viewer.queue.qsize())
        if i % 500 == 0:
            await asyncio.sleep(0)
    grown = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    raw.close()
    await runner.cleanup()
    return {"published": events, "published_mb": events * size / 1e6, "largest_queue": largest,
            "dropped": viewer.dropped_total, "peak_growth_mb": grown / 1e6}
