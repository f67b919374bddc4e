"""``armctl serve``'s process: open the arms, listen, stop cleanly.

Strategy: everything on one asyncio loop (aiohttp's).  The listening address is bound first
(``bind``: a taken address ends the command before any arm's port is opened), then the arms
are opened as ``AsyncArm``, then the server accepts its first request on the sockets bound;
SIGINT, SIGTERM and SIGHUP (the terminal closed: ``stop_signals``'s three)
stop the server the way Ctrl-C stops ``armctl run``: a running job is stopped (the abort
sequence, the arm waited for — a second signal cuts that wait short —, the journal closed, its
summary published), then the WebSockets closed, the arms closed, then the process exits 130.
"""
from __future__ import annotations

import asyncio
import errno
import os
import socket
import sys
from pathlib import Path

from ..errors import ConfigError
from ..host.stop_signals import STOP_SIGNALS
from . import auth
from .arms import NAME_PATTERN, ArmService

DEFAULT_LISTEN = "127.0.0.1:8765"
DEFAULT_ARM = "arm"


def parse_arms(specs: tuple[str, ...]) -> list[tuple[str, str | None]]:
    """``NAME=PORT`` options → [(name, port)]; none: the configured port as ``arm``."""
    if not specs:
        return [(DEFAULT_ARM, None)]
    arms: list[tuple[str, str | None]] = []
    for spec in specs:
        name, sep, port = spec.partition("=")
        if not sep or not NAME_PATTERN.fullmatch(name) or not port:
            raise ConfigError(f"--arm {spec!r}: expected NAME=PORT, NAME of 1-32 letters, digits, _ or - "
                              "(e.g. --arm 'a=sim://?speed=20')")
        if any(name == other for other, _ in arms):
            raise ConfigError(f"--arm {spec!r}: the name {name!r} is given twice")
        arms.append((name, port))
    return arms


def journal_root(journal_dir: str | None) -> Path:
    if journal_dir is not None:
        return Path(journal_dir)
    import platformdirs

    return Path(platformdirs.user_data_dir("armctl", appauthor=False)) / "serve-journal"


def serve(arm_specs: tuple[str, ...], listen: str, token_file: str | None, journal_dir: str | None,
          profile: str | None = None, lead_s: float = 2.0, say=print) -> None:
    """Serve until SIGINT/SIGTERM/SIGHUP (then KeyboardInterrupt).  ConfigError/PortError: nothing served."""
    host, port = auth.parse_listen(listen)
    arms = parse_arms(arm_specs)
    token = None
    if not auth.is_loopback(host) or token_file is not None:
        token, generated = auth.load_token(token_file)
        if generated:
            say(f"armctl serve: a token was generated and kept (0600) in {auth.token_path()}; it is shown this once:\n"
                f"  {token}")
        else:
            say(f"armctl serve: requests need the token in {token_file or auth.token_path()}")
    asyncio.run(_serve(arms, host, port, token, journal_root(journal_dir), profile, lead_s, say))
    raise KeyboardInterrupt  # stopped by a signal, cleanly: exit 130 like every command


def bind(host: str, port: int) -> list[socket.socket]:
    """Sockets listening on every address of ``host`` (IPv4 and IPv6 for ``localhost``), bound as
    aiohttp's ``TCPSite`` would bind them (SO_REUSEADDR on POSIX, IPv6 only on IPv6); a client
    that connects waits until they are served.  ``ConfigError`` when an address cannot be had
    (taken, not this machine's)."""
    sockets: list[socket.socket] = []
    try:
        for family, kind, protocol, _, address in dict.fromkeys(
                socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)):
            sockets.append(socket.socket(family, kind, protocol))
            if os.name == "posix":
                sockets[-1].setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6:
                sockets[-1].setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            sockets[-1].bind(address)
            sockets[-1].listen()  # (now: with SO_REUSEADDR another bind may succeed until one listens)
    except OSError as error:
        for bound in sockets:
            bound.close()
        taken = " (another program listens there: stop it, or give another --listen)" \
            if error.errno == errno.EADDRINUSE else ""
        raise ConfigError(f"cannot listen on {host}:{port}: {error.strerror or error}{taken}") from None
    return sockets


async def _serve(arms, host, port, token, journal, profile, lead_s, say) -> None:
    from aiohttp import web

    from ..aio import AsyncArm
    from .app import SETTINGS, build_app

    services: dict[str, ArmService] = {}
    listening = bind(host, port)  # before any arm is opened: a taken address touches no arm
    try:
        from ..host.port_choice import choose_port

        for name, url in arms:  # (resolved here: a bad URL is named as the --arm that gave it)
            arm = await AsyncArm.open(choose_port(url, origin=f"--arm {name}"), profile=profile, lead_s=lead_s)
            services[name] = ArmService(name, url or arm.url, arm, journal / name)
        app = build_app(services, token=token, host=host)
        runner = web.AppRunner(app, handle_signals=False, access_log=None)
        await runner.setup()
        try:
            for bound in listening:
                await web.SockSite(runner, bound).start()
        except OSError as error:
            raise ConfigError(f"cannot listen on {host}:{port}: {error.strerror or error}") from None
        for service in services.values():
            service.start()
        shown = f"[{host}]" if ":" in host else host
        say(f"armctl serve: {len(services)} arm(s) ({', '.join(f'{n}={s.arm.url}' for n, s in services.items())}) "
            f"on http://{shown}:{port}/" + ("" if token is None else "?token=TOKEN") + "  (Ctrl-C to stop)")
        sys.stdout.flush()
        stop = asyncio.Event()

        def signalled() -> None:
            if stop.is_set():  # a second one: as armctl run's second Ctrl-C, the arms are no longer waited for
                for service in services.values():
                    asyncio.ensure_future(service.stop_once("the server is stopping", again=True))
            stop.set()

        loop = asyncio.get_running_loop()
        for number in STOP_SIGNALS:  # (SIGHUP too: a closed terminal ended the process with no abort sequence)
            loop.add_signal_handler(number, signalled)
        await stop.wait()
        app[SETTINGS]["stopping"] = True  # every POST (503) and every jog refused from now on
        for service in services.values():  # a jog held now: the neutral at once, not at its lease's end
            await service.jog_stop()
        # every job or move stops first (no handler waits for it), and a job's end is published
        # before the WebSockets close: a page shows it interrupted, not running for good
        await asyncio.gather(*(service.stop_and_wait("the server is stopping") for service in services.values()))
        await runner.cleanup()
    finally:
        for service in services.values():
            await service.close()
        for bound in listening:  # (the runner closed those it served; closing twice does nothing)
            bound.close()
