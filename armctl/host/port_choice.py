"""The port a command will use, chosen once: ``--port``, ``ARMCTL_PORT``, ``port`` in armctl.toml, or
the built-in simulator.

Strategy: a few pure lines, apart from the port edge (armctl/host/link.py, which re-exports them), so
the commands that open no port — ``lint``, ``estimate``, ``plot``, a dry run — can name the arm
they would talk to (its kept calibration: armctl/host/calibration.py) without loading the status
reader, the link's thread machinery or the simulator.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from typing import Any

from ..errors import ConfigError
from .profile import CONFIG_NAME, check_config_value

SIMULATOR_URL = "sim://"
PORT_ENV = "ARMCTL_PORT"


@dataclass(frozen=True)
class PortChoice:
    url: str
    origin: str  # "--port", "ARMCTL_PORT", the armctl.toml it came from (project or user) or "default"
    # the arm on it, once read (``calibration.with_arm``: its identity, what ``armctl probe`` kept
    # for it): the command or ``Arm`` that chose the port reads it once and passes the choice on
    arm: Any = field(default=None, compare=False, repr=False)
    # a ``sim://?profile=FILE``'s profile, read once by the check (``check_sim_url``): the simulator
    # opened for this choice is given it (``link.connect``), so the file checked is the file run
    sim_profile: Any = field(default=None, compare=False, repr=False)

    @property
    def from_file(self) -> bool:
        return self.origin.endswith(CONFIG_NAME)  # (every armctl.toml, the project's or the user's)

    @property
    def is_simulator(self) -> bool:
        return self.url.startswith("sim://")

    def banner(self) -> str | None:
        """The first line a command prints when no real port was chosen."""
        if self.origin == "default":
            return "armctl: no port configured (--port, ARMCTL_PORT or armctl.toml): using the built-in simulator (sim://)"
        if self.is_simulator:
            return f"armctl: using the built-in simulator ({self.url})"
        return None


def resolve_port(option: str | None, environ=os.environ, config: dict | None = None, config_path=CONFIG_NAME,
                 origin: str = "--port") -> PortChoice:
    """``--port``, else ``ARMCTL_PORT``, else ``port`` in armctl.toml (``config``: the project
    file laid over the user file, ``config_path``: the one ``port`` came from), else the simulator.
    ``origin``: what the caller calls ``option`` in its messages (``Arm.open``'s ``port``, serve's ``--arm``).

    The simulator is the default only when no port is given anywhere: a port given empty (or,
    in armctl.toml, of the wrong type) is a ConfigError, never a quiet fallback to the simulator.
    """
    if option is not None:
        if not option.strip():
            raise ConfigError(f"{origin} is empty: give a device or URL (`armctl ports` lists the devices found), "
                              f"or leave {origin} out")
        if "\0" in option:  # (Arm.open's port, serve's --arm: a command line cannot hold one)
            raise ConfigError(f"{origin} {option!r} holds a NUL character, which no port name has")
        return PortChoice(_scheme_lowered(option), origin)
    if PORT_ENV in environ:
        if not environ[PORT_ENV].strip():
            raise ConfigError(f"{PORT_ENV} is set but empty: give a device or URL, or unset it "
                              f"(`unset {PORT_ENV}`)")
        return PortChoice(_scheme_lowered(environ[PORT_ENV]), PORT_ENV)
    if config and "port" in config:
        url = check_config_value(config_path, "port", config["port"])
        return PortChoice(_scheme_lowered(url), str(config_path))
    return PortChoice(SIMULATOR_URL, "default")


def _scheme_lowered(url: str) -> str:
    """``url`` with its scheme in lower case, as pyserial reads it (``SIM://`` opens its sim://
    handler): one spelling, so that every test of the scheme here (the banner, the simulator's own
    FIFO as proof, the arm's identity) sees the port pyserial opens."""
    scheme, separator, rest = url.partition("://")
    return scheme.lower() + separator + rest if separator else url


def choose_port(port: "str | PortChoice | None", config=None, origin: str = "--port") -> PortChoice:
    """``resolve_port`` with the armctl.toml files, a ``sim://`` URL checked: the port a command
    will open, resolved once (its arm's profile is loaded for it: ``calibration.arm_profile(port=…)``)."""
    if isinstance(port, PortChoice):
        return port
    from .profile import load_config

    config = config or load_config()
    choice = resolve_port(port, config=config.values, config_path=config.path_of("port"), origin=origin)
    return check_port_url(choice)


# schemes every command meets, known without asking pyserial (which ``check_port_url`` asks for the rest)
_KNOWN_SCHEMES = ("sim", "socket", "rfc2217")


def check_port_url(choice: PortChoice) -> PortChoice:
    """A URL whose scheme no pyserial handler takes (``http://``, `` sim://``) or a bad ``sim://``
    option is a usage error (exit 2) naming where the URL came from, raised before anything
    opens — by ``armctl config`` as by the commands that would open it.  Returns ``choice``, with
    its ``sim_profile`` read."""
    scheme, separator, _ = choice.url.partition("://")
    if separator and scheme not in _KNOWN_SCHEMES and not _pyserial_takes(scheme):
        raise ConfigError(f"{_where(choice)}: {choice.url!r}: no port type {scheme!r} (a device path such as /dev/ttyUSB0, "
                          "socket://HOST:PORT, rfc2217://HOST:PORT or sim://[?options])")
    return check_sim_url(choice) if choice.is_simulator else choice


def _where(choice: PortChoice) -> str:
    """Where a port came from, as its errors name it (a file's key, or the option or variable)."""
    return f"{choice.origin}: port" if choice.from_file else choice.origin


def _pyserial_takes(scheme: str) -> bool:
    """pyserial has a handler for ``scheme`` (its own ``loop://``, ``spy://``, ``hwgrep://`` …):
    the module ``serial_for_url`` would import, looked up in the packages it searches."""
    import importlib.util

    import serial

    if not scheme.isidentifier():
        return False
    for package in serial.protocol_handler_packages:
        try:
            if importlib.util.find_spec(f"{package}.protocol_{scheme}") is not None:
                return True
        except ImportError:
            continue
    return False


def check_sim_url(choice: PortChoice) -> PortChoice:
    """A bad ``sim://`` option is a usage error (exit 2) naming where the URL came from, raised
    before anything opens: the one parse is armctl/sim/protocol_sim.py's.  A ``profile`` option's
    file is read here (``read_sim_profile``; a missing or bad one is refused by ``armctl config`` as
    by the command that would open the port), the only time: ``choice`` is returned with it."""
    if choice.url in ("sim://", "sim:///", "sim://?"):
        return choice  # the default arm: nothing to parse, and lint or estimate need not load the simulator
    from ..errors import ProfileError
    from ..sim.protocol_sim import parse_sim_url

    where = _where(choice)
    try:
        options = parse_sim_url(choice.url)
    except ConfigError as error:
        raise ConfigError(f"{where}: {error}") from None
    try:
        return replace(choice, sim_profile=read_sim_profile(options))
    except (ConfigError, ProfileError) as error:
        raise ConfigError(f"{where}: sim:// option profile: {error}") from None


def read_sim_profile(options):
    """The profile a ``sim://`` URL's ``profile`` option names (None: it names none), read once for
    the simulator to be given (``PortChoice.sim_profile``, ``armctl sim``'s arm) — the profile as the
    simulator takes it (``chosen_profile``: no armctl.toml ``[connector]`` laid over; its
    connector is its options'), armctl.toml's ``[connector]`` checked as every command checks it."""
    if not isinstance(options.profile, str):
        return None
    from .profile import chosen_profile, load_config, with_file_connector

    config = load_config()
    profile = chosen_profile(options.profile, config=config)
    with_file_connector(profile, config)  # (the check ``load_profile`` made here before)
    return profile
