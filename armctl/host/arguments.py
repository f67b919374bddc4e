"""The Python API's arguments, checked before anything is opened or sent, and a move's one line.

Strategy: a wrong type met later — inside the worker, mid-job — would be an AttributeError from
deep inside, or a job ended "failed" after frames went out.  So every argument of ``Arm`` is
checked here, at the call, each check naming the argument (``TypeError`` / ``ValueError``), with
the CLI's ranges (armctl/core/limits.py).  ``job_snapshot`` reads the script a call names, once.
``move_line`` writes the one script line ``Arm.move`` runs: the same compiler, checks and
streamer as any job, never a second encoder.
"""
from __future__ import annotations

import numbers
import os
from decimal import Decimal
from typing import TYPE_CHECKING, Any, Mapping

if TYPE_CHECKING:
    from .profile import Profile

TEXT_NAME = "<script>"  # the name of a script given as text
# move()'s keywords, in the order the line is written: Cartesian (G1) and joint (G6) words
_CARTESIAN = ("x", "y", "z", "a", "b", "c")
_JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
_OTHER = ("u", "v", "t", "h", "s", "f")
MOVE_KEYWORDS = _CARTESIAN + _JOINTS + _OTHER  # Arm.move's words (``armctl move``'s too)
OBSERVER_METHODS = ("started", "update", "note", "warning")
# feed_override()'s percent (or its step, relative=True): any number here is put on the engine's
# 10…200 % grid (armctl/core/feed.py); one far outside it is a mistake, not a wish for 200 %
FEED_OVERRIDE_RANGE_PERCENT = (-1000.0, 1000.0)


def check_timeout(timeout_s: float | None, limits: str = "JOB_TIMEOUT_RANGE_S") -> float | None:
    """A ``timeout=`` is None or a number of seconds in its range (NaN or ±inf would never fire,
    or fire at once)."""
    return None if timeout_s is None else in_range("timeout", timeout_s, limits)


def in_range(name: str, value, limits: str, whole: bool = False) -> float:
    """``value`` if it is a number (a whole one if ``whole``) inside ``armctl.core.limits.<limits>``
    (the CLI's ranges), else ValueError naming it."""
    from ..core import limits as ranges

    low, high = getattr(ranges, limits)
    kinds = int if whole else (int, float)
    if isinstance(value, bool) or not isinstance(value, kinds) or not low <= value <= high:
        raise ValueError(f"{name}={value!r} must be a {'whole ' if whole else ''}number from {low:g} to {high:g}")
    return value


def path_or_none(name: str, value, *, also: tuple = (), none_ok: bool = True) -> Any:
    """``value`` as a str path (``os.PathLike`` accepted), None (if ``none_ok``), or one of the
    types ``also``; TypeError naming the argument otherwise (an open file, a number, bytes)."""
    if (value is None and none_ok) or (also and isinstance(value, also)):
        return value
    if isinstance(value, (str, os.PathLike)):
        path = os.fspath(value)
        if isinstance(path, str):
            return path
    wanted = " or ".join(["a path (str or os.PathLike)", *(t.__name__ for t in also), *(["None"] if none_ok else [])])
    raise TypeError(f"{name} must be {wanted}, not {kind_of(value)}")


def kind_of(value) -> str:
    if hasattr(value, "write") or hasattr(value, "read"):
        return f"an open file ({type(value).__name__})"
    return type(value).__name__


def check_callable(name: str, value) -> None:
    if value is not None and not callable(value):
        raise TypeError(f"{name} must be a function or None, not {kind_of(value)}")


def check_observer(observer) -> None:
    missing = [m for m in OBSERVER_METHODS if not callable(getattr(observer, m, None))]
    if observer is not None and missing:
        raise TypeError(f"observer must be a JobObserver (with {', '.join(OBSERVER_METHODS)}), not "
                        f"{kind_of(observer)}: it has no {missing[0]}()")


def check_log(log) -> None:
    """``log=`` is an open text file (the journal is written as the job runs), as ``open(path, "w")``
    gives: not a path (``armctl run --log`` opens one), not a binary file."""
    import io

    if log is None:
        return
    if isinstance(log, (str, bytes, os.PathLike)):
        raise TypeError(f"log must be an open text file such as open(path, 'w', encoding='utf-8'), not a path ({log!r})")
    if not callable(getattr(log, "write", None)):
        raise TypeError(f"log must be an open text file, not {kind_of(log)}")
    if isinstance(log, (io.RawIOBase, io.BufferedIOBase)) or "b" in getattr(log, "mode", ""):
        raise TypeError("log must be a text file (open(path, 'w')), not a binary one: the journal is JSON lines of text")
    if getattr(log, "closed", False):
        raise ValueError(f"log is closed ({short(log)}): give an open text file; nothing was sent")
    writable = getattr(log, "writable", None)
    if callable(writable) and not writable():
        raise TypeError(f"log must be a file open for writing (open(path, 'w')), not {short(log)}; nothing was sent")


def check_connected(connected) -> tuple[Any, int]:
    """What ``connect`` returned: (a link, the baud rate), else TypeError (closing what it opened)."""
    if isinstance(connected, tuple) and len(connected) == 2 and callable(getattr(connected[0], "write", None)) \
            and isinstance(connected[1], int) and not isinstance(connected[1], bool):
        return connected
    for part in connected if isinstance(connected, tuple) else (connected,):
        close = getattr(part, "close", None)
        if callable(close):
            close()
    raise TypeError(f"connect must return (an armctl.host.link.Link, the baud rate), not {short(connected)}")


def short(value, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _word(letter: str, value: float) -> str:
    """``X250`` — a word as the language reads it: no exponent, no ``inf``/``nan``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"move(): {letter.lower()} must be a number, not {type(value).__name__}")
    text = repr(value if isinstance(value, int) else float(value))  # the shortest text that reads back as the same float
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"move(): {letter.lower()}={text} is not a finite number")
    number = format(Decimal(text), "f")
    letter = letter.upper()
    return f"{letter}={number}" if letter.startswith("J") else f"{letter}{number}"


def default_speed(profile: Profile, words: Mapping[str, float | None]) -> float | None:
    """The F a move without ``f`` is sent with: the profile's ``[speed]`` default of the line's
    family (``default_joint_deg_s`` when a joint is named, else ``default_linear_mm_min``).
    None when no word is given (``move_line`` says what is missing)."""
    if all(value is None for value in words.values()):
        return None
    joint = any(words.get(name) is not None for name in _JOINTS)
    speed = profile.speed.default_joint_deg_s if joint else profile.speed.default_linear_mm_min
    return int(speed) if speed.is_integer() else speed


def move_line(**words: float | None) -> str:
    """The one script line ``Arm.move`` sends: G6 when a joint is named, else G1 (the
    compiler judges every word: a Cartesian word on G6, say, is its error, not ours)."""
    given = {name: value for name, value in words.items() if value is not None}
    unknown = sorted(set(given) - set(MOVE_KEYWORDS))
    if unknown:
        raise TypeError(f"move() got unexpected keyword arguments: {', '.join(unknown)}")
    if not given:
        raise ValueError("move() needs at least one word (x=…, j1=…, s=…, f=…)")
    code = "G6" if any(name in given for name in _JOINTS) else "G1"
    order = _JOINTS + _CARTESIAN + _OTHER if code == "G6" else _CARTESIAN + _JOINTS + _OTHER
    return " ".join([code] + [_word(name, given[name]) for name in order if name in given]) + "\n"


def open_port(port, baud, profile, connect, lead_s: float, status_timeout_s: float) -> tuple[Any, int, Any, Any]:
    """``Arm.open``'s arguments checked (types and the CLI's ranges, armctl/core/limits.py) before
    the port opens, then the port opened as they say: (the link, its baud rate, the profile, the
    ``PortChoice`` with its arm read once: ``calibration.with_arm``)."""
    from .calibration import arm_profile, with_arm
    from .link import PortChoice, choose_port, connect as open_link
    from .profile import Profile

    port = path_or_none("port", port, also=(PortChoice,))  # (a PortChoice: the CLI's port, resolved once)
    profile = path_or_none("profile", profile, also=(Profile,))
    check_callable("connect", connect)
    in_range("lead_s", lead_s, "LEAD_RANGE_S")
    in_range("status_timeout_s", status_timeout_s, "STATUS_TIMEOUT_RANGE_S")
    if baud is not None:
        in_range("baud", baud, "BAUD_RANGE", whole=True)
    # once: the arm on the port (its identity, its stored calibration) for its profile, line rate and job logs
    choice = with_arm(choose_port(port, origin="port"))
    loaded = profile if isinstance(profile, Profile) else \
        arm_profile(None if profile is None else os.fspath(profile), port=choice)
    link, line_baud = check_connected((open_link if connect is None else connect)(choice, baud, profile=loaded))
    return link, line_baud, loaded, choice


def feed_percent(percent) -> float:
    """``feed_override()``'s ``percent`` as a float inside ``FEED_OVERRIDE_RANGE_PERCENT``
    (TypeError, ValueError: NaN, ±inf and 10**60 too)."""
    import math

    if isinstance(percent, bool) or not isinstance(percent, numbers.Real):
        raise TypeError(f"feed_override(): percent must be a number, not {short(percent)}")
    low, high = FEED_OVERRIDE_RANGE_PERCENT
    try:
        value = float(percent)
    except OverflowError:
        value = math.inf
    if not low <= value <= high:
        raise ValueError(f"feed_override(): percent={short(percent)} must be a number from {low:g} to {high:g} "
                         "(it is then put on the 10…200 % grid)")
    return value


def job_snapshot_type(script) -> None:
    """TypeError unless ``script`` is a ``ScriptSnapshot``, a path or script text."""
    from ..script.files import ScriptSnapshot

    if not isinstance(script, ScriptSnapshot):
        path_or_none("script", script, none_ok=False)


def job_snapshot(script):
    """The ``ScriptSnapshot`` of ``Arm.run``'s ``script``, read once: a snapshot or a checked script
    as it is; a ``str`` holding a line break is the script's text; any other ``str`` or
    ``os.PathLike`` a path (``JobFailed`` when it cannot be read; TypeError for anything else)."""
    from ..core.checked import CheckedScript
    from .jobflow import JobFailed
    from ..script.files import ScriptSnapshot, read_script

    if isinstance(script, (ScriptSnapshot, CheckedScript)):
        return script  # read once already (``armctl run`` reads stdin or the file itself)
    job_snapshot_type(script)
    if isinstance(script, str) and ("\n" in script or "\r" in script):
        return ScriptSnapshot(TEXT_NAME, script.encode("utf-8", "surrogateescape"))
    path = os.fspath(script)
    try:
        return read_script(path)
    except OSError as error:
        hint = " (script text must hold a line break: end a one-line script with \\n)" if isinstance(script, str) else ""
        raise JobFailed(f"cannot read {path}: {error.strerror or error}{hint}; nothing was sent") from None
