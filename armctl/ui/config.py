"""``armctl config``: every effective setting and where it came from.

Strategy: no resolution of its own.  The settings are what the commands themselves compute —
``resolve_port`` for the port (``--port``, ``ARMCTL_PORT``, the project armctl.toml, the user
armctl.toml, the simulator), ``line_baud`` for the line rate, ``calibration.arm_profile`` for the arm
profile, ``load_config`` for the files and the ``[lint]``/``[jog]`` tables — so what this
command prints is what ``run`` would use.  A bad file fails here exactly as it fails there
(a ConfigError/ProfileError naming the file and key, exit 2).

Each setting has a ``source``: ``option``, ``environment``, ``project`` (the nearest
armctl.toml), ``user`` (the user's armctl.toml) or ``default`` (built in), and ``where``: the
option or variable name, the file's path, or null.  The ``connector.*`` settings are the arm's
on that port (``calibration.arm_profile(port=…)``): their source is also ``probe`` (where: "probed on DATE
for ARM", what ``armctl probe`` stored with the arm), ``profile`` (the profile file) or
``document`` (the vendor document's reading).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

import click

from .cli_types import number
from ..core.limits import BAUD_RANGE


@dataclass(frozen=True)
class Setting:
    name: str
    value: Any  # JSON-shaped
    source: str  # "option", "environment", "project", "user", "probe" or "default"
    where: str | None  # "--port", "ARMCTL_PORT", a file's path, or None for a built-in default

    def to_json(self) -> dict:
        return {"value": self.value, "source": self.source, "where": self.where}


def _file_source(config, key: str) -> tuple[str, str | None]:
    path = config.path_of(key)
    if path is None:
        return "default", None
    return ("project" if path == config.project_path else "user"), str(path)


def effective_settings(port: str | None = None, baud: int | None = None, environ=None) -> tuple[list[Setting], Any]:
    """The settings a port-using command would take with these options, and the ``Config``."""
    from ..host.link import PORT_ENV, check_port_url, line_baud, resolve_port
    from ..host.calibration import arm_profile
    from ..host.profile import DEFAULT_RESOURCE, load_config

    environ = os.environ if environ is None else environ
    config = load_config()
    settings = []

    choice = resolve_port(port, environ=environ, config=config.values, config_path=config.path_of("port"))
    check_port_url(choice)  # what every command that opens it refuses (exit 2)
    if choice.origin in ("--port", PORT_ENV):
        source = ("option" if choice.origin == "--port" else "environment"), choice.origin
    else:
        source = _file_source(config, "port")
    settings.append(Setting("port", choice.url, *source))

    rate, where = line_baud(baud, config, choice.url)  # --baud, armctl.toml, the arm's probe, the document's
    if baud is not None:
        settings.append(Setting("baud", rate, "option", "--baud"))
    elif where is not None and where.startswith("probed on "):
        settings.append(Setting("baud", rate, "probe", where))
    else:
        settings.append(Setting("baud", rate, *_file_source(config, "baud")))

    profile = arm_profile(port=choice.url)  # checks the profile the files name: a missing one fails here too
    entry = config.values.get("profile")
    if entry is None:
        shown = f"<packaged {DEFAULT_RESOURCE[1]}>"
    elif isinstance(entry, dict):
        shown = f"[profile] table ({profile.name or 'unnamed'})"
    else:
        shown = str(config.path_of("profile").parent / entry)
    settings.append(Setting("profile", shown, *_file_source(config, "profile")))

    settings += connector_settings(profile, config)
    _check_tables(config)
    for table in ("lint", "jog"):
        settings.append(Setting(table, config.values.get(table, {}), *_file_source(config, table)))
    return settings, config


def _check_tables(config) -> None:
    """The ``[lint]`` and ``[jog]`` tables checked as ``armctl lint`` and ``armctl jog`` read them
    (a bad value: exit 2, as there), so what this lists is what they would take."""
    from ..errors import ConfigError
    from ..jog.keymap import JogConfigError
    from ..jog.settings import jog_from_config
    from ..lint.command import check_lint_table

    try:
        if "lint" in config.values:
            check_lint_table(config.values["lint"], config.path_of("lint"))
        if "jog" in config.values:
            jog_from_config(config.values["jog"], str(config.path_of("jog")))
    except (JogConfigError, ValueError) as error:
        raise ConfigError(str(error)) from None


def connector_settings(profile, config) -> list[Setting]:
    """The ``[connector]`` (and ``timing.command_overhead_s``, which the probe measures too) in
    effect for the arm on the port, each value with its source: ``probe``
    (``where``: "probed on DATE for ARM", the calibration stored with the arm), ``project`` or
    ``user`` (armctl.toml's ``[connector]``), ``profile`` (the profile file's own table) or
    ``document`` (the vendor document's reading, an H-decision)."""
    from ..core.profile_build import MEASURED_ELSEWHERE
    from ..host.profile import CONNECTOR_KEYS, DOCUMENT, ILLUSTRATIVE

    files = {str(path): kind for kind, path in (("user", config.user_path), ("project", config.project_path)) if path}
    settings = []
    # and what the probe measures that lives in another section (timing.command_overhead_s)
    for section, key in [("connector", key) for key in CONNECTOR_KEYS] + [(s, k) for k, s in MEASURED_ELSEWHERE.items()]:
        source = profile.source_of(f"{section}.{key}")
        if source in (DOCUMENT, ILLUSTRATIVE):  # (the packaged default's)
            origin = ("document", None)
        elif source.startswith("probed on "):
            origin = ("probe", source)
        else:
            origin = (files.get(source, "profile"), source)
        settings.append(Setting(f"{section}.{key}", getattr(getattr(profile, section), key), *origin))
    return settings


def settings_json(settings: list[Setting], config) -> dict:
    return {
        "settings": {s.name: s.to_json() for s in settings},
        "files": {
            "project": None if config.project_path is None else str(config.project_path),
            "user": str(config.user_path),
            "user_exists": config.user_path.is_file(),
        },
    }


_ORIGINS = {"default": "built-in default", "document": "the document's default"}


def settings_text(settings: list[Setting], config) -> str:
    """The settings for people, with their control characters escaped: a profile's name, a file's
    path or an arm's identity is not ours, and must not drive the terminal (clear, retitle it)."""
    from .decode_output import plain_text

    lines = []
    for s in settings:
        value = s.value if isinstance(s.value, str) else json.dumps(s.value, ensure_ascii=False)
        origin = _ORIGINS.get(s.source) or (s.where if s.source == "probe" else f"{s.source}: {s.where}")
        lines.append(f"{s.name:<8} {value}  ({origin})")
    project = config.project_path or "none found from the working directory up"
    user = f"{config.user_path}{'' if config.user_path.is_file() else ' (not present)'}"
    lines += [f"project file: {project}", f"user file:    {user}"]
    return "\n".join(map(plain_text, lines))


@click.command()
@click.option("--port", "port", metavar="URL", help="Show the settings as a command given this --port would take them.")
@click.option("--baud", type=number(*BAUD_RANGE, whole=True), default=None, help="Likewise for --baud.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object on stdout.")
def config(port, baud, as_json):
    """Print every effective setting and where it came from.

    Order: an option, then ARMCTL_PORT (port only), then the nearest project armctl.toml, then
    the user's armctl.toml (e.g. ~/.config/armctl/armctl.toml), then the built-in default.
    """
    settings, loaded = effective_settings(port, baud)
    if as_json:
        click.echo(json.dumps(settings_json(settings, loaded), ensure_ascii=False))
    else:
        click.echo(settings_text(settings, loaded))
