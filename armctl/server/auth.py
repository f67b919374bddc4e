"""Who may talk to ``armctl serve``: the token, the Origin and the Host.

Strategy: secure by default, with nothing to configure on one machine.
- Loopback (``127.0.0.0/8``, ``::1``, ``localhost``) needs no token, but the Host header must
  name a loopback address (a page on another site cannot reach the arm by DNS rebinding).
- Any other ``--listen`` needs a token: ``--token-file``'s, else the one kept (0600) in the user
  config directory, generated and printed once, the first time it is needed.  Every ``/api``
  request then carries ``Authorization: Bearer TOKEN``; a browser's WebSocket cannot set that
  header, so it may offer the token as the subprotocol ``bearer.TOKEN`` instead.  The page at
  ``/`` holds no secret and is served to anyone: it reads the token from its own URL
  (``/?token=…``, the one the server prints), keeps it in sessionStorage and drops it from the
  address bar.
- State-changing requests (POST) and WebSockets that carry an ``Origin`` must come from the
  server's own origin: another site's page in the same browser gets 403.
"""
from __future__ import annotations

import hmac
import ipaddress
import os
import secrets
from pathlib import Path

from ..errors import ConfigError

TOKEN_NAME = "serve-token"
TOKEN_BYTES = 32
WS_PROTOCOL_PREFIX = "bearer."


def is_loopback(host: str) -> bool:
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def parse_listen(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6) → (host, port); ConfigError otherwise."""
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"--listen {text!r}: expected HOST:PORT with a port 1-65535 (e.g. 127.0.0.1:8765)")
    return host.strip("[]"), int(port)


def token_path() -> Path:
    """Where the generated token is kept: beside the user armctl.toml."""
    from ..host.profile import user_config_path

    return user_config_path().parent / TOKEN_NAME


def load_token(token_file: str | None) -> tuple[str, bool]:
    """The token and whether it was generated now (then the caller prints it, once)."""
    path = Path(token_file) if token_file is not None else token_path()
    if token_file is not None or path.exists():
        try:
            token = path.read_text(encoding="utf-8").strip()
        except (OSError, UnicodeDecodeError) as error:
            raise ConfigError(f"cannot read the token file {path}: {getattr(error, 'strerror', None) or error}") from None
        if len(token) < 16 or any(c.isspace() for c in token):
            raise ConfigError(f"the token in {path} must be one word of at least 16 characters")
        return token, False
    token = secrets.token_urlsafe(TOKEN_BYTES)
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as file:
        file.write(token + "\n")
    return token, True


def bearer_ok(token: str, authorization: str | None, ws_protocols: str | None = None) -> bool:
    """The request carries ``token``: as ``Authorization: Bearer``, or (a WebSocket) as a
    ``bearer.TOKEN`` subprotocol.  Compared in constant time."""
    offered = []
    if authorization and authorization.startswith("Bearer "):
        offered.append(authorization[len("Bearer "):].strip())
    for protocol in (ws_protocols or "").split(","):
        protocol = protocol.strip()
        if protocol.startswith(WS_PROTOCOL_PREFIX):
            offered.append(protocol[len(WS_PROTOCOL_PREFIX):])
    return any(hmac.compare_digest(candidate.encode(), token.encode()) for candidate in offered)


def host_ok(host_header: str | None, listen_host: str) -> bool:
    """Without a token the server answers only to a loopback Host (DNS rebinding)."""
    if not host_header:
        return False
    name = host_header.rsplit(":", 1)[0] if not host_header.endswith("]") else host_header
    return is_loopback(name.strip("[]")) or name.strip("[]") == listen_host


def origin_ok(origin: str | None, host_header: str | None) -> bool:
    """No Origin (a script, curl) or the server's own (``http://`` + its Host)."""
    if origin is None:
        return True
    return host_header is not None and origin in (f"http://{host_header}", f"https://{host_header}")
