"""The routes of ``armctl serve`` (docs/server.md documents each, with examples a test runs).

Strategy: each handler reads its request, calls ``ArmService`` and answers JSON; every error a
client can cause is a 4xx JSON ``{"error": message, "code": word}`` (a script's errors add its
``diagnostics``), never a traceback.  One middleware does, before any handler: the Host check
(without a token), the token (``/api`` only), the Origin check (POST and WebSockets), and the
mapping of armctl's errors to status codes.  Bodies are bounded by the script size limit
(armctl/host/inputs.py), and the script bodies held at once — read, waiting for their check
(one at a time in the process: ``off_loop``), being checked — by ``SCRIPTS_HELD_BYTES``
(``_holding``; a resumed job's journal script counts as an upload): beyond, an upload is 503 at once, so a neighbour's uploads cannot queue more
than two biggest scripts' checks nor hold more than their bytes.
"""
from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import uuid
from importlib import resources

from aiohttp import WSCloseCode, WSMsgType, web

from ..errors import ArmctlError, PortError, ScriptError
from ..host.inputs import MAX_INPUT_BYTES, describe_limit
from . import auth
from .arms import MAX_VIEWERS, Busy, NotController, UnknownJob, abandon_script_work, off_loop
from .hub import Viewer

_logger = logging.getLogger(__name__)
CLIENT_HEADER = "X-Armctl-Client"  # which client a state-changing request comes from (the controller's id)
WS_HEARTBEAT_S = 10.0  # aiohttp's ping on idle WebSockets (a dead peer is noticed)
CLOSE_AT_SHUTDOWN_S = 1.0  # a WebSocket's time to answer the server's close when it stops (then dropped)
STOPPING = "the server is stopping: it takes no new job, move, jog or control now"  # (a POST's 503, a jog's error)
SERVICES = web.AppKey("services", dict)
SETTINGS = web.AppKey("settings", dict)
SOCKETS = web.AppKey("sockets", set)  # the open WebSockets, closed at shutdown
HELD = web.AppKey("held", dict)  # {"bytes": the script bodies held now (``_script``)}
SCRIPTS_HELD_BYTES = 2 * MAX_INPUT_BYTES  # script bodies held at once, each counted from before its read


def _error(status: int, code: str, message: str, **extra) -> web.Response:
    return web.json_response({"error": message, "code": code, **extra}, status=status)


def _diagnostics(error: ScriptError) -> list[dict]:
    from ..lint.formatters import as_record

    return [as_record(d) for d in error.diagnostics]


@web.middleware
async def _guard(request: web.Request, handler):
    settings = request.app[SETTINGS]
    token = settings["token"]
    is_api = request.path.startswith("/api")
    if token is None and not auth.host_ok(request.headers.get("Host"), settings["host"]):
        return _error(403, "bad_host", "this server answers only to a loopback Host (start it with a token to serve others)")
    if token is not None and is_api and not auth.bearer_ok(token, request.headers.get("Authorization"),
                                                          request.headers.get("Sec-WebSocket-Protocol")):
        return _error(401, "unauthorized", "this server needs its token: Authorization: Bearer TOKEN")
    if request.method == "POST" and settings.get("stopping"):  # (its jobs stopping: nothing new begins)
        return _error(503, "stopping", STOPPING)
    websocket = request.headers.get("Upgrade", "").lower() == "websocket"
    if (request.method == "POST" or websocket) and not auth.origin_ok(request.headers.get("Origin"), request.headers.get("Host")):
        return _error(403, "bad_origin", f"requests from the origin {request.headers.get('Origin')!r} are refused")
    try:
        return await handler(request)
    except web.HTTPException as error:
        if error.status == 413:
            return _error(413, "too_large", f"the body is over the script size limit ({MAX_INPUT_BYTES} bytes)")
        if error.status == 404:
            return _error(404, "not_found", f"no such resource: {request.path}")
        if error.status == 405:
            return _error(405, "method_not_allowed", f"{request.method} is not allowed on {request.path}")
        if 400 <= error.status < 500:  # aiohttp's own refusals (a GET of the WebSocket path without its upgrade)
            return _error(error.status, "bad_request", " ".join((error.text or error.reason).split()))
        raise
    except ScriptError as error:
        return _error(422, "script_errors", str(error), diagnostics=_diagnostics(error))
    except (Busy, NotController) as error:
        return _error(409, "busy" if isinstance(error, Busy) else "read_only", str(error))
    except UnknownJob as error:
        return _error(404, "unknown_arm" if isinstance(error, _NotFound) else "unknown_job", str(error))
    except _BadJson as error:
        return _error(400, "bad_json", str(error))
    except _TooBusy as error:
        return _error(503, "too_busy", str(error))
    except PortError as error:  # the arm's condition, not the request's: the server never reopens a port
        return _error(503, "port_lost", f"{error}; reconnect the arm, then restart armctl serve (a job cut short "
                      f"continues from its journal: POST /api/arms/{request.match_info.get('name', 'NAME')}/jobs?resume=ID)")
    except (ArmctlError, ValueError, TypeError) as error:
        return _error(422, "refused", str(error))
    except OSError as error:  # the journal directory, a full disk
        return _error(503, "io_error", f"{error.strerror or error}{f': {error.filename}' if error.filename else ''}")
    except Exception as error:  # a fault of ours: logged with its traceback, the client gets JSON
        _logger.exception("armctl serve: %s %s failed", request.method, request.path)
        return _error(500, "internal", f"internal error ({type(error).__name__}); the server's log has the details")


def _service(request: web.Request):
    name = request.match_info["name"]
    try:
        return request.app[SERVICES][name]
    except KeyError:
        raise _NotFound(f"no arm named {name!r} (GET /api/arms lists them)") from None


class _NotFound(UnknownJob):
    pass


class _BadJson(ValueError):
    pass


class _TooBusy(ArmctlError):
    pass


@contextlib.asynccontextmanager
async def _script(request: web.Request):
    """The body as a script snapshot (read once; its name from ``?name=``), its length (or, not
    declared, the size limit) counted against ``SCRIPTS_HELD_BYTES`` from before the read until
    the block (the check) ends; ``_TooBusy`` when it does not fit."""
    from ..script.files import ScriptSnapshot

    size = MAX_INPUT_BYTES if request.content_length is None else request.content_length
    if size > MAX_INPUT_BYTES:  # (refused before it is read)
        raise web.HTTPRequestEntityTooLarge(max_size=MAX_INPUT_BYTES, actual_size=size)
    with _holding(request, size):
        yield ScriptSnapshot(request.query.get("name", "script")[:200], await request.read())


@contextlib.contextmanager
def _holding(request: web.Request, size: int):
    """``size`` bytes of script counted against ``SCRIPTS_HELD_BYTES`` for the block (an
    upload's body, a resumed job's journal script); ``_TooBusy`` when they do not fit."""
    held = request.app[HELD]
    if held["bytes"] + size > SCRIPTS_HELD_BYTES:
        raise _TooBusy(f"other uploads fill the {describe_limit(SCRIPTS_HELD_BYTES)} of scripts the server holds "
                       "for checking at once: try again once they are answered")
    held["bytes"] += size
    try:
        yield
    finally:
        held["bytes"] -= size


def _loads(text: str):
    """``json.loads``; JSON nested deeper than the parser recurses is a ``JSONDecodeError`` too."""
    try:
        return json.loads(text)
    except RecursionError:
        raise json.JSONDecodeError("nested too deeply", text, 0) from None


async def _json_object(request: web.Request) -> dict:
    data = await request.read()
    try:  # JSON is UTF-8 (RFC 8259), whatever charset a Content-Type names
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise _BadJson(f"the body is not JSON: byte {data[error.start]:#04x} at offset {error.start} is not UTF-8 text") from None
    try:
        value = _loads(text) if text.strip() else {}
    except json.JSONDecodeError as error:
        raise _BadJson(f"the body is not JSON: {error.msg} at line {error.lineno} column {error.colno}") from None
    if not isinstance(value, dict):
        raise _BadJson("the body must be a JSON object")
    return value


def _client(request: web.Request) -> str | None:
    return request.headers.get(CLIENT_HEADER)


# --- handlers --------------------------------------------------------------------------------

async def page(request: web.Request) -> web.Response:
    html = resources.files("armctl.server").joinpath("page/index.html").read_text(encoding="utf-8")
    return web.Response(text=html, content_type="text/html",
                        headers={"Content-Security-Policy": "default-src 'self'; script-src 'unsafe-inline'; "
                                 "style-src 'unsafe-inline'; connect-src 'self'", "Cache-Control": "no-store"})


async def list_arms(request: web.Request) -> web.Response:
    return web.json_response([service.describe() for service in request.app[SERVICES].values()])


async def status(request: web.Request) -> web.Response:
    service = _service(request)
    return web.json_response(await service.read_status())


async def lint(request: web.Request) -> web.Response:
    from ..lint.formatters import as_record

    service = _service(request)
    async with _script(request) as snapshot:
        report = await service.check(snapshot, errors_raise=False)
    return web.json_response({"errors": report.errors, "diagnostics": [as_record(d) for d in report.diagnostics]})


async def preview(request: web.Request) -> web.Response:
    """The path the job will take (``armctl plot``'s data), from the profile's fixed pose."""
    from ..lint.formatters import as_record
    from ..core.motion import MotionModel
    from ..plot.path import build_path

    service = _service(request)
    async with _script(request) as snapshot:
        report = await service.check(snapshot)
        path = await off_loop(lambda: build_path(snapshot.compile(), MotionModel(service.arm.profile), snapshot.name,
                                                 report.diagnostics))
    return web.json_response({
        "start": list(path.start), "omitted": path.omitted,
        "segments": [{"line": s.line, "first_line": s.first_line, "kind": s.kind, "points": [list(p) for p in s.points]}
                     for s in path.segments],
        "findings": [{**as_record(f.diagnostic), "point": list(f.point)} for f in path.findings]})


async def create_job(request: web.Request) -> web.Response:
    from ..lint.formatters import as_record

    service = _service(request)
    resume = request.query.get("resume")
    if resume is not None:  # (its journal script held while it waits for its check, as an upload's body is)
        with _holding(request, service.journal_script(resume).stat().st_size):
            job, report = await service.resume_job(resume, _client(request))
    else:
        async with _script(request) as snapshot:
            job, report = await service.start_job(snapshot, _client(request))
    return web.json_response({"id": job.id, "journal": str(job.log_path),
                              "diagnostics": [as_record(d) for d in report.diagnostics]}, status=201)


async def list_jobs(request: web.Request) -> web.Response:
    service = _service(request)
    return web.json_response([job.to_json() for job in service.jobs.values()])


async def get_job(request: web.Request) -> web.Response:
    service = _service(request)
    return web.json_response(service.job(request.match_info["id"]).to_json())


async def control_job(request: web.Request) -> web.Response:
    service = _service(request)
    action = request.match_info["action"]
    job = await service.running_job(request.match_info["id"], _client(request), action)
    arm = service.arm
    if action == "pause":
        return web.json_response({"id": job.id, "toggle_sent": await arm.pause()})
    if action == "resume":
        return web.json_response({"id": job.id, "toggle_sent": await arm.resume()})
    if action == "stop":
        await service.stop_once("stopped from the API")
        return web.json_response({"id": job.id, "stopping": True})
    body = await _json_object(request)
    percent = body.get("percent")
    if isinstance(percent, bool) or not isinstance(percent, (int, float)):
        raise ValueError('feed needs {"percent": N} with N a number (10-200)')
    return web.json_response({"id": job.id, "feed_percent": await arm.feed_override(percent)})


async def stop_arm(request: web.Request) -> web.Response:
    """Stop whatever the arm is doing (a job, or a move a client started and may have left)."""
    service = _service(request)
    return web.json_response({"arm": service.name, "stopping": await service.stop(_client(request))})


async def move(request: web.Request) -> web.Response:
    from ..host.api import move_line

    service = _service(request)
    words = await _json_object(request)
    allowed = {"timeout"} | set("xyzabcuvsthf") | {f"j{i}" for i in range(1, 7)}
    unknown = sorted(set(words) - allowed)
    if unknown:
        raise ValueError(f"unknown move keywords: {', '.join(unknown)} (x y z a b c j1…j6 u v s t h f timeout)")
    move_line(**{k: v for k, v in words.items() if k != "timeout"})  # the words' own errors, before anything
    return web.json_response(await service.move(words, _client(request)))


async def events(request: web.Request) -> web.WebSocketResponse:
    """The WebSocket: the arm's events; with ``?control=1`` the client asks to control it."""
    service = _service(request)
    client = request.query.get("client") or uuid.uuid4().hex
    viewer, sender = Viewer(client), None
    if not service.hub.add(viewer, MAX_VIEWERS):  # (counted before the handshake's waits: its events queue meanwhile)
        return _error(503, "too_many_viewers", f"arm {service.name!r} has {MAX_VIEWERS} viewers already")
    # a browser offering "armctl" and "bearer.TOKEN" gets "armctl" back (it must get one it offered)
    socket = web.WebSocketResponse(heartbeat=WS_HEARTBEAT_S, protocols=("armctl",), max_msg_size=64 * 1024)
    try:
        await socket.prepare(request)
    except BaseException:
        service.hub.remove(viewer)
        raise
    control = request.query.get("control") in ("1", "true") and service.take_control(client)
    request.app[SOCKETS].add(socket)
    try:  # (from here on: a client gone before its hello was written held control for good)
        await socket.send_json({"event": "hello", "arm": service.name, "client": client, "control": control,
                                "controlled": service.controller is not None, "status": service.status,
                                "job": None if service.running is None else service.running.to_json()})
        if control:
            service.publish({"event": "control", "controller": "another client"}, but=viewer)
        sender = asyncio.ensure_future(viewer.send_all(socket.send_str))
        async for message in socket:
            if message.type == WSMsgType.TEXT:
                await _on_message(service, client, socket, message.data, request.app[SETTINGS].get("stopping", False))
            elif message.type == WSMsgType.BINARY:  # answered too: the client would wait for an answer
                await socket.send_json({"event": "error", "error": "expected a text message (JSON), not a binary one"})
    except ConnectionError:
        pass  # the client went away while we wrote to it: as if it closed
    finally:
        request.app[SOCKETS].discard(socket)
        if sender is not None:
            sender.cancel()
        service.hub.remove(viewer)
        if control:  # (this socket's own control: a duplicated tab keeps it while its socket lives)
            try:
                await service.jog_stop()  # a closed tab: the neutral at once
            finally:
                service.release_control(client)
    return socket


async def _on_message(service, client: str, socket, text: str, stopping: bool = False) -> None:
    """A message from a viewer: ``{"jog": "j1_plus"}`` (a heartbeat: start or renew; refused
    once the server is ``stopping``: nothing moves an arm while it shuts down), ``{"jog": null}``
    (release), ``{"ping": …}``."""
    try:
        message = _loads(text)
    except json.JSONDecodeError:
        await socket.send_json({"event": "error", "error": "not JSON"})
        return
    if not isinstance(message, dict) or not ("jog" in message or "ping" in message):
        # (a client's mistake is answered, never silently dropped: it would wait for an answer)
        await socket.send_json({"event": "error", "error": 'expected an object with "jog" or "ping", '
                                'e.g. {"jog": "j1_plus"}, {"jog": null} or {"ping": 1}'})
        return
    try:
        if "jog" in message:
            if message["jog"] is None:
                if client == service.controller:
                    await service.jog_stop()
            elif stopping:
                await socket.send_json({"event": "error", "error": STOPPING})
            else:
                await service.jog(str(message["jog"]), client)
        else:
            await socket.send_json({"event": "pong", "ping": message["ping"]})
    except ArmctlError as error:
        await socket.send_json({"event": "error", "error": str(error)})


async def server_stats(request: web.Request) -> web.Response:
    return web.json_response({name: {**service.hub.stats(), "controlled": service.controller is not None}
                              for name, service in request.app[SERVICES].items()})


async def _on_shutdown(app: web.Application) -> None:
    """At shutdown, nothing holds the server's exit: the requests waiting for a script's check
    end (it is abandoned), every WebSocket is closed "going away" (an open one, a page, held it
    for aiohttp's 15 s wait for its handler)."""
    abandon_script_work()

    async def close(socket) -> None:
        try:  # (a client that never reads never answers: cancelled, its connection is dropped)
            await asyncio.wait_for(socket.close(code=WSCloseCode.GOING_AWAY, message=b"the server is stopping"),
                                   CLOSE_AT_SHUTDOWN_S)
        except (asyncio.TimeoutError, ConnectionError):
            pass

    await asyncio.gather(*(close(socket) for socket in list(app[SOCKETS])))


def build_app(services: dict, *, token: str | None, host: str) -> web.Application:
    app = web.Application(middlewares=[_guard], client_max_size=MAX_INPUT_BYTES)
    app[SERVICES] = services
    app[SETTINGS] = {"token": token, "host": host}
    app[SOCKETS] = set()
    app[HELD] = {"bytes": 0}
    app.on_shutdown.append(_on_shutdown)
    app.router.add_get("/", page)
    app.router.add_get("/api/arms", list_arms)
    app.router.add_get("/api/server", server_stats)
    app.router.add_get("/api/arms/{name}/status", status)
    app.router.add_post("/api/arms/{name}/lint", lint)
    app.router.add_post("/api/arms/{name}/preview", preview)
    app.router.add_post("/api/arms/{name}/jobs", create_job)
    app.router.add_get("/api/arms/{name}/jobs", list_jobs)
    app.router.add_get("/api/arms/{name}/jobs/{id}", get_job)
    app.router.add_post("/api/arms/{name}/jobs/{id}/{action:pause|resume|stop|feed}", control_job)
    app.router.add_post("/api/arms/{name}/move", move)
    app.router.add_post("/api/arms/{name}/stop", stop_arm)
    app.router.add_get("/api/arms/{name}/events", events)
    return app
