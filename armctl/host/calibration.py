"""The calibration store: what ``armctl probe`` measured, kept with the arm it measured.

Strategy: an arm is known by its identity, never by the directory a command runs in.
``arm_identity`` turns a port into one: a USB device's VID:PID and serial number (or, without
a serial number, the USB location it is plugged into) as pyserial's ``list_ports`` reports them
for the port's device, ``host:port`` for ``socket://`` and ``rfc2217://``, the arm's own options
for ``sim://`` (what the simulated arm does — FIFO, control frames, status frame, speed factor,
links, baud, profile — in one canonical spelling, defaults left out; not the clock, the time
scale, the seed or the faults, which are the line's and the test's, not the arm's), and the
device path itself for a device pyserial knows nothing more of (a pty's with the moment it was
made: the next pty takes its path).  Two spellings of one arm
(``sim://?speed_factor=1.3&fifo=50&clock=virtual`` and ``sim://?fifo_frames=50&speed_factor=1.3``)
are one identity; an identity is a port too (``arm_identity`` of it is itself).

A ``Calibration`` is one arm's measured ``[connector]`` settings (and ``command_overhead_s``, the
profile's ``[timing]`` value: ``with_connector`` lays it there), each with the date it was
probed, its evidence and how sure the probe was.  A later probe replaces the values it measured
and keeps the others (a ``--no-motion`` probe does not forget a speed factor measured before).
The store is one JSON file per arm in the user data directory (``$XDG_DATA_HOME/armctl/arms/``,
platformdirs' ``user_data_dir("armctl")`` elsewhere), named by the identity (quoted), written
atomically (a temporary file, fsync, rename): a crash leaves the old record or the new one.

Pure apart from the edges: ``list_ports`` (``port_infos``, only for a device path) and the
store's files (``load``, ``save``, ``stored``, ``forget``).  The arm on a port — its identity and
its record in the store — is read once, where the port is resolved (``with_arm``: it rides on the
``PortChoice``; ``quiet_port`` for a command that opens none); the profile of that arm
(``arm_profile``), the line rate its probe kept (``probed_baud``) and a job's log take it from
there, and everything after reads the profile.  ``stale_notes`` reads a finished job's evidence
against the values.
"""

from __future__ import annotations

import os
import sys
import urllib.parse
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError

STORE_FOLDER = "arms"
FORMAT = 1  # the record's "format": a later armctl that changes it reads this one or refuses it by name
# sim:// options that describe the arm (SimOptions fields), in the identity's order; the rest
# (clock, speed, seed, loss, corrupt, noise) are the line's or the test's
SIM_ARM_FIELDS = ("baud", "control_frames", "fifo_frames", "link_scale", "profile", "speed_factor", "status_jitter_s",
                  "status_xyz_frame")
_NETWORK_SCHEMES = ("socket", "rfc2217")
_USB, _DEVICE = "usb ", "device "
# a path's bytes that are not UTF-8 (``/dev/tty\xff``, a profile ``p\xff.toml``: Python hands them over
# as surrogates) are those bytes again in a quoted identity or a record's file name (``%FF``)
_FILE_NAME_BYTES = "surrogateescape"
_PTY_FOLDER, _PTY_MADE = "/dev/pts/", " pty made "  # a pty's identity: its path and when it was made (_pty_made)


# --- identity -------------------------------------------------------------------------------------


def arm_identity(port: str, ports=None) -> str:
    """The identity of the arm on ``port`` (a device path, a pyserial URL or an identity).
    ``ports``: pyserial ``ListPortInfo`` records (default: ``list_ports.comports()``, read
    only for a device path)."""
    if port.startswith((_USB, _DEVICE)):
        return port
    parts = _url_parts(port) if "://" in port else None
    scheme = parts.scheme if parts is not None else ""
    if scheme == "sim":
        return _sim_identity(port)
    if scheme in _NETWORK_SCHEMES:
        if parts.port is None or not parts.hostname:  # (pyserial's own words for it: "'<=' not supported …")
            raise ConfigError(f"{port!r} needs a host and a port number: {scheme}://HOST:PORT")
        return f"{scheme}://{parts.hostname.lower()}:{parts.port}"
    if scheme:  # loop://, spy://…: the URL without its options
        return f"{scheme}://{parts.netloc}{parts.path}"
    return _device_identity(port, port_infos() if ports is None else ports)


def _url_parts(url: str) -> urllib.parse.SplitResult:
    """``url`` split, its port number read: a URL urllib cannot split (``socket://[::1``) or whose
    port is no number 0…65535 (``socket://host:99999``) is a ConfigError naming it (exit 2), not
    the ValueError urllib raises on reading it."""
    try:
        parts = urllib.parse.urlsplit(url)
        parts.port  # (read for its ValueError)
    except ValueError as error:
        raise ConfigError(f"{url!r} is not a port URL armctl can use: {error}") from None
    return parts


def _sim_identity(url: str) -> str:
    if url in ("sim://", "sim:///", "sim://?"):  # the default arm, without loading the simulator (lint, estimate)
        return "sim://"
    from ..sim.model import SimOptions
    from ..sim.protocol_sim import parse_sim_url

    options, default = parse_sim_url(url), SimOptions()
    words = []
    for name in SIM_ARM_FIELDS:
        value = getattr(options, name)
        if value == getattr(default, name):
            continue
        if name == "profile":
            value = os.path.abspath(value)
        elif name == "status_jitter_s":  # spelled as its URL option, in ms: an identity is a URL of that arm
            name, value = "status_jitter_ms", format(value * 1000.0, "g")
        elif isinstance(value, float):
            value = format(value, "g")
        words.append(f"{name}={urllib.parse.quote(str(value), safe='/', errors=_FILE_NAME_BYTES)}")
    return "sim://" + ("?" + "&".join(words) if words else "")


def _device_identity(path: str, ports) -> str:
    """A USB adapter by VID:PID and serial number (or its USB location); any other device by path."""
    real = os.path.realpath(path) if os.path.lexists(path) else path  # COM3 is no file: kept as named
    for info in ports:
        if info.device not in (path, real) and os.path.realpath(info.device) != real:
            continue
        if info.vid is None or info.pid is None:
            break
        usb = f"{_USB}{info.vid:04x}:{info.pid:04x}"
        if info.serial_number:
            return f"{usb} serial {info.serial_number}"
        if info.location:
            return f"{usb} at {info.location}"
        break
    made = _pty_made(real)
    return f"{_DEVICE}{real}" + ("" if made is None else f"{_PTY_MADE}{made}")


def _pty_made(real: str) -> str | None:
    """When the kernel made the pty ``real`` (its node's ctime, UTC to the ns; None for any other device): a
    pty's path names whichever pty has that number now — the next ``armctl sim --pty`` gets
    /dev/pts/1 as soon as the last one closed — so the moment tells one arm behind it from the next
    (the kernel's clock is coarse: two ptys made within its tick, a few ms, would share it; no
    program that serves an arm starts that fast)."""
    if not real.startswith(_PTY_FOLDER):
        return None
    import time

    try:
        made_ns = os.stat(real).st_ctime_ns
    except OSError:
        return None
    return time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(made_ns // 10**9)) + f".{made_ns % 10**9:09d}Z"


def _pty_device(identity: str) -> str | None:
    """A pty's identity without the moment it was made (``device /dev/pts/N``); None for any other."""
    device, made, _ = identity.partition(_PTY_MADE)
    return device if made and identity.startswith(_DEVICE) else None


def by_name_only(identity: str) -> bool:
    """An identity no more than the path or address its port leads to (a device without a USB
    serial number or location, a TCP port): another arm there has the same one.  Not a pty's: the
    moment it was made is in it."""
    if _pty_device(identity) is not None:
        return False
    return identity.startswith((_DEVICE, *(f"{scheme}://" for scheme in _NETWORK_SCHEMES)))


def reads_port_list(port: str) -> bool:
    """``arm_identity`` of ``port`` reads pyserial's port list: a device path (no URL, no identity)."""
    return "://" not in port and not port.startswith((_USB, _DEVICE))


def ports_to_search(identity: str, ports) -> list[str]:
    """Where the arm of ``identity`` may be plugged now: for a USB adapter's, every device pyserial
    lists (``ports``); for a device's, the path it names, if there is one; else nowhere else."""
    if identity.startswith(_USB):
        return sorted(info.device for info in ports)
    path = (_pty_device(identity) or identity)[len(_DEVICE):]
    return [path] if identity.startswith(_DEVICE) and os.path.exists(path) else []


def port_infos():
    """The serial ports pyserial finds (the edge ``arm_identity`` reads for a device path)."""
    from serial.tools import list_ports

    return list_ports.comports()


@dataclass(frozen=True)
class ArmOnPort:
    """The arm on a port, read once (``with_arm``): its ``identity`` and what ``armctl probe``
    kept for it (``kept``: a ``Calibration``, or None)."""

    identity: str
    kept: "Calibration | None"


def with_arm(port, identity: str | None = None):
    """``port`` (a ``port_choice.PortChoice``, or a URL) with the arm on it read (``PortChoice.arm``,
    an ``ArmOnPort``) — once: a device's identity lists pyserial's ports, so the command or ``Arm``
    that chose the port reads it here and passes the choice on; its profile (``arm_profile``), its
    line rate (``probed_baud``) and its job's log (``resume_port.arm_of``) take it from there.
    ConfigError for a URL whose arm cannot be named (``identity``: its ``arm_identity``, read already)."""
    from dataclasses import replace

    from .port_choice import PortChoice

    choice = port if isinstance(port, PortChoice) else PortChoice(port, "--port")
    if choice.arm is not None:
        return choice
    identity = arm_identity(choice.url) if identity is None else identity
    return replace(choice, arm=ArmOnPort(identity, load(identity)))


def quiet_port(option, config=None):
    """The port a command that opens none would name (lint, estimate, plot, a dry run: ``option``,
    else the configured one), its arm read (``with_arm``), for the arm's kept calibration and line
    rate; None when the port or its arm cannot be named (an empty ARMCTL_PORT, a bad URL): such a
    command does not talk to the arm, so a port it would not open does not stop it — no stored
    calibration applies then, no [connector] that names an arm, and the line rate is armctl.toml's
    or the document's."""
    from .port_choice import choose_port

    try:
        choice = choose_port(option, config)  # (a PortChoice: itself, its arm read already or now)
        identity = arm_identity(choice.url) if choice.arm is None else None
    except ConfigError:
        return None
    return with_arm(choice, identity)  # (a kept calibration it cannot read is an error all the same)


# --- one arm's record ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Measured:
    value: object  # as armctl.toml's [connector] spells it: a number, a word or a boolean
    probed_on: str  # the date, YYYY-MM-DD (UTC)
    evidence: str = ""
    confidence: str = ""


@dataclass(frozen=True)
class Calibration:
    arm: str  # arm_identity
    port: str  # the port it was last probed through, as given
    settings: dict[str, Measured] = field(default_factory=dict)
    baud: int | None = None  # the line rate the probe read the arm's status at (None: a record from before)
    baud_on: str = ""  # ... on that date

    def values(self) -> dict:
        return {name: measured.value for name, measured in self.settings.items()}

    def source_of(self, name: str) -> str:
        """The source a profile names for ``name`` (``Profile.sources``, ``armctl config``)."""
        return f"probed on {self.settings[name].probed_on} for {self.arm}"

    def updated(self, newer: "Calibration") -> "Calibration":
        """This record with ``newer``'s values laid over it (what a later probe measured wins)."""
        baud, baud_on = (newer.baud, newer.baud_on) if newer.baud is not None else (self.baud, self.baud_on)
        return Calibration(self.arm, newer.port, {**self.settings, **newer.settings}, baud, baud_on)

    def to_json(self) -> dict:
        line = {} if self.baud is None else {"baud": self.baud, "baud_probed_on": self.baud_on}
        return {"format": FORMAT, "arm": self.arm, "port": self.port, **line,
                "settings": {name: vars(measured) for name, measured in self.settings.items()}}

    @classmethod
    def from_json(cls, data, where: str) -> "Calibration":
        try:
            if data.get("format") != FORMAT:
                raise ValueError(f"format {data.get('format')!r}, not {FORMAT}")
            settings = {str(name): Measured(**record) for name, record in data["settings"].items()}
            baud = data.get("baud")
            if baud is not None and (not isinstance(baud, int) or isinstance(baud, bool) or baud <= 0):
                raise ValueError(f"baud {baud!r}")
            return cls(str(data["arm"]), str(data["port"]), settings, baud, str(data.get("baud_probed_on", "")))
        except (AttributeError, KeyError, TypeError, ValueError) as error:
            raise ConfigError(f"{where}: not a calibration this armctl reads ({error}): delete the file, "
                              "or `armctl probe --forget ARM`, and probe again") from None


def calibration_of(port: str, arm: str, findings, probed_on: str, baud: int | None = None) -> Calibration:
    """A record from a probe's findings (``(name, value, evidence, confidence)``: the values the
    probe states, as ``--write`` writes them) and the line rate it read the arm's status at."""
    settings = {name: Measured(value, probed_on, evidence, confidence) for name, value, evidence, confidence in findings}
    return Calibration(arm, port, settings, baud, probed_on if baud is not None else "")


def probed_baud(port) -> tuple[int, str] | None:
    """The line rate ``armctl probe`` read the status of the arm on ``port`` (a ``PortChoice`` or a
    URL: ``with_arm``) at, and the source a setting names for it (``probed on DATE for ARM``); None
    when no probe of it kept one."""
    stored_record = with_arm(port).arm.kept
    if stored_record is None or stored_record.baud is None:
        return None
    return stored_record.baud, f"probed on {stored_record.baud_on} for {stored_record.arm}"


# --- the profile of the arm on a port --------------------------------------------------------------


def arm_profile(path=None, port=None, start=None):
    """``armctl.host.profile.load_profile`` for the arm on ``port`` (a device path or URL, as resolved,
    or a ``PortChoice``, its arm read once: ``with_arm``; None: the configured port — ARMCTL_PORT,
    armctl.toml, the simulator — for the commands that open none: lint, estimate, plot, a dry run:
    ``quiet_port``): the chosen profile with that arm's ``[connector]`` laid over its own, key by
    key — what ``armctl probe`` stored for the arm, then armctl.toml's top-level ``[connector]`` if
    it names no arm or its ``measured_on`` is this arm.  Everything after it reads the profile
    (``Profile.sources`` says where each value came from)."""
    from .profile import chosen_profile, load_config, with_connector, with_file_connector

    config = load_config(start)
    profile = chosen_profile(path, config=config)
    choice = quiet_port(None, config) if port is None else with_arm(port)
    arm, stored = (None, None) if choice is None else (choice.arm.identity, choice.arm.kept)
    for name in () if stored is None else stored.settings:
        profile = with_connector(profile, {name: stored.settings[name].value}, stored.source_of(name))
    return with_file_connector(profile, config, lambda measured_on, where: _identity_in(measured_on, where) == arm)


def _identity_in(measured_on: str, where: str) -> str:
    from .profile import MEASURED_ON

    try:
        return arm_identity(measured_on)
    except ConfigError as error:  # a bad sim:// URL
        raise ConfigError(f"{where}: connector.{MEASURED_ON}: {error}") from None


# --- the store (the file edge) -------------------------------------------------------------------


def data_dir() -> Path:
    """armctl's user data directory: ``$XDG_DATA_HOME/armctl`` (``~/.local/share/armctl`` when
    unset) on Linux and the BSDs, platformdirs' ``user_data_dir`` on macOS and Windows."""
    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        # platformdirs' own rule, without importing it at every start (as profile.user_config_path)
        base = os.environ.get("XDG_DATA_HOME", "")
        return Path(base if os.path.isabs(base) else os.path.expanduser("~/.local/share")) / "armctl"
    import platformdirs

    return Path(platformdirs.user_data_dir("armctl", appauthor=False))


def store_dir() -> Path:
    return data_dir() / STORE_FOLDER


def record_path(arm: str, directory: Path | None = None) -> Path:
    """``arm``'s file: the identity, quoted (one name per identity, readable in a listing), or a
    hash of it when that would be too long a file name."""
    name = urllib.parse.quote(arm, safe="", errors=_FILE_NAME_BYTES)
    if len(name) > 200:
        import hashlib

        name = "sha256-" + hashlib.sha256(arm.encode("utf-8", _FILE_NAME_BYTES)).hexdigest()
    return (store_dir() if directory is None else directory) / f"{name}.json"


def _read(path: Path) -> Calibration:
    import json

    try:
        data = json.loads(path.read_bytes())
    except OSError as error:
        raise ConfigError(f"cannot read {path}: {error.strerror or error}") from None
    except ValueError as error:  # not JSON, not UTF-8
        raise ConfigError(f"{path}: not a calibration this armctl reads ({error}): delete it and probe again") from None
    return Calibration.from_json(data, str(path))


def load(arm: str, directory: Path | None = None) -> Calibration | None:
    """The stored calibration of ``arm`` (an identity), or None."""
    path = record_path(arm, directory)
    if not path.is_file():
        return None
    found = _read(path)
    return found if found.arm == arm else None  # a hash collision: not this arm


def save(calibration: Calibration, directory: Path | None = None) -> Path:
    """Keep ``calibration``, laid over what was stored for that arm; atomically."""
    import json
    import tempfile

    directory = store_dir() if directory is None else directory
    earlier = load(calibration.arm, directory)
    record = calibration if earlier is None else earlier.updated(calibration)
    path = record_path(calibration.arm, directory)
    # (ASCII: a path's bytes that are not UTF-8 are kept as JSON's \\u escapes, which read back the same)
    text = json.dumps(record.to_json(), indent=2) + "\n"
    try:
        directory.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(prefix=".", suffix=".tmp", dir=directory)
        try:
            with os.fdopen(handle, "w", encoding="utf-8") as file:
                file.write(text)
                file.flush()
                os.fsync(file.fileno())
            os.replace(temporary, path)
        except BaseException:
            os.unlink(temporary)
            raise
        _sync_directory(directory)
    except OSError as error:
        raise ConfigError(f"cannot keep the calibration in {directory}: {error.strerror or error}") from None
    for gone in _gone_ptys(calibration.arm, directory):
        gone.unlink(missing_ok=True)
    return path


def _gone_ptys(arm: str, directory: Path) -> list[Path]:
    """The records of the ptys that had ``arm``'s path before it (a pty's identity is its path and
    when it was made; a record from before that, its path alone): gone for good, as another pty
    has the path now — without this every ``armctl sim --pty`` probed would stay listed."""
    import glob

    device = _pty_device(arm)
    if device is None:
        return []
    mine, prefix = record_path(arm, directory), record_path(device + _PTY_MADE, directory).name[:-len(".json")]
    earlier = [record_path(device, directory), *directory.glob(glob.escape(prefix) + "*.json")]
    return [path for path in earlier if path != mine and path.exists()]


def _sync_directory(directory: Path) -> None:
    """The rename made durable (POSIX: fsync the directory); where that cannot be done, skipped."""
    try:
        descriptor = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:
        pass
    finally:
        os.close(descriptor)


def stored(directory: Path | None = None) -> list[Calibration]:
    """Every stored calibration, by identity."""
    directory = store_dir() if directory is None else directory
    if not directory.is_dir():
        return []
    return sorted((_read(path) for path in directory.glob("*.json")), key=lambda c: c.arm)


def forget(arm: str, directory: Path | None = None) -> bool:
    """Remove ``arm``'s calibration; False if none was stored."""
    path = record_path(arm, directory)
    try:
        path.unlink()
    except FileNotFoundError:
        return False
    except OSError as error:
        raise ConfigError(f"cannot remove {path}: {error.strerror or error}") from None
    return True


# --- evidence against the values a job ran with ----------------------------------------------------


# A job this much over its estimate, held back by the FIFO's bound with frames only time could
# confirm, names an unmeasured speed_tolerance: on a probed arm the arm time is within a few
# percent of the estimate (README, "armctl bench": <= 1.02x omniscient), so 10 % is no noise.
SLOWED_OVERRUN = 0.10


def stale_notes(profile, port: str, slowest: float, frames_lost: bool, time_held_overrun: float | None = None, *,
                moved_past_bound: bool = False) -> list[str]:
    """What a finished job says about the ``[connector]`` values it ran with (``profile``'s, for the
    arm on ``port``): the arm proven slower than ``speed_tolerance`` allows (``slowest``: the arm's
    seconds ÷ the model's on a frame, a lower bound from two pairs of its reports —
    ``Streamer.slowest_proven``, 0 when never) means its ``speed_factor`` is wrong; frames that
    may have been lost at an ordinary pace mean the FIFO holds fewer than ``fifo_frames`` (or the
    arm runs faster than its ``speed_factor``), unless the arm was seen moving after even the
    slowest arm allowed for would have finished every frame (``moved_past_bound``: the streamer's
    sign of loss ``Losses.moved_past_time_bound``): then ``speed_tolerance`` (or ``speed_factor``)
    is too small for it.  Each note names the value, where it came from
    (probed on DATE, a file, the document's default) and the probe to run; none when nothing
    speaks against them.  And one that speaks for measuring: ``time_held_overrun`` (how far the
    arm time ran over the estimate, as a share, when the job finished after the FIFO's bound held
    frames back that only time could confirm) past ``SLOWED_OVERRUN`` with a ``speed_tolerance``
    never probed: the time bound allows for an arm that much slower, and a probe measures it."""
    import shlex

    connector = profile.connector
    tolerance = connector.speed_tolerance
    if slowest > tolerance:
        named = ["speed_factor"]
        said = (f"{_setting(profile, 'speed_factor')} looks wrong: the arm ran at least {slowest:.2f}x slower than it says "
                f"(more than speed_tolerance {tolerance:g} allows: speed_factor at least {connector.speed_factor * slowest:.2f})")
    elif moved_past_bound:
        named = ["speed_tolerance", "speed_factor"]
        said = (f"{_setting(profile, 'speed_tolerance')} looks too small (or {_setting(profile, 'speed_factor')}): the "
                f"arm still moved after an arm {tolerance:g}x slower than the model would have finished every frame")
    elif frames_lost:
        named = ["fifo_frames", "speed_factor"]
        said = (f"{_setting(profile, 'fifo_frames')} looks wrong: frames may have been lost, so the FIFO may hold "
                f"fewer (or the arm runs faster than {_setting(profile, 'speed_factor')})")
    elif (time_held_overrun is not None and time_held_overrun > SLOWED_OVERRUN
          and not profile.source_of("connector.speed_tolerance").startswith("probed on ")):
        named = ["speed_tolerance"]
        said = (f"{_setting(profile, 'speed_tolerance')} may have slowed this job: its arm time ran "
                f"{time_held_overrun:.1%} over the estimate while the FIFO's bound held back frames that only time "
                f"could confirm, allowing for an arm {tolerance:g}x slower")
    else:
        return []
    probed = any(profile.source_of(f"connector.{name}").startswith("probed on ") for name in named)
    return [f"{said}: {'probe it again' if probed else 'probe it'}: armctl probe --port {shlex.quote(port)}"]


def _setting(profile, name: str) -> str:
    """``name = value (where it came from)``."""
    from .profile import DOCUMENT

    value = getattr(profile.connector, name)
    shown = str(value).lower() if isinstance(value, bool) else format(value, "g") if isinstance(value, float) else str(value)
    source = profile.source_of(f"connector.{name}")
    return f"{name} = {shown} ({'the document default, never measured on this arm' if source == DOCUMENT else source})"
